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

A module `<area>/<module>.py` has its unit tests in `test_<area>_<module>.py` (`hardware` is
`hw`), a module at the package's root in `test_<module>.py`. An effect of
`models/<system>_effects/` has `test_<system>_effect_<effect>.py`, and the contract's `base` is
tested by the conformance test named after the package (`test_<system>_effects.py`). The name is
exact: a test module named after a module of another area does not count.

The other way round, a test module is a module's, or one of the kinds that test the package as a
whole: `test_core_*` (checks across the package), `test_graph_*` (node graphs), or one of
`WHOLE_PACKAGE`.
"""
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / 'bellows_ros'
TESTS = Path(__file__).resolve().parent
AREA_PREFIX = {'hardware': 'hw'}
WHOLE_PACKAGE = {
    # the doctor end to end, on records of the plant
    'test_doctor_actuator', 'test_doctor_bag', 'test_doctor_edges', 'test_doctor_identifiability',
    'test_doctor_live_segments', 'test_doctor_segment',
    # ament's linters, the docs, the layers, the launch files, the user's workflow
    'test_copyright', 'test_flake8', 'test_pep257', 'test_docs', 'test_import_layers',
    'test_launch', 'test_workflow',
    # every node's parameters and processes, the recorder under signals, the sourced-ROS path
    'test_node_parameters', 'test_loopback_only', 'test_record_signals',
    'test_session_processes', 'test_sourced_ros', 'test_tests_mirror_the_code',
}


def expected_test_module(module):
    """Return the name of the test module of `module` (a path below the package, no suffix)."""
    *areas, name = Path(module).parts
    if not areas:
        return f'test_{name}'
    if areas[-1].endswith('_effects'):
        system = areas[-1][:-len('_effects')]
        return f'test_{areas[-1]}' if name == 'base' else f'test_{system}_effect_{name}'
    return f'test_{AREA_PREFIX.get(areas[0], areas[0])}_{name}'


def modules():
    """Return the package's modules, as paths below the package without the suffix."""
    return [str(p.relative_to(PACKAGE).with_suffix('')) for p in PACKAGE.rglob('*.py')
            if p.name != '__init__.py']


def test_every_module_has_its_test_module():
    tests = {p.stem for p in TESTS.glob('test_*.py')}
    missing = sorted(f'{module}: {expected_test_module(module)}.py' for module in modules()
                     if expected_test_module(module) not in tests)
    assert missing == [], 'give these modules their test module'


def test_every_test_module_is_a_modules_or_tests_the_whole_package():
    named = {expected_test_module(module) for module in modules()} | WHOLE_PACKAGE
    stray = sorted(p.name for p in TESTS.glob('test_*.py') if p.stem not in named
                   and not p.stem.startswith(('test_core_', 'test_graph_')))
    assert stray == [], 'name these after the module they test, or say what they are'


def test_the_rule_reads_names_as_the_docs_say():
    assert expected_test_module('hardware/device') == 'test_hw_device'
    assert expected_test_module('control/angle_tracking') == 'test_control_angle_tracking'
    assert expected_test_module('interfaces') == 'test_interfaces'
    assert expected_test_module('models/actuator_effects/base') == 'test_actuator_effects'
    assert expected_test_module('models/segment_effects/sensor_lag') == \
        'test_segment_effect_sensor_lag'
    # Another area's test of the same name is not the module's: models/actuator is not tested
    # by the doctor's end-to-end test_doctor_actuator.
    assert expected_test_module('models/actuator') == 'test_models_actuator'
