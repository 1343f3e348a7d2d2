#!/usr/bin/env bash
# The test command: set up (if needed), then run the whole test suite, the graph tests on both
# runtimes (rclpy and the Cyclone DDS runtime). Extra arguments go to pytest, e.g.
#   scripts/test.sh -m "not slow"      # the quick tier, under a minute
#
# The rclpy tier:
# - with a ROS 2 Jazzy already sourced (rclpy importable), that ROS is used;
# - else, where ../shared/ros2 lies beside the checkout (CI), that build is installed into
#   /opt/ros/jazzy and sourced, and rclpy becomes required: a failure to install or import it
#   fails the run (BELLOWS_REQUIRE_RCLPY=1);
# - else the rclpy tests are skipped, each with its reason.
# DDS stays on loopback either way (test/conftest.py).
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
"$top/scripts/setup.sh"
venv="${BELLOWS_VENV:-$top/.venv}"
shared_ros="$top/../shared/ros2"
cd "$top"

if "$venv/bin/python" -c 'import rclpy' 2>/dev/null; then
  echo "bellows test: rclpy tier on the sourced ROS 2 ${ROS_DISTRO:-}" >&2
elif [ -f "$shared_ros/install.sh" ]; then
  echo "bellows test: installing ROS 2 from $shared_ros for the rclpy tier" >&2
  bash "$shared_ros/install.sh"
  stamp="$venv/.bellows-ros-deps"
  if [ ! -f "$stamp" ] || [ "$shared_ros/requirements.txt" -nt "$stamp" ]; then
    PYTHON="$venv/bin/python" bash "$shared_ros/install.sh" --pip
    touch "$stamp"
  fi
  # shellcheck disable=SC1091
  source /opt/ros/jazzy/share/ros-jazzy-minimal/env_loopback.sh
  export BELLOWS_REQUIRE_RCLPY=1
  "$venv/bin/python" -c 'import rclpy' || { echo "bellows test: rclpy does not import" >&2; exit 1; }
else
  echo "bellows test: no ROS 2 here; the rclpy tier is skipped (each test says why)" >&2
fi
# A crash in native code (a DDS library, NumPy) prints the Python stacks of every thread.
export PYTHONFAULTHANDLER=1
# The ros2 command line runs `python3` from PATH: the venv's, which has its dependencies.
export PATH="$venv/bin:$PATH"
exec "$venv/bin/python" -m pytest "$@"
