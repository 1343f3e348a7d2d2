#!/usr/bin/env bash
# The test command: set up (if needed), then run the whole test suite on rclpy. Extra arguments
# go to pytest, e.g.
#   scripts/test.sh -m "not slow"      # the quick tier, a few minutes
#   scripts/test.sh test/test_doctor_live.py -x
#
# The whole suite (no test path, -m or -k given; give options as --name=value) runs in two
# phases: first every test not marked `realtime` in parallel, one pytest-xdist worker per core
# (a module's tests on one worker), then the `realtime` ones (node graphs, simulated devices, the
# ROS 2 command line) one at a time, alone on the machine, as their 1 kHz processes need. The
# exit status is the worse of the two. With a path, -m or -k, pytest runs once, as given.
#
# rclpy is the sourced ROS 2 Jazzy's, else the PyPI wheels scripts/setup.sh put into .venv.
# The ROS 2 command line and launch (ros2 param, ros2 lifecycle, ros2 launch) for the tests that
# need them: the sourced ROS's, else ../shared/ros2-pip's pure-Python wheels when that lies beside
# the checkout (as on CI); elsewhere those tests skip, each saying why. DDS stays on loopback
# (test/conftest.py).
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
"$top/scripts/setup.sh"
venv="${BELLOWS_VENV:-$top/.venv}"
ros2_pip="$top/../shared/ros2-pip"
cd "$top"

if [ "${ROS_DISTRO:-}" = jazzy ] && command -v ros2 >/dev/null; then
  echo "bellows test: the ROS 2 command line of the sourced $ROS_DISTRO" >&2
elif [ -f "$ros2_pip/install.sh" ]; then
  stamp="$venv/.bellows-ros2-pip"
  if [ ! -f "$stamp" ] || [ "$ros2_pip/requirements-pypi.txt" -nt "$stamp" ]; then
    echo "bellows test: installing the ROS 2 command line from $ros2_pip" >&2
    PYTHON="$venv/bin/python" bash "$ros2_pip/install.sh" >/dev/null
    touch "$stamp"
  fi
  # shellcheck disable=SC1091
  VIRTUAL_ENV="$venv" source "$ros2_pip/env.sh"
  export BELLOWS_REQUIRE_ROS2_CLI=1
else
  echo "bellows test: no ROS 2 command line here; the tests that need it are skipped" >&2
fi
# A crash in native code (a DDS library, NumPy) prints the Python stacks of every thread.
export PYTHONFAULTHANDLER=1
# The ros2 command line runs `python3` from PATH: the venv's, which has its dependencies.
export PATH="$venv/bin:$PATH"
pytest=("$venv/bin/python" -m pytest)

whole=1
for arg in "$@"; do
  case "$arg" in
    -m|-m?*|-k|-k?*|-n|-n?*|--numprocesses*) whole=0 ;;
    -*) ;;
    *) whole=0 ;;  # a test path (or an option's value given apart: use --name=value)
  esac
done
if [ "$whole" = 0 ]; then
  exec "${pytest[@]}" "$@"
fi

# pytest's "no test selected" (5) is no failure of a phase.
phase() { "$@" && return 0; local status=$?; [ "$status" = 5 ] && return 0; return "$status"; }
workers=$(nproc 2>/dev/null || echo 1)
parallel=()
# Whole modules to the workers, in collection order (test/conftest.py puts the slow ones first;
# xdist's own order, by test count, left a one-test slow module for the end).
[ "$workers" -gt 1 ] && parallel=(-n "$workers" --dist loadfile --no-loadscope-reorder)
status=0
echo "bellows test: 1/2, the tests not marked realtime (${workers} worker(s))" >&2
# One BLAS thread per worker: the workers already take every core.
OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 \
  phase "${pytest[@]}" "${parallel[@]}" -m "not realtime" "$@" || status=$?
echo "bellows test: 2/2, the realtime tests, one at a time" >&2
phase "${pytest[@]}" -p no:xdist -m realtime "$@" || { s=$?; [ "$status" = 0 ] && status=$s; }
exit "$status"
