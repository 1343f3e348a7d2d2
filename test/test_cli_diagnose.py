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
`bellows diagnose` (cli/diagnose.py): the doctor's file work, run in this process.

The parameters (config with --params over it), the record read for the doctor (whole, or as
block means with the raw chunks' noise floors), the report directory written whole, and the
refusals before any work (one line, exit 2, no report). What the doctor finds is its own tests'.
"""
import csv
import json

import numpy as np
import pytest

from bellows_ros.cli import main
from bellows_ros.cli.diagnose import load_params, read_for_doctor
from bellows_ros.config.actuator import load_actuator
from bellows_ros.doctor.diagnosis import raw_noise
from bellows_ros.io import data
from bellows_ros.papers.actuator_experiments import actuator_record

OVERLAY = '/**:\n  ros__parameters:\n    actuator:\n      gas:\n        v_tube: 2.0e-05\n'


def write_record(path, duration, seed=1):
    """Write a simulated actuator record (paper B's programme, the YAML's sensor noise)."""
    config = load_actuator()
    record = actuator_record(config.model, config.plant, seed=seed, duration=duration)
    with open(path, 'w', newline='') as stream:
        writer = csv.writer(stream)
        writer.writerow(list(record))
        writer.writerows(zip(*(column.tolist() for column in record.values())))
    return path


@pytest.fixture(scope='module')
def record_10s(tmp_path_factory):
    return write_record(tmp_path_factory.mktemp('record') / 'actuator.csv', 10.0)


def one_line(capsys, *fragments):
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'Traceback' not in err, err
    for fragment in fragments:
        assert fragment in err, err


def test_params_are_the_systems_config_with_the_overlay_laid_over_it(tmp_path):
    overlay = tmp_path / 'p.yaml'
    overlay.write_text(OVERLAY)
    default = load_params('actuator', None)
    laid = load_params('actuator', str(overlay))
    assert default.model.v_tube != 2.0e-5 and laid.model.v_tube == 2.0e-5
    assert laid.model.chamber == default.model.chamber  # the rest is the config's
    assert type(load_params('segment', None)).__name__ == 'SegmentConfig'


def test_a_short_record_goes_to_the_doctor_whole(record_10s):
    config = load_actuator()
    table, extra = read_for_doctor(str(record_10s), 'actuator', config.model)
    assert extra == {}  # no block means, so no raw floors to carry
    assert len(table) == 10000 and table.names == ['t', 'x_c', 'x_s', 'p', 'f']


def test_a_long_record_goes_as_block_means_with_its_raw_chunks_noise(record_10s, monkeypatch):
    # 10000 rows over a 2000-row limit: blocks of 5 rows; 1000-row chunks, 10 of them.
    monkeypatch.setattr(data, 'FIT_ROWS', 2000)
    monkeypatch.setattr(data, 'CHUNK_ROWS', 1000)
    model = load_actuator().model
    table, extra = read_for_doctor(str(record_10s), 'actuator', model)
    assert extra['factor'] == 5 and len(table) == 2000
    chunks = [raw_noise('actuator', chunk, model)
              for chunk in data.read_chunks(str(record_10s), 'actuator')]
    assert len(chunks) == 10
    assert extra['raw_noise'] == {name: pytest.approx(np.median([c[name] for c in chunks]))
                                  for name in ('p', 'f')}
    # The block means hide the noise: their own floor is lower than the raw rows'.
    averaged = raw_noise('actuator', table, model)
    assert averaged['p'] < 0.7 * extra['raw_noise']['p']


def test_the_report_directory_holds_every_output_and_the_summary_is_printed(
        record_10s, tmp_path, capsys):
    report = tmp_path / 'report'
    assert main(['diagnose', 'actuator', str(record_10s), '--report', str(report),
                 '--quiet']) == 0
    out = capsys.readouterr().out
    assert out.startswith('actuator: cause ') and out.endswith(f'; report in {report}\n')
    names = {p.name for p in report.iterdir()}
    assert {'report.json', 'details.json', 'report.md', 'extended.yaml'} <= names
    assert json.loads((report / 'report.json').read_text())
    assert json.loads((report / 'details.json').read_text())
    # Every plot is written and report.md shows each.
    plots = sorted(name for name in names if name.endswith('.png'))
    markdown = (report / 'report.md').read_text()
    assert plots and all(f'({name})' in markdown for name in plots)
    assert all((report / name).read_bytes().startswith(b'\x89PNG') for name in plots)
    assert (report / 'extended.yaml').read_text().startswith('# Extended actuator model')
    # Built beside it and swapped in: nothing else is left in the parent.
    assert sorted(p.name for p in tmp_path.iterdir()) == ['report']


def test_a_report_directory_that_holds_the_input_is_refused(tmp_path, capsys):
    report = tmp_path / 'report'
    report.mkdir()
    source = write_record(report / 'actuator.csv', 0.5)
    before = source.read_bytes()
    assert main(['diagnose', 'actuator', str(source), '--report', str(report), '--quiet']) == 2
    one_line(capsys, f'--report {report}', 'holds an input of this command')
    assert [p.name for p in report.iterdir()] == ['actuator.csv']
    assert source.read_bytes() == before


def test_a_report_path_that_is_a_file_is_refused(record_10s, tmp_path, capsys):
    report = tmp_path / 'report'
    report.write_text('mine\n')
    assert main(['diagnose', 'actuator', str(record_10s), '--report', str(report),
                 '--quiet']) == 2
    one_line(capsys, f'--report {report}', 'is a file, not a directory')
    assert report.read_text() == 'mine\n'


@pytest.mark.parametrize('what', ['params', 'data'])
def test_a_bad_parameter_file_or_record_is_named_and_no_report_written(
        record_10s, tmp_path, capsys, what):
    params = tmp_path / 'p.yaml'
    params.write_text(OVERLAY.replace('2.0e-05', '-1.0'))  # a negative volume
    source = tmp_path / 'missing.csv'
    args = {'params': [str(record_10s), '--params', str(params)], 'data': [str(source)]}[what]
    assert main(['diagnose', 'actuator', *args, '--report', str(tmp_path / 'report'),
                 '--quiet']) == 2
    one_line(capsys, 'bellows diagnose: error:', str(params if what == 'params' else source))
    assert not (tmp_path / 'report').exists()
