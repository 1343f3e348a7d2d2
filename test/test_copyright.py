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
Every Python file carries the Apache-2.0 header, as ament_copyright checks it in ROS 2 packages.

Where ROS 2 is sourced (CI, a colcon workspace) ament_copyright itself does the check. Elsewhere
(a plain virtual environment) this test does the same check on the same header text: after an
optional shebang or coding line, the first comment block is `Copyright <year> <holder>` followed
by the Apache License 2.0 notice; empty files need none.
"""
from pathlib import Path
import re

import pytest

ROOT = Path(__file__).resolve().parent.parent
PATHS = ['bellows_ros', 'test', 'launch', 'setup.py']

# The notice ament_copyright's 'apache2' license expects below the copyright line and a blank one.
APACHE_NOTICE = """Licensed under the Apache License, Version 2.0 (the "License");
you may not use this file except in compliance with the License.
You may obtain a copy of the License at

    http://www.apache.org/licenses/LICENSE-2.0

Unless required by applicable law or agreed to in writing, software
distributed under the License is distributed on an "AS IS" BASIS,
WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
See the License for the specific language governing permissions and
limitations under the License."""
COPYRIGHT = re.compile(r'Copyright (\d{4})(-\d{4})?(, \d{4}(-\d{4})?)* \S.*')


def python_files():
    """Yield the .py files ament_copyright would check, skipping folders that start with . or _."""
    for name in PATHS:
        path = ROOT / name
        if path.is_file():
            yield path
            continue
        for file in sorted(path.rglob('*.py')):
            if not any(part[0] in '._' for part in file.relative_to(path).parent.parts):
                yield file


def header_problem(text):
    """Why `text` lacks the copyright and license header, or None when it has them."""
    lines = text.splitlines()
    while lines and lines[0].startswith('#') and (
            lines[0].startswith('#!') or re.match(r'#.*coding[:=]', lines[0])):
        lines.pop(0)
    while lines and not lines[0].strip():
        lines.pop(0)
    block = []
    for line in lines:
        if not line.startswith('#'):
            break
        block.append(line[2:] if line.startswith('# ') else line[1:])
    if not block or not COPYRIGHT.fullmatch(block[0]):
        return 'could not find copyright notice'
    notice = [''] + APACHE_NOTICE.split('\n')
    if block[1:1 + len(notice)] != notice:
        return 'copyright found, but not followed by the Apache-2.0 notice'
    return None


def test_header_check_tells_good_from_bad():
    header = ''.join(f'# {line}\n' if line else '#\n'
                     for line in ('Copyright 2026 holder\n\n' + APACHE_NOTICE).split('\n'))
    assert header_problem(header + '\nimport os\n') is None
    assert header_problem('#!/usr/bin/env python3\n' + header) is None
    assert header_problem('"""Doc."""\n' + header) == 'could not find copyright notice'
    assert header_problem(header.replace('2.0', '3.0', 1)) is not None
    assert header_problem(header.replace('# Copyright 2026 holder', '# Copyright holder')) \
        == 'could not find copyright notice'


@pytest.mark.linter
def test_copyright():
    try:
        from ament_copyright.main import main
    except ImportError:  # no ROS 2 sourced: the same check, done here
        problems = []
        for file in python_files():
            text = file.read_text(encoding='utf-8')
            problem = header_problem(text) if text.strip() else None
            if problem:
                problems.append(f'{file.relative_to(ROOT)}: {problem}')
        checked = len(list(python_files()))
        assert checked > 50, f'only {checked} files found under {PATHS}'
        assert not problems, f'{len(problems)} files without the header:\n' + '\n'.join(problems)
    else:
        rc = main(argv=[str(ROOT / name) for name in PATHS])
        assert rc == 0, 'Found errors (listed above)'
