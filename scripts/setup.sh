#!/usr/bin/env bash
# Set up everything bellows_ros needs on a machine that has only Python 3.11 and pip:
# a virtual environment in .venv with the package (editable) and its test tools.
# Idempotent: a second run only checks that the environment is complete.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
venv="${BELLOWS_VENV:-$top/.venv}"
python="${PYTHON:-python3}"

if [ ! -x "$venv/bin/python" ]; then
  echo "bellows setup: creating $venv" >&2
  "$python" -m venv "$venv"
fi
stamp="$venv/.bellows-installed"
if [ ! -f "$stamp" ] || [ "$top/setup.py" -nt "$stamp" ]; then
  echo "bellows setup: installing bellows_ros and its dependencies" >&2
  "$venv/bin/python" -m pip install --quiet --upgrade pip
  "$venv/bin/python" -m pip install --quiet -e "$top[test]"
  touch "$stamp"
fi
