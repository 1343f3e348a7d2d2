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
`bellows identify {segment|actuator} DATA --output P.yaml` (cli/identify.py): its arguments.

What this module decides before a system's fit starts: the seed's range, `--leak` only for the
actuator, an output that can be written and is no input of the command; then the system's own
`identify` gets the arguments as given. The fits themselves are the system modules' (stood in for
here by a recorder: a refusal must come before the fit, and the fit must see what was asked).
"""
import pytest

from bellows_ros.cli import identify, main


@pytest.fixture
def fits(monkeypatch):
    """Record the arguments each system's `identify` is called with, by system; return 0."""
    called = {'segment': [], 'actuator': []}
    for system, seen in called.items():
        monkeypatch.setattr(f'bellows_ros.cli.{system}.identify',
                            lambda args, seen=seen: seen.append(args) or 0)
    return called


@pytest.fixture
def data(tmp_path):
    path = tmp_path / 'record.csv'
    path.write_text('t,x_c,x_s,p,f\n0.0,0.01,0.0,120000.0,3.0\n')
    return path


def one_line(capsys):
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'Traceback' not in err, err
    return err


@pytest.mark.parametrize('text, value', [('0', 0), ('4294967295', 2 ** 32 - 1), ('007', 7)])
def test_a_seed_is_a_whole_number_numpy_takes(text, value):
    assert identify.seed(text) == value


@pytest.mark.parametrize('text, words', [
    ('-1', 'expected 0 .. 2**32 - 1, got -1'),
    ('4294967296', 'expected 0 .. 2**32 - 1, got 4294967296'),
    ('1.5', "expected a whole number, got '1.5'"),
    ('seven', "expected a whole number, got 'seven'"),
])
def test_a_bad_seed_is_one_line_and_exit_2_before_the_fit(fits, data, tmp_path, capsys, text,
                                                          words):
    with pytest.raises(SystemExit) as stopped:
        main(['identify', 'actuator', str(data), '--output', str(tmp_path / 'p.yaml'),
              '--seed', text])
    assert stopped.value.code == 2
    err = one_line(capsys)
    assert 'argument --seed' in err and words in err, err
    assert fits == {'segment': [], 'actuator': []}


def test_the_systems_fit_gets_the_arguments_as_given(fits, data, tmp_path):
    params = tmp_path / 'start.yaml'
    params.write_text('/**:\n  ros__parameters: {}\n')
    output = tmp_path / 'fit.yaml'
    assert main(['identify', 'actuator', str(data), '--output', str(output), '--params',
                 str(params), '--seed', '42', '--quiet', '--leak']) == 0
    assert main(['identify', 'segment', str(data), '--output', str(output)]) == 0
    (actuator,), (segment,) = fits['actuator'], fits['segment']
    assert (actuator.data, actuator.output, actuator.params) == \
        (str(data), str(output), str(params))
    assert (actuator.seed, actuator.quiet, actuator.leak) == (42, True, True)
    assert (segment.seed, segment.quiet, segment.leak, segment.params) == (0, False, False, None)


def test_the_fits_status_is_the_commands(monkeypatch, data, tmp_path):
    monkeypatch.setattr('bellows_ros.cli.segment.identify', lambda args: 3)
    assert main(['identify', 'segment', str(data), '--output', str(tmp_path / 'p.yaml')]) == 3


def test_leak_is_refused_for_the_segment_before_the_fit(fits, data, tmp_path, capsys):
    output = tmp_path / 'p.yaml'
    assert main(['identify', 'segment', str(data), '--output', str(output), '--leak']) == 2
    assert one_line(capsys) == ('bellows identify: error: --leak: only the actuator holds a '
                                'sealed gas that can leak\n')
    assert fits['segment'] == [] and not output.exists()


@pytest.mark.parametrize('which', ['data', 'params'])
def test_an_output_that_is_an_input_is_refused_before_the_fit(fits, data, tmp_path, capsys,
                                                              which):
    params = tmp_path / 'start.yaml'
    params.write_text('/**:\n  ros__parameters: {}\n')
    before = {path: path.read_bytes() for path in (data, params)}
    output = data if which == 'data' else params
    assert main(['identify', 'actuator', str(data), '--output', str(output), '--params',
                 str(params)]) == 2
    err = one_line(capsys)
    assert f'--output {output}: that is an input of this command' in err, err
    assert fits['actuator'] == []
    assert {path: path.read_bytes() for path in (data, params)} == before


def test_an_output_in_a_missing_directory_is_refused_before_the_fit(
        fits, data, tmp_path, capsys):
    output = tmp_path / 'no' / 'such' / 'p.yaml'
    assert main(['identify', 'actuator', str(data), '--output', str(output)]) == 2
    err = one_line(capsys)
    assert f'--output {output}' in err, err
    assert fits['actuator'] == [] and not (tmp_path / 'no').exists()


def test_output_is_required_and_the_system_one_of_two(data, capsys):
    for argv, words in [(['identify', 'actuator', str(data)], '--output'),
                        (['identify', 'arm', str(data), '--output', 'p.yaml'], "'arm'")]:
        with pytest.raises(SystemExit) as stopped:
            main(argv)
        assert stopped.value.code == 2
        assert words in one_line(capsys)
