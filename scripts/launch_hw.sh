#!/usr/bin/env bash
# The bellows graph against real hardware (no simulators).
#
#   scripts/launch_hw.sh [--actuator-port PORT | --no-actuator] [--can-channel CH | --no-arm]
#                        [--can-interface IF] [--params FILE] [-- extra --ros-args]
#
# Ports default to config/hardware.yaml (the board's /dev/serial/by-id link, socketcan can0).
# Starts driver_node, model_node and stiffness_controller_node in the background; Ctrl-C stops
# all of them (trap). A node that cannot start (absent device, bad parameter) stops the launch
# with its one-line error and exit status 2. Works from a checkout, a pip install and a colcon
# install (the executables are found as `ros2 run` finds them). The network is left as the user
# configured it (ROS_AUTOMATIC_DISCOVERY_RANGE, CYCLONEDDS_URI): a robot is meant to be seen.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
if [ -f "$top/setup.py" ]; then here=$top; else here=$PWD; fi  # a checkout, or an install
# shellcheck source=scripts/node_processes.sh
source "$top/scripts/node_processes.sh"
bin=$(find_executables "$top" launch_hw) || exit 2
echo "launch_hw: executables in $bin" >&2
params="$top/config/nodes_hw.yaml"
logs="$here/out/hw_logs"
driver=()
actuator=1
arm=1
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    # node:name:=value: under rcl the file's driver_node section beats a bare -p (= /**).
    --actuator-port) driver+=(-p "driver_node:actuator.port:=$2"); shift ;;
    --can-channel) driver+=(-p "driver_node:arm.channel:=$2"); shift ;;
    --can-interface) driver+=(-p "driver_node:arm.interface:=$2"); shift ;;
    --no-actuator) actuator=0 ;;
    --no-arm) arm=0 ;;
    --params) params="$2"; shift ;;
    --) shift; extra=("$@"); break ;;
    -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
    *) echo "launch_hw.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done
[ "$actuator" = 1 ] || driver+=(-p driver_node:actuator.enabled:=false)
[ "$arm" = 1 ] || driver+=(-p driver_node:arm.enabled:=false)
[ -f "$params" ] || { echo "launch_hw.sh: --params '$params': no such file" >&2; exit 2; }
mkdir -p "$logs"
common=(--ros-args --params-file "$params")

node_logs="$logs"
trap stop_nodes EXIT
trap 'exit 130' INT TERM

start() {
  start_node "$@"
  echo "launch_hw: $1 (pid $!), log $logs/$1.log" >&2
}

# The driver is a managed node: autostart configures and activates it (a device absent: exit 2).
start driver_node -p driver_node:autostart:=true "${driver[@]}"
# The driver exits within its startup_timeout when a device is absent: report that, not a hang.
sleep 3
nodes_alive launch_hw
[ "$arm" = 1 ] && start model_node
[ "$actuator" = 1 ] && start stiffness_controller_node
echo "launch_hw: graph running; Ctrl-C to stop" >&2
wait -n "${pids[@]}" || true
echo "launch_hw: a node exited; stopping the graph" >&2
tail -n 3 "$logs"/*.log >&2
exit 1
