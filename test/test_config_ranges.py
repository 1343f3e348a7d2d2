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
The physical range of every number (config/ranges.py): the check, its message and its parts.

A value outside its closed range is refused in one line naming the source, the parameter, the
range with its unit and, where one is likely, the unit mistake; strings and booleans are left to
`params.overlay`, which names a value of the wrong kind. The `bellows` command's numeric options
take their ranges from the same module and refuse with argparse's one line, exit 2.
(test_core_refusals.py holds every number of the three files to an entry of RANGES.)
"""
import argparse

import pytest

from bellows_ros.cli import main
from bellows_ros.config import ranges
from bellows_ros.config.ranges import check_effects, check_ranges, option_type, Range, range_of
from bellows_ros.errors import ParameterError


def parameter_file(path, body):
    path.write_text(f'/**:\n  ros__parameters:\n    {body}\n')
    return path


def test_a_range_is_closed_and_its_refusal_names_source_range_unit_and_hint():
    rule = ranges.RANGES['segment.geometry.l0']
    for value in (rule.low, rule.high, 0.05):
        check_ranges({'segment.geometry.l0': value}, 'p.yaml')
    for value in (rule.low * 0.999, rule.high * 1.001):
        with pytest.raises(ParameterError) as error:
            check_ranges({'segment.geometry.l0': value}, 'p.yaml')
        assert str(error.value) == (f"p.yaml: parameter 'segment.geometry.l0' is {value:g}, "
                                    'outside its physical range 0.001..1 m (was it written in '
                                    'mm?)')


def test_a_list_is_checked_item_by_item_with_each_items_range():
    # segment.ogden.mu: one range for every item; actuator.force.e_f: one range per item (11).
    check_ranges({'segment.ogden.mu': [4000.0, 300.0]}, 'p.yaml')
    with pytest.raises(ParameterError, match=r"'segment\.ogden\.mu' item 2 is 0\.5, outside"):
        check_ranges({'segment.ogden.mu': [4000.0, 0.5]}, 'p.yaml')
    e_f = [2.36, 1e-5, 527.0, -6.6]
    check_ranges({'actuator.force.e_f': e_f}, 'p.yaml')
    # 2100 fits the first item's range (N) but not the third's (1/m): the third's applies.
    with pytest.raises(ParameterError, match=r"'actuator\.force\.e_f' item 3 is 2100, outside "
                                             r'its physical range -2000\.\.2000 1/m$'):
        check_ranges({'actuator.force.e_f': [2.36, 1e-5, 2100.0, -6.6]}, 'p.yaml')


def test_strings_booleans_and_unranged_names_are_left_to_others():
    check_ranges({'hardware.actuator_board.port': '/dev/ttyUSB0',   # a string parameter
                  'segment.geometry.l0': True,                     # a kind error: overlay's
                  'segment.ogden.mu': ['a', 4000.0],
                  'no.such.name': 1e30}, 'p.yaml')
    assert range_of('hardware.actuator_board.port') is None


def test_a_fit_bound_takes_the_range_of_its_parameter():
    assert range_of('actuator.buckling.bounds.critical_pressure') == \
        ranges.RANGES['actuator.buckling.critical_pressure']
    with pytest.raises(ParameterError, match=r"'actuator\.buckling\.bounds\.critical_pressure' "
                                             r'item 1 is 0, outside'):
        check_ranges({'actuator.buckling.bounds.critical_pressure': [0.0, 3e5]}, 'p.yaml')


def test_ranges_of_their_own_are_given_by_more():
    more = {'actuator.effects.demo.k': Range(0.0, 1.0, '1', 'a fraction')}
    check_ranges({'actuator.effects.demo.k': 2.0}, 'p.yaml')  # unknown here: not checked
    with pytest.raises(ParameterError, match=r"'actuator\.effects\.demo\.k' is 2, outside its "
                                             r'physical range 0\.\.1 1 \(a fraction\)'):
        check_ranges({'actuator.effects.demo.k': 2.0}, 'p.yaml', more)


def test_load_blames_the_users_file_and_opens_only_the_effects_section(tmp_path):
    user = parameter_file(tmp_path / 'u.yaml', 'segment: {p0: 1.01325}')
    with pytest.raises(ParameterError, match=rf"^{user}: parameter 'segment\.p0' is 1\.01325, "
                                             r'outside .*\(an ambient pressure: was it written '
                                             r'in bar or kPa\?\)$'):
        ranges.load('segment', user)
    # actuator.effects.* belong to the effects (config.actuator checks them), nothing else does.
    effects = parameter_file(tmp_path / 'e.yaml', 'actuator: {effects: {demo: {k: 1.0}}}')
    assert ranges.load('actuator', effects)['actuator.effects.demo.k'] == 1.0
    other = parameter_file(tmp_path / 'o.yaml', 'segment: {effects: {demo: {k: 1.0}}}')
    with pytest.raises(ParameterError, match="unknown parameter 'segment.effects.demo.k'"):
        ranges.load('segment', other)


def test_an_effect_value_outside_its_range_is_named_as_given():
    def effect_range(effect, key):
        return Range(0.0, 10.0, 'N', 'a force') if (effect, key) == ('push', 'f') else None
    check_effects({'push': {'f': 10.0}, 'other': {'x': 1e9}}, effect_range)
    with pytest.raises(ParameterError) as error:
        check_effects({'push': {'f': 12.5}}, effect_range)
    assert str(error.value) == ('--effect push:f=12.5: 12.5 is outside its range 0..10 N '
                                '(a force)')


def test_an_options_type_takes_a_finite_number_in_its_range():
    window = option_type('stiffness.window')
    assert window('4') == 4.0 and window('0.01') == 0.01 and window('3600') == 3600.0
    for text, needle in [('abc', "expected a number in s, got 'abc'"),
                         ('nan', "expected a finite number in s, got 'nan'"),
                         ('inf', "expected a finite number in s, got 'inf'"),
                         ('0.001', '0.001 is outside its range 0.01..3600 s')]:
        with pytest.raises(argparse.ArgumentTypeError, match=needle):
            window(text)


def test_an_option_outside_its_range_is_one_line_and_status_2(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(['stiffness', str(tmp_path / 'r.csv'), '--setpoint', '1e9'])
    assert exit_.value.code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    assert '--setpoint' in lines[0] and '1e+09 is outside its range 1..1e+06 N/m' in lines[0]
