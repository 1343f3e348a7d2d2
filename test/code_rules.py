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

"""Rules the tests hold the code and the docs to, read from their text."""
import ast


def names_in_conditions(source, names):
    """Return (line, name) of every string of `names` inside an if, a loop's or a match's test."""
    found = []
    for node in ast.walk(ast.parse(source)):
        tests = ([node.test] if isinstance(node, (ast.If, ast.IfExp, ast.While)) else
                 node.ifs if isinstance(node, ast.comprehension) else
                 [node.subject] if isinstance(node, ast.Match) else [])
        for test in tests:
            found += [(test.lineno, c.value) for c in ast.walk(test)
                      if isinstance(c, ast.Constant) and c.value in names]
    return found


def missing_from_section(text, heading, names):
    """Return the `names` the Markdown section under `heading` of `text` does not name in code."""
    assert heading in text, f'no section {heading!r}'
    section = text.split(heading, 1)[1].split('\n## ', 1)[0]
    return [name for name in names if f'`{name}`' not in section]
