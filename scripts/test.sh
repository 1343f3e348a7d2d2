#!/usr/bin/env bash
# The test command: set up (if needed), then run the whole test suite on rclpy. Extra arguments
# go to pytest, e.g.
#   scripts/test.sh -m "not slow"      # the quick tier, a few minutes
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
exec "$venv/bin/python" -m pytest "$@"
