#!/usr/bin/env bash
# netns_run.sh COMMAND...: run COMMAND in a private network namespace that has a way off the
# machine, and print how many packets left through it.
#
# The namespace has loopback and one veth pair whose far end stands for the network: it has an
# IPv4 address, the default route and multicast (IPv6 off, so the kernel itself sends nothing).
# Whatever COMMAND sends anywhere but loopback shows up in the veth's tx_packets. The last line
# printed is `off-machine packets: N`, counted from just before COMMAND to just after it.
# Needs CAP_SYS_ADMIN (root); run as `unshare -n test/netns_run.sh COMMAND...`.
set -euo pipefail
PATH="$PATH:/usr/sbin:/sbin"  # ip(8) lives there; a minimal PATH may lack it
for knob in /proc/sys/net/ipv6/conf/all/disable_ipv6 /proc/sys/net/ipv6/conf/default/disable_ipv6; do
  if [ -w "$knob" ]; then echo 1 > "$knob"; fi  # no IPv6 in the kernel: nothing to switch off
done
ip link set lo up
ip link add bellows_net type veth peer name bellows_far
ip addr add 10.253.0.1/24 dev bellows_net
ip link set bellows_net multicast on up
ip link set bellows_far up
ip route add default via 10.253.0.2 dev bellows_net
# /proc/net/dev is the namespace's own (sysfs would still show the parent's): field 11 of the
# interface's line is its transmitted packets.
sent() { awk '$1 == "bellows_net:" { print $11 }' /proc/net/dev; }
before=$(sent)
status=0
"$@" || status=$?
after=$(sent)
echo "off-machine packets: $((after - before))"
exit "$status"
