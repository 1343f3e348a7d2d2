# Sourced by launch_sim.sh and launch_hw.sh: nodes started in the background and stopped together.
# The caller sets bin (the node executables: find_executables), common and extra (arguments before
# and after each node's own) and node_logs (the log folder), and traps EXIT with stop_nodes.
pids=()
session=$(command -v setsid || true)  # util-linux; without it the nodes share this session
devices=()  # the simulated devices among pids: stopped after the rest (stop_nodes)

find_executables() {  # find_executables TOP WHO: print the folder holding bellows_ros' executables
  # As `ros2 run` finds them: a checkout's venv; the install the script itself came from
  # (TOP = <prefix>/share/bellows_ros: colcon puts them in <prefix>/lib/bellows_ros, pip in the
  # venv's bin/); the ament index (AMENT_PREFIX_PATH: <prefix>/lib/bellows_ros); then PATH.
  local top=$1 who=$2 prefix dir
  local candidates=()
  [ -f "$top/setup.py" ] && candidates+=("${BELLOWS_VENV:-$top/.venv}/bin")
  prefix=$(cd "$top/../.." && pwd)
  candidates+=("$prefix/lib/bellows_ros" "$prefix/bin")
  local IFS=:
  for dir in ${AMENT_PREFIX_PATH:-}; do
    [ -e "$dir/share/ament_index/resource_index/packages/bellows_ros" ] \
      && candidates+=("$dir/lib/bellows_ros")
  done
  unset IFS
  if command -v driver_node >/dev/null; then
    candidates+=("$(dirname "$(command -v driver_node)")")
  fi
  for dir in "${candidates[@]}"; do
    if [ -x "$dir/driver_node" ]; then echo "$dir"; return 0; fi
  done
  echo "$who: cannot find the bellows_ros executables (looked in: ${candidates[*]}); run" \
    "scripts/setup.sh, pip install bellows_ros, or source a colcon install's setup.bash" >&2
  return 2
}

stop_nodes() {  # every started node, the simulated devices last
  trap - EXIT INT TERM
  local pid rest=()
  for pid in "${pids[@]}"; do
    [[ " ${devices[*]} " == *" $pid "* ]] || rest+=("$pid")
  done
  # The driver vents at shutdown and waits for every chamber to read ambient: a simulated device
  # stopped with it leaves it nothing to read, and it rightly says the arm may still hold air.
  terminate "${rest[@]}"
  terminate "${devices[@]}"
  wait 2>/dev/null || true
}

terminate() {  # terminate PID...: TERM, up to 5 s to exit, then KILL
  # SIGTERM, not SIGINT: a non-interactive shell starts background jobs with SIGINT ignored.
  local pid
  for pid in "$@"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "$@"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$pid" 2>/dev/null || true
  done
}

start_node() {  # start_node NAME ARGS...: a node in the background, log in $node_logs/NAME.log
  local name=$1; shift
  # Each node in a session of its own: a scheduler autogroup of its own (docs/nodes.md, "Timing").
  # A background job of this shell is no group leader, so setsid execs in place and $! is the
  # node; stop_nodes still stops it by pid.
  $session "$bin/$name" "${common[@]}" "$@" "${extra[@]}" >"$node_logs/$name.log" 2>&1 &
  pids+=($!)
}

nodes_alive() {  # nodes_alive WHO: exit 2, naming WHO and showing the logs, if a started node exited
  for pid in "${pids[@]}"; do
    if ! kill -0 "$pid" 2>/dev/null; then
      echo "$1: a node exited (bad parameters, absent device?); logs in $node_logs:" >&2
      tail -n 3 "$node_logs"/*.log >&2
      exit 2
    fi
  done
}
