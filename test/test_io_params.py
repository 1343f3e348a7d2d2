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
Parameter files (io/params.py): ROS 2's format, read as rcl reads it, laid over the defaults.

Nested maps flatten to dotted names, node sections lie over the wildcard as rcl merges them, a
plain scalar is typed as rcl types it, and a user's file can only change what the defaults have,
with a value of the same kind. Every refusal is one line naming the file (and its line, or the
parameter); the `bellows` command turns it into exit status 2.
"""
import re

import numpy as np
import pytest

from bellows_ros.cli import main
from bellows_ros.errors import ParameterError
from bellows_ros.io import params


def write(path, text):
    path.write_text(text)
    return path


def test_ros2_parameter_file_flattens_and_overlays(tmp_path):
    defaults = write(tmp_path / 'd.yaml',
                     '/**:\n  ros__parameters:\n    a:\n      b: 1.0\n      c: [1.0, 2.0]\n')
    user = write(tmp_path / 'u.yaml', '/**:\n  ros__parameters:\n    a: {b: 5.0}\n')
    merged = params.overlay(params.read_file(defaults), params.read_file(user), user)
    assert merged == {'a.b': 5.0, 'a.c': [1.0, 2.0]}


def test_node_section_lies_over_wildcard(tmp_path):
    path = write(tmp_path / 'p.yaml', '/**:\n  ros__parameters: {x: 1, y: 2}\n'
                                      'model_node:\n  ros__parameters: {x: 3}\n'
                                      'other:\n  ros__parameters: {y: 9}\n')
    assert params.read_file(path, 'model_node') == {'x': 3, 'y': 2}


def test_a_package_url_names_a_file_of_the_packages_share(tmp_path):
    url = 'package://bellows_ros/config/segment_sim_arm.yaml'
    assert params.resolve(url) == params.config_dir() / 'segment_sim_arm.yaml'
    assert params.read_file(url) == params.read_file(params.resolve(url))
    assert params.resolve(tmp_path / 'p.yaml') == tmp_path / 'p.yaml'  # a path stays a path
    with pytest.raises(ParameterError, match=r'package://no_such_package/x\.yaml: no package '
                                             r"'no_such_package'"):
        params.read_file('package://no_such_package/x.yaml')


def test_unknown_parameter_is_named(tmp_path):
    user = write(tmp_path / 'u.yaml', '/**:\n  ros__parameters:\n    a: {bogus: 1.0}\n')
    with pytest.raises(ParameterError, match=r"u\.yaml: unknown parameter 'a\.bogus'"):
        params.overlay({'a.b': 1.0}, params.read_file(user), user)


def test_yaml_syntax_error_names_line(tmp_path):
    bad = write(tmp_path / 'bad.yaml', '/**:\n  ros__parameters:\n    a: [1, 2\n')
    with pytest.raises(ParameterError, match=r'bad\.yaml:\d+: '):
        params.read_file(bad)


def test_non_finite_parameter_rejected(tmp_path):
    bad = write(tmp_path / 'nan.yaml', '/**:\n  ros__parameters:\n    a: .nan\n')
    with pytest.raises(ParameterError, match="'a' is not finite"):
        params.read_file(bad)


def test_write_then_read_round_trip(tmp_path):
    flat = {'s.mu': [1.5, np.float64(2.5)], 's.n': 4, 's.name': 'x'}
    params.write_file(tmp_path / 'o.yaml', flat, header='fitted')
    assert params.read_file(tmp_path / 'o.yaml') == {'s.mu': [1.5, 2.5], 's.n': 4, 's.name': 'x'}


def test_plain_scalars_are_typed_as_rcl_types_them(tmp_path):
    path = write(tmp_path / 'p.yaml', '/**:\n  ros__parameters:\n'
                 '    on: yes\n    off: Off\n    hex: 0x1F\n    octal: 012\n    minus: -0x10\n'
                 '    half: .5\n    small: 1e-3\n    under: 1_000\n    date: 2026-01-01\n'
                 '    ratio: 1:20\n    quoted: "12"\n    hexfloat: 0x1p-2\n')
    flat = params.read_file(path)
    # Keys are names as written (YAML 1.1 would make `on`, `off` booleans); `1_000`, the date and
    # the ratio stay strings; a quoted number is a string.
    assert flat == {'on': True, 'off': False, 'hex': 31, 'octal': 10, 'minus': -16,
                    'half': 0.5, 'small': 1e-3, 'under': '1_000', 'date': '2026-01-01',
                    'ratio': '1:20', 'quoted': '12', 'hexfloat': 0.25}
    assert type(flat['hex']) is int and type(flat['half']) is float


@pytest.mark.parametrize('section, node, applies', [
    ('/**', '/model_node', True),
    ('/**', '/arm_a/model_node', True),
    ('/*', '/model_node', True),
    ('/*', '/arm_a/model_node', False),          # `*` is one name token
    ('/arm_a/*', '/arm_a/model_node', True),
    ('/**/model_node', '/a/b/model_node', True),  # `**` is any number of them
    ('/model_node', '/arm_a/model_node', False),
    ('/arm_a/model_node', '/arm_b/model_node', False),
])
def test_a_section_applies_to_a_node_by_rcls_rule(section, node, applies):
    assert params.section_matches(section, node) is applies


def test_sections_for_a_node_in_a_namespace_merge_in_file_order(tmp_path):
    path = write(tmp_path / 'p.yaml', '/**:\n  ros__parameters: {x: 1, y: 1, z: 1}\n'
                                      '/arm_a/*:\n  ros__parameters: {x: 2, y: 2}\n'
                                      '/arm_a/model_node:\n  ros__parameters: {x: 3}\n'
                                      '/arm_b/model_node:\n  ros__parameters: {z: 9}\n')
    assert params.read_file(path, '/arm_a/model_node') == {'x': 3, 'y': 2, 'z': 1}
    assert params.read_file(path, 'model_node') == {'x': 1, 'y': 1, 'z': 1}


@pytest.mark.parametrize('default, value, needle', [
    (1.0, "'fast'", "expects a number (like 1.0), got 'fast'"),
    (1.0, 'true', 'expects a number (like 1.0), got True'),  # YAML's true is not the number 1
    ([1.0, 2.0], '3.0', 'expects a list (like [1.0, 2.0]), got 3.0'),
    ([1.0, 2.0], "[1.0, 'x']", "expects a list of numbers (like [1.0, 2.0]), got 'x' in it"),
    ('label', '5', "expects a string (like 'label'), got 5"),
])
def test_a_value_of_another_kind_than_the_default_is_refused(tmp_path, default, value, needle):
    user = write(tmp_path / 'u.yaml', f'/**:\n  ros__parameters:\n    a: {value}\n')
    with pytest.raises(ParameterError) as error:
        params.overlay({'a': default}, params.read_file(user), user)
    assert str(error.value) == f"{user}: parameter 'a' {needle}"
    assert params.overlay({'a': 1.0}, {'a': 2}, user) == {'a': 2}  # an int is a number


@pytest.mark.parametrize('text, needle', [
    ('- 1\n- 2\n', "expected a map of node names to 'ros__parameters'"),
    ('/**:\n  parameters: {a: 1}\n', "section '/**' has no 'ros__parameters' map"),
    ('/**:\n  ros__parameters:\n    "a b": 1\n', "'a b' is not a parameter name"),
    ('/**:\n  ros__parameters:\n    a: {b: {c: [1, {d: 2}]}}\n', "parameter 'a.b.c' has an "
     "unsupported value {'d': 2}"),
    ('/**:\n  ros__parameters:\n    a: 1' + '0' * 400 + '\n', "parameter 'a' is beyond float "
     'range'),
    ('other_node:\n  ros__parameters: {a: 1}\n', "no '/**' section with 'ros__parameters'"),
])
def test_a_malformed_file_is_one_line_naming_it(tmp_path, text, needle):
    path = write(tmp_path / 'bad.yaml', text)
    with pytest.raises(ParameterError) as error:
        params.read_file(path)
    assert str(error.value).startswith(f'{path}') and needle in str(error.value)
    assert '\n' not in str(error.value)


def test_what_is_no_parameter_file_is_named(tmp_path):
    binary = tmp_path / 'p.yaml'
    binary.write_bytes(b'\xff\xfe\x00garbage')
    for path, needle in [(tmp_path, 'not a regular file'),
                         (tmp_path / 'missing.yaml', 'cannot read parameter file'),
                         (binary, 'not a text file')]:
        with pytest.raises(ParameterError, match=needle):
            params.read_file(path)


def test_build_makes_the_dataclass_and_names_what_does_not_fit():
    import dataclasses

    @dataclasses.dataclass(frozen=True)
    class Gains:
        kp: float
        taps: tuple
        ki: float = 0.0

    gains = params.build(Gains, {'kp': 2.0, 'taps': [1, 2]}, 'g.yaml')
    assert gains == Gains(2.0, (1.0, 2.0)) and isinstance(gains.taps[0], float)
    with pytest.raises(ParameterError, match=r"^g\.yaml: unknown parameter 'kd'$"):
        params.build(Gains, {'kp': 2.0, 'taps': [], 'kd': 1.0}, 'g.yaml')
    with pytest.raises(ParameterError, match=r"^g\.yaml: missing parameter 'taps'$"):
        params.build(Gains, {'kp': 2.0}, 'g.yaml')


def test_flatten_and_unflatten_are_inverse():
    tree = {'segment': {'ogden': {'mu': [1.0, 2.0], 'gamma': [3.0, 6.0]}, 'p0': 1e5}, 'n': 'x'}
    flat = params.flatten(tree)
    assert flat == {'segment.ogden.mu': [1.0, 2.0], 'segment.ogden.gamma': [3.0, 6.0],
                    'segment.p0': 1e5, 'n': 'x'}
    assert params.unflatten(flat) == tree
    assert params.section(flat, 'segment.ogden') == {'mu': [1.0, 2.0], 'gamma': [3.0, 6.0]}


def test_a_bad_parameter_file_given_to_the_command_is_one_line_and_status_2(tmp_path, capsys):
    bad = write(tmp_path / 'bad.yaml', '/**:\n  ros__parameters:\n    actuator:\n'
                '      stiffness: {x_s_low: [0.0\n')
    unknown = write(tmp_path / 'unknown.yaml', '/**:\n  ros__parameters:\n    actuator:\n'
                    '      stiffness: {x_s_middle: 0.006}\n')
    for path, needle in [(bad, rf'{bad}:\d+: '),
                         (unknown, rf"{unknown}: unknown parameter 'actuator\.stiffness\."
                                   r"x_s_middle'")]:
        # the parameters are read before the data: the record need not exist
        assert main(['stiffness', str(tmp_path / 'r.csv'), '--params', str(path)]) == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert len(lines) == 1, lines
        assert lines[0].startswith('bellows stiffness: error: '), lines
        assert re.search(needle, lines[0]), lines
