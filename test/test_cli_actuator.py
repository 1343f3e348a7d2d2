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

"""`bellows simulate actuator` and `bellows identify actuator`: outputs and one-line errors."""
import csv
import subprocess
import sys

import numpy as np
import pytest

from bellows_ros.cli import main
from bellows_ros.config.actuator import load_actuator_params, load_actuator_plant_params
from bellows_ros.models.actuator import evaluate_array
from bellows_ros.papers.actuator_experiments import actuator_record, volume_test_series

PLANT = load_actuator_plant_params()

PARAMS = load_actuator_params()


def write(path, columns):
    names = list(columns)
    with open(path, 'w', newline='') as stream:
        writer = csv.writer(stream)
        writer.writerow(names)
        writer.writerows(zip(*[columns[n] for n in names]))
    return str(path)


def read(path):
    with open(path, newline='') as stream:
        rows = list(csv.DictReader(stream))
    return {name: np.array([float(r[name]) for r in rows]) for name in rows[0]}


@pytest.fixture(scope='module')
def record(tmp_path_factory):
    data = actuator_record(PARAMS, PLANT, seed=5, duration=4.0)
    return write(tmp_path_factory.mktemp('rec') / 'in.csv', data), data


def test_simulate_model_writes_input_plus_p_f_k(record, tmp_path):
    path, data = record
    out = tmp_path / 'out.csv'
    assert main(['simulate', 'actuator', '--input', path, '--output', str(out)]) == 0
    result = read(out)
    assert list(result) == ['t', 'x_c', 'x_s', 'p', 'f', 'k']
    p, f, k = evaluate_array(PARAMS, data['x_c'], data['x_s'])
    assert np.allclose(result['p'], p, rtol=1e-12) and np.allclose(result['k'], k, rtol=1e-12)
    assert np.array_equal(result['x_c'], data['x_c'])


def test_simulate_with_effects_runs_the_plant(record, tmp_path):
    path, data = record
    leak, tight = tmp_path / 'leak.csv', tmp_path / 'tight.csv'
    assert main(['simulate', 'actuator', '--input', path, '--output', str(leak),
                 '--effect', 'air_leak:conductance=1e-9']) == 0
    assert main(['simulate', 'actuator', '--input', path, '--output', str(tight),
                 '--effect', 'air_leak:conductance=0']) == 0
    a, b = read(leak), read(tight)
    assert a['p'][0] == b['p'][0]
    assert np.any(np.abs(a['p'] - b['p']) > 50.0)
    # Effects-off plant replays the geometric model exactly (noise-free sensors).
    from bellows_ros.models.actuator import without_bulging
    p, _, _ = evaluate_array(without_bulging(PARAMS), data['x_c'], data['x_s'])
    assert np.allclose(b['p'], p, rtol=1e-9)


@pytest.mark.parametrize('change,needle', [
    (lambda d: d.pop('x_s'), "missing column 'x_s'"),
    (lambda d: d['x_c'].__setitem__(3, np.nan), "in.csv:5: column 'x_c'"),
    (lambda d: d['x_c'].__setitem__(7, 0.060), "in.csv:9: column 'x_c': 0.06 m is outside"),
    (lambda d: d['x_s'].__setitem__(2, -0.2), "in.csv:4: column 'x_s'"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, change, needle):
    data = {k: v.copy() for k, v in actuator_record(PARAMS, PLANT, seed=1, duration=0.02).items()}
    change(data)
    path = write(tmp_path / 'in.csv', data)
    code = main(['simulate', 'actuator', '--input', path, '--output', str(tmp_path / 'o.csv')])
    err = capsys.readouterr().err
    assert code == 2
    assert needle in err and err.count('\n') == 1


@pytest.mark.parametrize('effect,needle', [('air_leek', "'air_leek'"),
                                           ('backlash:widht=0.001', "'widht'"),
                                           ('sensor_lag:time_constant=abc', 'time_constant')])
def test_bad_effect_is_one_line_and_exit_2(record, tmp_path, capsys, effect, needle):
    path, _ = record
    code = main(['simulate', 'actuator', '--input', path, '--output', str(tmp_path / 'o.csv'),
                 '--effect', effect])
    err = capsys.readouterr().err
    assert code == 2 and needle in err and err.count('\n') == 1


def test_exit_status_of_the_real_command(tmp_path):
    path = write(tmp_path / 'in.csv', {'t': [0.0, 0.001], 'x_c': [0.0, 0.0]})
    command = 'import sys; from bellows_ros.cli import main; sys.exit(main())'
    done = subprocess.run([sys.executable, '-c', command, 'simulate', 'actuator', '--input', path,
                           '--output', str(tmp_path / 'o.csv')], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 2
    assert "missing column 'x_s'" in done.stderr and 'Traceback' not in done.stderr


def test_identify_writes_loadable_parameters(tmp_path, capsys):
    data = volume_test_series(PARAMS, PLANT, gases=(0.95, 1.05), effects=('wall_bulging',), seed=3,
                              duration=6.0)
    path = write(tmp_path / 'series.csv', data)
    out = tmp_path / 'fit.yaml'
    assert main(['identify', 'actuator', path, '--output', str(out), '--quiet']) == 0
    text = capsys.readouterr().out
    assert 'volume error:' in text and 'mL' in text and 'force error:' in text
    fitted = load_actuator_params(out)
    assert fitted.v_tube == pytest.approx(PARAMS.v_tube, abs=1e-6)
    assert fitted.p_ref == pytest.approx(0.95 * PARAMS.p_ref, rel=2e-3)
