#!/usr/bin/env bash
# Branch coverage of bellows_ros by the quick tier of the tests (not `slow`, not `realtime`; every
# core; their subprocesses included), with coverage.py: prints the total and writes
# build/coverage/html/index.html. About two minutes here. Under the tracer the slow tests (fits,
# whole doctor runs) got through 6 % in 20 minutes and the realtime ones (1 kHz node graphs) fall
# behind, so they are left out: the figure is a floor, the one to hold when code moves. Extra
# arguments go to pytest.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
"$top/scripts/setup.sh"
venv="${BELLOWS_VENV:-$top/.venv}"
cd "$top"
rm -rf build/coverage
mkdir -p build/coverage
status=0
"$venv/bin/python" -m coverage run -m pytest -q -m "not realtime and not slow" -n "$(nproc 2>/dev/null || echo 1)" \
  -p no:cacheprovider "$@" || status=$?
"$venv/bin/python" -m coverage combine -q
"$venv/bin/python" -m coverage html -q -d build/coverage/html
echo "bellows coverage: branch coverage of bellows_ros $("$venv/bin/python" -m coverage report \
  --format=total)% (build/coverage/html/index.html)"
exit "$status"
