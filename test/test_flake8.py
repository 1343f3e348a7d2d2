# Copyright 2026 bellows_ros maintainers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""
flake8 with ament_flake8's configuration (setup.cfg [flake8]): 99 columns, Google import order.

ament_flake8 is not in every ROS 2 build nor on PyPI, so the test runs flake8 itself, with the
plugins ament_flake8 brings (flake8-quotes, flake8-import-order, flake8-builtins,
flake8-comprehensions; the `test` extra installs them) and its settings, which setup.cfg holds so
that `flake8` alone, run in the package, checks the same.
"""
from pathlib import Path
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parent.parent
PATHS = ['bellows_ros', 'test', 'launch', 'setup.py']


@pytest.mark.linter
@pytest.mark.slow  # the whole tree
def test_flake8():
    result = subprocess.run(
        [sys.executable, '-m', 'flake8', '--no-show-source', *PATHS], cwd=ROOT,
        capture_output=True, text=True)
    errors = [line for line in result.stdout.splitlines() if line.startswith(tuple(PATHS))]
    assert result.returncode == 0 and not result.stderr, \
        f'Found {len(errors)} code style errors / warnings:\n{result.stdout}{result.stderr}'
