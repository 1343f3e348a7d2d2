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
The tests mirror the code (docs/development.md, "The tests"): each module has a test module.

A module's unit tests are `test_<area>_<module>.py`; a contract's `base` is tested by the test
named after its package (`test_actuator_effects.py`). The modules of `NOT_YET` have no test module
of their own yet: each is tested from another module's tests or, for the nodes and commands,
through their processes and `main`. A new module gets its own, and a module that gets its own
leaves the list: this test fails both ways.
"""
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / 'bellows_ros'
TESTS = Path(__file__).resolve().parent
NOT_YET = {
    'hardware/sim_arm_bus',
}


def unmirrored(modules, test_names):
    """Return the modules (paths below the package, no suffix) no test module is named after."""
    def named(module):
        path = Path(module)
        stem = path.parent.name if path.name == 'base' else path.name
        return any(name == f'test_{stem}' or name.endswith(f'_{stem}') for name in test_names)
    return {module for module in modules if not named(module)}


def test_every_module_has_its_test_module_or_is_listed_as_not_yet():
    modules = {str(p.relative_to(PACKAGE).with_suffix('')) for p in PACKAGE.rglob('*.py')
               if p.name != '__init__.py'}
    missing = unmirrored(modules, {p.stem for p in TESTS.glob('test_*.py')})
    assert sorted(missing - NOT_YET) == [], 'give these a test module named after them'
    assert sorted(NOT_YET - missing) == [], 'these have theirs now: take them off NOT_YET'


def test_the_rule_reads_names_as_the_docs_say():
    tests = {'test_hw_device', 'test_actuator_effects', 'test_control_angle_tracking'}
    assert unmirrored({'hardware/device', 'models/actuator_effects/base',
                       'control/angle_tracking', 'control/closed_loop'}, tests) \
        == {'control/closed_loop'}
