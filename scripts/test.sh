#!/usr/bin/env bash
# The test command: set up (if needed) and run the whole test suite. Extra arguments go to pytest.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
"$top/scripts/setup.sh"
cd "$top"
exec "${BELLOWS_VENV:-$top/.venv}/bin/python" -m pytest "$@"
