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
`--effect NAME[:k=v,...]` arguments (cli/effects.py): read, and refused before any work.

A value is read as a CSV cell is (a plain decimal number); a parameter or an effect given twice,
a missing name or `=`, and a value outside the range of the parameter it sets are each one
ParameterError that quotes what was given, and at the command one line and exit status 2 before
anything is read or written.
"""
import pytest

from bellows_ros.cli import main
from bellows_ros.cli.effects import parse_effect, parse_effects
from bellows_ros.errors import ParameterError


@pytest.mark.parametrize('text, effect', [
    ('air_leak:conductance=2e-9,p_ambient=101325',
     ('air_leak', {'conductance': 2e-9, 'p_ambient': 101325.0})),
    (' air_leak : conductance = 2E-9 , ', ('air_leak', {'conductance': 2e-9})),
    ('backlash', ('backlash', {})),
    ('backlash:', ('backlash', {})),
    ('x:a=.5,b=-1e-3,c=+7.', ('x', {'a': 0.5, 'b': -1e-3, 'c': 7.0})),
])
def test_an_effect_is_its_name_and_its_parameters_as_floats(text, effect):
    name, options = parse_effect(text)
    assert (name, options) == effect
    assert all(type(value) is float for value in options.values())


@pytest.mark.parametrize('text, words', [
    (':conductance=1e-9', 'missing effect name'),
    ('air_leak:conductance', "expected k=v, got 'conductance'"),
    ('air_leak:=1e-9', "expected k=v, got '=1e-9'"),
    ('air_leak:conductance=1e-9,conductance=2e-9', 'conductance is given twice'),
    # what Python's float() takes and no CSV cell holds
    ('air_leak:conductance=1_0', "conductance must be a finite decimal number, got '1_0'"),
    ('air_leak:conductance=0x10', "got '0x10'"),
    ('air_leak:conductance=nan', "got 'nan'"),
    ('air_leak:conductance=-inf', "got '-inf'"),
    ('air_leak:conductance=', "got ''"),
    ('air_leak:conductance=\uff11', "got '\uff11'"),   # a full-width digit one
])
def test_a_malformed_effect_is_refused_quoting_it(text, words):
    with pytest.raises(ParameterError) as refused:
        parse_effect(text)
    message = str(refused.value)
    assert message.startswith(f'--effect {text!r}: ') and words in message, message
    assert '\n' not in message


def test_effects_of_a_system_are_one_dict_each_value_in_its_range():
    assert parse_effects(['air_leak:conductance=2e-11', 'backlash:width=1e-4'], 'actuator') == \
        {'air_leak': {'conductance': 2e-11}, 'backlash': {'width': 1e-4}}
    assert parse_effects([], 'segment') == {}
    # the range bounds are the parameter's own, inclusive (config.actuator.effect_range)
    assert parse_effects(['air_leak:conductance=1e-6'], 'actuator') == \
        {'air_leak': {'conductance': 1e-6}}
    with pytest.raises(ParameterError, match=r'--effect air_leak:conductance=1\.1e-06: '
                                             r'1\.1e-06 is outside its range 0\.\.1e-06'):
        parse_effects(['air_leak:conductance=1.1e-6'], 'actuator')
    with pytest.raises(ParameterError, match=r'--effect sensor_lag:tau=-1: .*outside its range'):
        parse_effects(['sensor_lag:tau=-1'], 'segment')


def test_an_effect_given_twice_is_refused_not_merged():
    with pytest.raises(ParameterError, match='--effect air_leak: given twice; give each effect '
                                             r'once, with all its parameters \(NAME:k=v,k=v\)'):
        parse_effects(['air_leak:conductance=2e-11', 'air_leak:p_ambient=101325'], 'actuator')


def test_the_command_refuses_a_bad_effect_in_one_line_before_any_work(tmp_path, capsys):
    data, output = tmp_path / 'in.csv', tmp_path / 'out.csv'
    data.write_text('t,x_c,x_s,p,f\n')   # never read: the effects are checked first
    assert main(['simulate', 'actuator', '--input', str(data), '--output', str(output),
                 '--effect', 'air_leak:conductance=1', '--effect', 'backlash']) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'Traceback' not in err, err
    assert err.startswith('bellows simulate: error: --effect air_leak:conductance=1: ')
    assert not output.exists() and sorted(p.name for p in tmp_path.iterdir()) == ['in.csv']
