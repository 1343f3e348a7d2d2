#!/usr/bin/env bash
# The whole bellows graph on simulated hardware, plus a short scripted scenario.
#
#   scripts/launch_sim.sh [--no-scenario] [--duration S] [--output DIR] [--params FILE]
#                         [--namespace NS] [--record BAG] [--actuator-only]
#                         [-- extra --ros-args for every node]
#
# Starts sim_arm_node (CAN over udp_multicast) and sim_actuator_node (serial on a pty), then
# driver_node, model_node, stiffness_controller_node and arm_controller_node, all in the background
# with their logs in DIR/logs. Then scenario_node (stiffness step 1400 -> 1900 N/m; segment_1
# tracks an angle trajectory with paper A's feedforward, then without) prints a summary, writes
# DIR/scenario.png and .csv, and the graph stops. With --no-scenario it runs until Ctrl-C. With
# --namespace NS every node runs in /NS (its topics under /NS/...), so graphs in different
# namespaces run side by side, each with its own pty and CAN group. With --record BAG, `bellows
# record` writes the devices' samples (/joint_states, /actuator/joint_states, one message each)
# and /bellows/wrench (an arm's torque sensor) to the rosbag2 directory BAG while the graph runs
# (root namespace only; docs/workflow.md). With --actuator-only the arm's nodes (sim_arm_node,
# model_node, arm_controller_node) are left out and the actuator path runs SCHED_FIFO where the
# machine grants it (a lighter graph whose recording keeps every sample on a busy machine; the
# scenario's angle part then reports no samples). Every process is stopped on exit, Ctrl-C or
# error (trap). Works from a checkout, a pip install and a colcon install (the executables are
# found as `ros2 run` finds them). DDS discovery stays on this host.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
# From a checkout, set up first (idempotent: a no-op once done). An install has no setup.py.
if [ -f "$top/setup.py" ]; then "$top/scripts/setup.sh"; here=$top; else here=$PWD; fi
# shellcheck source=scripts/node_processes.sh
source "$top/scripts/node_processes.sh"
bin=$(find_executables "$top" launch_sim) || exit 2
echo "launch_sim: executables in $bin" >&2
params="$top/config/nodes_sim.yaml"
output="$here/out/scenario"
duration=''  # the scenario's own (config/nodes_sim.yaml, scenario_node)
scenario=1
namespace=''
record=''
arm=1
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --no-scenario) scenario=0 ;;
    --duration) duration="$2"; shift ;;
    --output) output="$2"; shift ;;
    --params) params="$2"; shift ;;
    --) shift; extra=("$@"); break ;;
    --namespace) namespace="$2"; shift ;;
    --record) record="$2"; shift ;;
    --actuator-only) arm=0 ;;
    -h|--help) sed -n '2,22p' "$0"; exit 0 ;;
    *) echo "launch_sim.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done
case "$duration" in
  '') ;;
  *[!0-9.]*|*.*.*) echo "launch_sim.sh: --duration '$duration': expected seconds, e.g. 40" >&2
                     exit 2 ;;
  *.*) ;;
  *) duration="$duration.0" ;;  # rcl types parameters strictly: duration is a double
esac
[ -f "$params" ] || { echo "launch_sim.sh: --params '$params': no such file" >&2; exit 2; }
namespace=${namespace#/}
if [ -n "$record" ]; then
  [ -z "$namespace" ] || { echo "launch_sim.sh: --record records the root namespace; drop --namespace" >&2; exit 2; }
  [ ! -e "$record" ] || { echo "launch_sim.sh: --record '$record': already exists (a bag is a new directory)" >&2; exit 2; }
fi
if [ -n "$namespace" ] && ! [[ "$namespace" =~ ^[A-Za-z][A-Za-z0-9_]*(/[A-Za-z][A-Za-z0-9_]*)*$ ]]; then
  echo "launch_sim.sh: --namespace '$namespace': expected a ROS name such as arm_a" >&2; exit 2
fi
# A simulation stays off the network: DDS discovery on this host only (ROS 2's switch, which
# Fast DDS and Cyclone DDS honour; Cyclone also bound to loopback unless the user configured
# it); the simulated CAN bus is on loopback already.
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
if [ -z "${CYCLONEDDS_URI:-}" ]; then
  export CYCLONEDDS_URI='<CycloneDDS><Domain><General><Interfaces><NetworkInterface name="lo"/></Interfaces><AllowMulticast>false</AllowMulticast></General></Domain></CycloneDDS>'
fi
mkdir -p "$output/logs"
output=$(cd "$output" && pwd)
# A private pty link and multicast group per run, so two launches on one machine do not collide.
# The link lives in a directory of this run's own; the simulated board removes the link it made,
# and the launcher then removes the directory only if it is empty (rmdir deletes no content).
portdir=$(mktemp -d "${TMPDIR:-/tmp}/bellows_sim_actuator.XXXXXX")
port="$portdir/board"
group="239.74.163.$(( ($$ % 200) + 20 ))"
# This run's own values, in a parameter file of its own after the user's: a section
# `/**/<node>` reaches the node in any namespace and, coming later, wins over the file's
# (a `-p node:name:=v` would reach only a node in the root namespace).
overrides="$output/launch_parameters.yaml"
cat >"$overrides.tmp" <<YAML
/**/sim_arm_node:
  ros__parameters: {can: {channel: '$group'}}
/**/sim_actuator_node:
  ros__parameters: {port: '$port'$( [ "$arm" = 1 ] || echo ', realtime_priority: 60')}
/**/driver_node:
  ros__parameters: {autostart: true, arm: {channel: '$group'$( [ "$arm" = 1 ] || echo ', enabled: false')}, actuator: {port: '$port'}}
$( [ "$arm" = 1 ] || printf '%s\n  %s' '/**/stiffness_controller_node:' 'ros__parameters: {realtime_priority: 50}')
/**/scenario_node:
  ros__parameters: {$( [ -z "$duration" ] || echo "duration: $duration, ")output_dir: '$output'}
YAML
mv -f "$overrides.tmp" "$overrides"
common=(--ros-args -r "__ns:=/$namespace" --params-file "$params" --params-file "$overrides")

node_logs="$output/logs"
cleanup() {
  stop_nodes
  rmdir "$portdir" 2>/dev/null || true
}
trap cleanup EXIT
trap 'exit 130' INT TERM

start() {  # start NAME ARGS...: a node in the background, log in $output/logs/NAME.log
  start_node "$@"
  echo "launch_sim: $1 (pid $!)" >&2
}

[ "$arm" = 1 ] && start sim_arm_node && devices+=($!)
start sim_actuator_node
devices+=($!)
for _ in $(seq 50); do [ -e "$port" ] && break; sleep 0.1; done
nodes_alive launch_sim
# The driver is a managed node: autostart (launch_parameters.yaml) configures and activates it.
start driver_node
[ "$arm" = 1 ] && start model_node
start stiffness_controller_node
[ "$arm" = 1 ] && start arm_controller_node
if [ -n "$record" ]; then
  "$bin/bellows" record --output "$record" --topics /joint_states /actuator/joint_states \
    /bellows/wrench >"$node_logs/record.log" 2>&1 &
  pids+=($!)
  echo "launch_sim: bellows record -> $record (pid $!)" >&2
fi
sleep 3
nodes_alive launch_sim

if [ "$scenario" = 1 ]; then
  "$bin/scenario_node" "${common[@]}" "${extra[@]}"
  nodes_alive launch_sim
else
  echo "launch_sim: graph running; Ctrl-C to stop" >&2
  wait -n "${pids[@]}"
  nodes_alive launch_sim
fi
