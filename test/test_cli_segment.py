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
`bellows simulate segment` / `bellows identify segment`: round trip and bad input.

Bad input: exit 2, one line naming file, line and column, no traceback.
"""
import csv
from pathlib import Path
import subprocess
import sys

import numpy as np
import pytest

from bellows_ros.cli import main
from bellows_ros.config.segment import load_segment_params, load_segment_plant_params
from bellows_ros.models.segment import OUTPUTS, simulate_model
from bellows_ros.models.segment_plant import FULL_MODEL
from bellows_ros.papers.segment_experiments import quasi_static_record

PLANT = load_segment_plant_params()

COLUMNS = ['t', 'psi', 'p1', 'p2', 'tau_ext', 'psi_dot']


def write(path, record, columns=COLUMNS, extra=True):
    with open(path, 'w', newline='') as stream:
        writer = csv.writer(stream)
        writer.writerow(columns + (['note'] if extra else []))
        for k in range(len(record['t'])):
            writer.writerow([repr(float(record[c][k])) for c in columns]
                            + (['keep me'] if extra else []))
    return path


def read(path):
    with open(path, newline='') as stream:
        rows = list(csv.reader(stream))
    return rows[0], rows[1:]


@pytest.fixture(scope='module')
def record():
    return quasi_static_record(load_segment_params(), PLANT, FULL_MODEL, None, seed=4,
                               duration=8.0, dt=1e-2)


def test_simulate_writes_input_plus_the_model_outputs_with_state_carried(tmp_path, record):
    source = write(tmp_path / 'in.csv', record)
    assert main(['simulate', 'segment', '--input', str(source), '--output',
                 str(tmp_path / 'out.csv')]) == 0
    header, rows = read(tmp_path / 'out.csv')
    assert header == COLUMNS + ['note'] + list(OUTPUTS)
    assert all(row[6] == 'keep me' for row in rows)
    out = np.array([[float(v) for v in row[7:]] for row in rows])
    expected = simulate_model(load_segment_params(), record['psi'], record['p1'], record['p2'],
                              record['psi_dot'])
    for k, name in enumerate(OUTPUTS):
        np.testing.assert_allclose(out[:, k], expected[name], rtol=1e-12, atol=1e-12)
    assert np.ptp(out[:, 0]) > 0.005  # the strain memory moved along the rows


def test_simulate_with_effects_runs_the_plant(tmp_path, record):
    source = write(tmp_path / 'in.csv', record)
    args = ['simulate', 'segment', '--input', str(source), '--output', str(tmp_path / 'plant.csv')]
    assert main(args + ['--effect', 'contact_hysteresis', '--effect', 'sensor_lag:tau=0.1']) == 0
    header, rows = read(tmp_path / 'plant.csv')
    assert {'p1_cmd', 'p2_cmd', 'tau_motion'} <= set(header) and set(OUTPUTS) <= set(header)
    p1 = np.array([float(r[header.index('p1')]) for r in rows])
    cmd = np.array([float(r[header.index('p1_cmd')]) for r in rows])
    assert np.max(np.abs(p1 - cmd)) > 1e4  # the measured pressure lags the command


@pytest.mark.slow
def test_identify_round_trip_through_the_cli(tmp_path, record):
    """Identify (subprocess: the real entry point) -> YAML -> simulate with --params."""
    short = {k: v[:400] for k, v in record.items()}
    data = write(tmp_path / 'data.csv', short)
    fitted = tmp_path / 'fitted.yaml'
    bellows = Path(sys.executable).with_name('bellows')  # the installed console script
    done = subprocess.run([str(bellows), 'identify', 'segment', str(data),
                           '--output', str(fitted), '--quiet'], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    assert 'paper A' in done.stdout and 'previous model (34)' in done.stdout
    assert 'RMSE' in done.stdout
    assert load_segment_params(fitted).ogden_gamma[0] > 2.0
    assert main(['simulate', 'segment', '--input', str(data), '--output', str(tmp_path / 'o.csv'),
                 '--params', str(fitted)]) == 0


def _error(capsys, args):
    status = main(args)
    err = capsys.readouterr().err
    assert status == 2
    assert len(err.strip().splitlines()) == 1 and 'Traceback' not in err
    return err


def _rewrite(path, line, column, value):
    with open(path, newline='') as stream:
        rows = list(csv.reader(stream))
    rows[line - 1][rows[0].index(column)] = value
    with open(path, 'w', newline='') as stream:
        csv.writer(stream).writerows(rows)
    return path


@pytest.mark.parametrize('line, column, value, expected', [
    (5, 'psi', 'nan', "bad.csv:5: column 'psi'"),
    (6, 't', '0.0', "bad.csv:6: column 't': not increasing"),
    (7, 'p1', '-5', "bad.csv:7: column 'p1'"),
    (8, 'p2', '800000', "bad.csv:8: column 'p2'"),
    (9, 'psi_dot', 'fast', "bad.csv:9: column 'psi_dot': not a number"),
])
def test_bad_rows_name_file_line_and_column(tmp_path, capsys, record, line, column, value,
                                            expected):
    bad = _rewrite(write(tmp_path / 'bad.csv', record), line, column, value)
    err = _error(capsys,
                 ['simulate', 'segment', '--input', str(bad), '--output', str(tmp_path / 'o.csv')])
    assert expected in err


def test_missing_column_is_named(tmp_path, capsys, record):
    bad = write(tmp_path / 'bad.csv', record, columns=['t', 'psi', 'p2', 'tau_ext'])
    err = _error(capsys,
                 ['simulate', 'segment', '--input', str(bad), '--output', str(tmp_path / 'o.csv')])
    assert "bad.csv:1: missing column 'p1'" in err
    err = _error(capsys, ['identify', 'segment', str(bad), '--output', str(tmp_path / 'p.yaml'),
                          '--quiet'])
    assert "missing column 'p1'" in err


def test_unknown_parameter_and_effect_are_named(tmp_path, capsys, record):
    source = write(tmp_path / 'in.csv', record)
    params = tmp_path / 'p.yaml'
    params.write_text('/**:\n  ros__parameters:\n    segment:\n      geometry:\n        l1: '
                      '0.05\n')
    base = ['simulate', 'segment', '--input', str(source), '--output', str(tmp_path / 'o.csv')]
    assert "p.yaml: unknown parameter 'segment.geometry.l1'" in _error(
        capsys, base + ['--params', str(params)])
    assert "unknown segment effect 'bogus'" in _error(capsys, base + ['--effect', 'bogus'])
    assert "unknown parameter 'tau_x'" in _error(capsys, base + ['--effect', 'sensor_lag:tau_x=1'])


def test_bench_reports_the_step_and_the_previous_model_in_one_run(capsys):
    import json
    assert main(['bench', '--only', 'segment', '--quick', '--json']) == 0
    results = {r['name']: r for r in json.loads(capsys.readouterr().out)['results']}
    step = results['segment: paper A model step (both chains)']
    assert step['reference'] == 'segment: previous model (34) step'
    # structure only: tests never judge wall-clock times
    assert step['ratio'] is not None and step['target'] == 20e-6 and step['samples'] >= 20000
