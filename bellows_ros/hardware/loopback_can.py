# Copyright 2026 bellows_ros maintainers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""
The simulated arm's CAN bus: python-can's `udp_multicast`, kept to the loopback interface.

udp_multicast stands in for the arm's CAN bus between processes of one machine. python-can's own
backend resolves the channel with `getaddrinfo` (a name reaches the resolver), binds to the
wildcard address and joins the group on the default interface, so an IGMP report and every frame
(5000 a second) would leave the machine. This backend overrides only the socket's creation, as a
python-can backend overrides a few methods of its base:

- the channel must be an IPv4 multicast address, written as one (`check_channel`): no name
  lookup, an error before any socket exists;
- before it joins or sends anything, the socket is bound to the group's port with
  IP_MULTICAST_IF = loopback, TTL 0 (a datagram may not leave the host) and multicast loop on;
  it joins the group on the loopback interface only;
- IP_MULTICAST_ALL = 0: Linux would otherwise deliver to this socket every group any process on
  the host joined on the port, and two simulated arms on one machine would hear each other;
- the kernel's default receive buffer holds 256 frames, 51 ms of the arm's 5000 frames a second:
  a reader the host stalls for longer loses whole instants, and the model's strain memory needs
  every one. `RECEIVE_BUFFER` holds about a second's frames where net.core.rmem_max allows it
  (the DDS topics keep five: interfaces.SAMPLE_DEPTH). Joined on loopback, a frame and
  its echo also cost about a third less CPU than on the default interface (53-56 us instead of
  76-89 us).
"""
import errno
import ipaddress
import socket

import can
from can import BusABC, CanProtocol
from can.interfaces.udp_multicast.bus import (
    GeneralPurposeUdpMulticastBus, SO_TIMESTAMPNS, UdpMulticastBus)

from bellows_ros.errors import ParameterError

# Linux's IP_MULTICAST_ALL (linux/in.h); Python's socket module does not export it.
_IP_MULTICAST_ALL = 49
_LOOPBACK = socket.inet_aton('127.0.0.1')
# Bytes of kernel receive buffer asked for; Linux doubles the request, within net.core.rmem_max.
# 2 MiB kept 5041 frames of 6000 sent unread on this machine (4 MiB given).
RECEIVE_BUFFER = 2 << 20


def check_channel(channel):
    """
    Return `channel` when it is an IPv4 multicast address written as one; else ParameterError.

    Only the text is read: nothing is looked up.
    """
    try:
        group = ipaddress.IPv4Address(str(channel).strip())
    except ValueError:
        group = None
    if group is None or not group.is_multicast:
        raise ParameterError(f"CAN channel '{channel}': the simulated bus (udp_multicast) needs "
                             'an IPv4 multicast group such as 239.74.163.2')
    return str(group)


class _LoopbackMulticast(GeneralPurposeUdpMulticastBus):
    """python-can's multicast socket handler with the socket made on loopback (module doc)."""

    def __init__(self, group, port, hop_limit=0, max_buffer=4096):
        # The base resolves `group` with getaddrinfo: a checked literal never reaches a resolver.
        super().__init__(check_channel(group), port, hop_limit, max_buffer)

    def _create_socket(self, address_family):
        if address_family != socket.AF_INET:
            raise OSError(errno.EAFNOSUPPORT, 'IPv4 only')
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, _LOOPBACK)
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
            sock.setsockopt(socket.IPPROTO_IP, _IP_MULTICAST_ALL, 0)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT, 1)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RECEIVE_BUFFER)
            sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)
            self.timestamp_nanosecond = True
            sock.bind((self.group, self.port))  # the group's datagrams only, not the port's
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP,
                            socket.inet_aton(self.group) + _LOOPBACK)
        except OSError as error:
            sock.close()
            raise can.CanInitializationError('could not create or configure socket') from error
        return sock


class LoopbackUdpMulticastBus(UdpMulticastBus):
    """`udp_multicast` on the loopback interface only (module doc); python-can's Bus contract."""

    def __init__(self, channel, port=43113, fd=True, **kwargs):
        # UdpMulticastBus.__init__ would open python-can's own socket (joined on the default
        # interface): only BusABC's part of it runs, and the socket is ours.
        channel = check_channel(channel)
        BusABC.__init__(self, channel, **kwargs)
        self._multicast = _LoopbackMulticast(channel, port)
        self._can_protocol = CanProtocol.CAN_FD if fd else CanProtocol.CAN_20
