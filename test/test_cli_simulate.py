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
`bellows simulate` (cli/simulate.py): the model, or the plant with --effect, over an input file.

Run in this process through the `bellows` entry point. The command checks its output and its
--effect arguments before any work (one line, exit 2, nothing written), then hands the input,
the output, --params and the effects to the system's `simulate` (cli/actuator.py,
cli/segment.py), whose physics their own tests hold.
"""
import csv

import numpy as np
import pytest
from test_cli_export import one_line, read_csv

from bellows_ros.cli import main
from bellows_ros.config.actuator import load_actuator_params
from bellows_ros.models.actuator import evaluate_array
from bellows_ros.models.segment import OUTPUTS


def write_actuator_input(path, n=200, dt=1e-3):
    """x_c (m) around the design point, x_s (m) from 0: inside both travel limits."""
    t = np.arange(n) * dt
    x_c = 0.02 + 0.005 * np.sin(10.0 * t)
    x_s = 0.004 * (1.0 - np.cos(20.0 * t))
    with open(path, 'w', newline='') as stream:
        writer = csv.writer(stream)
        writer.writerow(['t', 'x_c', 'x_s'])
        writer.writerows(zip(*(column.tolist() for column in (t, x_c, x_s))))
    return path


def write_segment_input(path, n=100, dt=1e-2):
    t = np.arange(n) * dt
    psi = 0.5 * np.sin(t)
    p1, p2 = 101325.0 + 2e5 * (1 + np.sin(t)), 101325.0 + 1e5 * (1 + np.cos(t))
    with open(path, 'w', newline='') as stream:
        writer = csv.writer(stream)
        writer.writerow(['t', 'psi', 'p1', 'p2'])
        writer.writerows(zip(*(column.tolist() for column in (t, psi, p1, p2))))
    return path


def simulate(system, source, output, *more):
    return main(['simulate', system, '--input', str(source), '--output', str(output), *more])


def test_without_effects_the_output_is_the_input_plus_the_models(tmp_path, capsys):
    source = write_actuator_input(tmp_path / 'in.csv')
    assert simulate('actuator', source, tmp_path / 'out.csv') == 0
    header, table = read_csv(tmp_path / 'out.csv')
    assert header == ['t', 'x_c', 'x_s', 'p', 'f', 'k']
    _, given = read_csv(source)
    np.testing.assert_array_equal(table[:, :3], given)
    # p Pa, f N, k N/m: the model (paper B) at each row's compressions.
    expected = evaluate_array(load_actuator_params(), given[:, 1], given[:, 2])
    for k, column in enumerate(expected):
        np.testing.assert_allclose(table[:, 3 + k], column, rtol=1e-12)
    assert 'bellows simulate actuator: 200 rows, model -> ' in capsys.readouterr().err


def test_an_effect_runs_the_plant_and_params_are_laid_over_the_config(tmp_path, capsys):
    source = write_actuator_input(tmp_path / 'in.csv')
    assert simulate('actuator', source, tmp_path / 'model.csv') == 0
    assert simulate('actuator', source, tmp_path / 'plant.csv',
                    '--effect', 'air_leak:conductance=1e-9') == 0
    assert 'plant with air_leak -> ' in capsys.readouterr().err
    _, model = read_csv(tmp_path / 'model.csv')
    _, plant = read_csv(tmp_path / 'plant.csv')
    assert not np.allclose(plant[:, 3], model[:, 3], rtol=1e-6, atol=0.0)
    # A larger tube volume (--params) damps the pressure swing of the same compressions.
    overlay = tmp_path / 'p.yaml'
    overlay.write_text('/**:\n  ros__parameters:\n    actuator:\n      gas:\n'
                       '        v_tube: 3.0e-05\n')
    assert simulate('actuator', source, tmp_path / 'tube.csv', '--params', str(overlay)) == 0
    _, tube = read_csv(tmp_path / 'tube.csv')
    assert 0.0 < np.ptp(tube[:, 3]) < np.ptp(model[:, 3])


def test_the_segment_goes_to_the_segment_model(tmp_path):
    source = write_segment_input(tmp_path / 'in.csv')
    assert simulate('segment', source, tmp_path / 'out.csv') == 0
    header, table = read_csv(tmp_path / 'out.csv')
    assert header == ['t', 'psi', 'p1', 'p2', *OUTPUTS] and len(table) == 100


@pytest.mark.parametrize('effect, needle', [
    ('air_leek', "unknown actuator effect 'air_leek'"),
    ('contact_hysteresis', "unknown actuator effect 'contact_hysteresis'"),  # the segment's
    ('air_leak:conductance=-1', 'outside its range'),
    ('air_leak:conductance=nan', 'finite decimal number'),
    ('air_leak:conductance', 'expected k=v'),
])
def test_a_bad_effect_is_refused_before_the_input_is_read(tmp_path, capsys, effect, needle):
    # The input does not exist: the effect is judged first.
    output = tmp_path / 'out.csv'
    assert simulate('actuator', tmp_path / 'missing.csv', output, '--effect', effect) == 2
    one_line(capsys, 'bellows simulate: error:', needle)
    assert not output.exists()


def test_an_effect_given_twice_is_refused(tmp_path, capsys):
    source = write_actuator_input(tmp_path / 'in.csv')
    assert simulate('actuator', source, tmp_path / 'out.csv',
                    '--effect', 'air_leak', '--effect', 'air_leak:conductance=1e-9') == 2
    one_line(capsys, '--effect air_leak: given twice')
    assert not (tmp_path / 'out.csv').exists()


@pytest.mark.parametrize('over', ['input', 'params'])
def test_an_output_over_an_input_is_refused_and_the_input_kept(tmp_path, capsys, over):
    source = write_actuator_input(tmp_path / 'in.csv')
    overlay = tmp_path / 'p.yaml'
    overlay.write_text('/**:\n  ros__parameters:\n    actuator:\n      gas:\n'
                       '        v_tube: 3.0e-05\n')
    target = source if over == 'input' else overlay
    before = target.read_bytes()
    assert simulate('actuator', source, target, '--params', str(overlay)) == 2
    one_line(capsys, f'--output {target}', 'an input of this command')
    assert target.read_bytes() == before


def test_a_missing_input_is_named_and_nothing_is_written(tmp_path, capsys):
    missing = tmp_path / 'missing.csv'
    assert simulate('segment', missing, tmp_path / 'out.csv') == 2
    one_line(capsys, str(missing))
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_input_and_output_are_required_arguments(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        main(['simulate', 'actuator', '--output', str(tmp_path / 'out.csv')])
    assert stop.value.code == 2
    one_line(capsys, '--input')
