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
Docstrings follow PEP 257 as ament_pep257 checks them (setup.cfg [pydocstyle]).

ament_pep257's defaults leave out the codes for missing docstrings, D203, D212 and D404, so a
multi-line docstring starts its summary on the second line (D213). pydocstyle (the `test` extra)
runs with those settings, from setup.cfg, on every .py file, test files included.
"""
from pathlib import Path
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parent.parent
PATHS = ['bellows_ros', 'test', 'launch', 'setup.py']


@pytest.mark.linter
@pytest.mark.slow  # the whole tree
def test_pep257():
    result = subprocess.run([sys.executable, '-m', 'pydocstyle', *PATHS], cwd=ROOT,
                            capture_output=True, text=True)
    assert result.returncode == 0, \
        f'Found {result.stdout.count(chr(10)) // 2} docstring errors:\n{result.stdout}' \
        f'{result.stderr}'
