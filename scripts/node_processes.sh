# Sourced by launch_sim.sh and launch_hw.sh: nodes started in the background and stopped together.
# The caller sets bin (the node executables), common and extra (arguments before and after each
# node's own) and node_logs (the log folder), and traps EXIT with stop_nodes.
pids=()

stop_nodes() {  # every started node: TERM, up to 5 s to exit, then KILL
  trap - EXIT INT TERM
  # SIGTERM, not SIGINT: a non-interactive shell starts background jobs with SIGINT ignored.
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$pid" 2>/dev/null || true
  done
  wait 2>/dev/null || true
}

start_node() {  # start_node NAME ARGS...: a node in the background, log in $node_logs/NAME.log
  local name=$1; shift
  "$bin/$name" "${common[@]}" "$@" "${extra[@]}" >"$node_logs/$name.log" 2>&1 &
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
