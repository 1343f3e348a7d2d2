#!/usr/bin/env bash
# Set up everything bellows_ros needs on a machine that has only Python 3.11 and pip:
# a virtual environment in .venv with the package (editable), its test tools, and rclpy.
#   - With a ROS 2 Jazzy sourced (rclpy importable, ROS_DISTRO=jazzy), the venv uses that ROS:
#     its rclpy and messages reach the venv's python through PYTHONPATH, as colcon's do.
#   - Otherwise ROS 2 Jazzy's Python client comes from PyPI: the exact pins of
#     requirements/ros-jazzy.txt (rclpy on Fast DDS and the message packages) go into .venv.
# Idempotent: a second run only checks that the environment is complete.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
venv="${BELLOWS_VENV:-$top/.venv}"
python="${PYTHON:-python3}"

if [ ! -x "$venv/bin/python" ]; then
  echo "bellows setup: creating $venv" >&2
  "$python" -m venv "$venv"
fi
sourced_ros=0
# rclpy on the sourced ROS's PYTHONPATH (found, not imported: its own pip dependencies may be
# installed only in the venv).
if [ "${ROS_DISTRO:-}" = jazzy ] && "$python" -c 'import importlib.util, sys
sys.exit(importlib.util.find_spec("rclpy") is None)' 2>/dev/null; then
  sourced_ros=1
fi
stamp="$venv/.bellows-installed"
if [ ! -f "$stamp" ] || [ "$top/setup.py" -nt "$stamp" ]; then
  echo "bellows setup: installing bellows_ros and its dependencies" >&2
  "$venv/bin/python" -m pip install --quiet --upgrade pip
  "$venv/bin/python" -m pip install --quiet -e "$top[test]"
  touch "$stamp"
fi
ros_stamp="$venv/.bellows-ros-jazzy"
if [ "$sourced_ros" = 1 ]; then
  echo "bellows setup: using the sourced ROS 2 $ROS_DISTRO" >&2
elif [ ! -f "$ros_stamp" ] || [ "$top/requirements/ros-jazzy.txt" -nt "$ros_stamp" ]; then
  echo "bellows setup: installing ROS 2 Jazzy's rclpy and messages from PyPI (a few minutes" \
       "the first time)" >&2
  "$venv/bin/python" -m pip install --quiet -r "$top/requirements/ros-jazzy.txt"
  touch "$ros_stamp"
fi
