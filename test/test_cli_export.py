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
`bellows export` (cli/export.py): a recording's table as CSV, cut to --start/--end.

Run in this process through the `bellows` entry point; the bags are written with rosbags' own
writer (test/bag_messages.py). Bad input is one line on stderr and exit status 2, and nothing is
written.
"""
import argparse
import csv
import math

from bag_messages import write_actuator_bag
import numpy as np
import pytest
from rosbags.rosbag2 import StoragePlugin
from test_doctor_bag import write_actuator_bag as write_record_bag
from test_identify_measured_stiffness import held_chamber_record

from bellows_ros.cli import main
from bellows_ros.cli.export import time_s
from bellows_ros.io.data import read_table

START_NS = 5 * 10 ** 9


def actuator_rows(n=400):
    """(stamp ns, x_c m, x_s m, p Pa, f N) at 1 kHz, every column moving."""
    return [(START_NS + k * 1_000_000, 0.01 + 1e-5 * np.sin(k / 30), 0.002 + 1e-3 * np.sin(k / 50),
             1.2e5 + 100.0 * np.sin(k / 40), 3.0 + np.sin(k / 50)) for k in range(n)]


def read_csv(path):
    with open(path, newline='') as stream:
        rows = list(csv.reader(stream))
    return rows[0], np.array([[float(v) for v in row] for row in rows[1:]])


def one_line(capsys, *fragments):
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'Traceback' not in err, err
    for fragment in fragments:
        assert fragment in err, err


@pytest.fixture
def bag(tmp_path):
    return write_actuator_bag(tmp_path / 'bag', actuator_rows(), StoragePlugin.MCAP, version=9)


def test_time_s_takes_finite_seconds_only():
    assert time_s('1.5') == 1.5 and time_s('-2e-3') == -2e-3
    for text in ('abc', '', 'nan', 'inf', '-inf'):
        with pytest.raises(argparse.ArgumentTypeError, match='time in s'):
            time_s(text)


def test_a_bag_is_exported_whole_with_its_values_in_si(bag, tmp_path, capsys):
    output = tmp_path / 'out.csv'
    assert main(['export', 'actuator', str(bag), '--output', str(output)]) == 0
    header, table = read_csv(output)
    assert header == ['t', 'x_c', 'x_s', 'p', 'f']
    rows = np.array(actuator_rows())
    assert table.shape == (400, 5)
    # t counts from the first sample, s; the other columns as recorded (m, m, Pa, N).
    np.testing.assert_allclose(table[:, 0], (rows[:, 0] - START_NS) * 1e-9, atol=1e-12)
    np.testing.assert_allclose(table[:, 1:], rows[:, 1:], rtol=1e-12)
    assert 'bellows export actuator: 400 rows (t, x_c, x_s, p, f)' in capsys.readouterr().err


def test_start_and_end_keep_the_rows_between_them_inclusive(bag, tmp_path):
    output = tmp_path / 'part.csv'
    assert main(['export', 'actuator', str(bag), '--output', str(output),
                 '--start', '0.1', '--end', '0.2']) == 0
    _, table = read_csv(output)
    assert len(table) == 101   # 0.100, 0.101, ... 0.200 s
    assert table[0, 0] == pytest.approx(0.1) and table[-1, 0] == pytest.approx(0.2)
    # Only one bound given: the other end is the record's own.
    assert main(['export', 'actuator', str(bag), '--output', str(output), '--start', '0.35']) == 0
    _, table = read_csv(output)
    assert table[0, 0] == pytest.approx(0.35) and table[-1, 0] == pytest.approx(0.399)


@pytest.mark.parametrize('start, end', [('0.2', '0.1'), ('0.2', '0.2')])
def test_a_start_not_before_the_end_is_refused_before_any_work(
        bag, tmp_path, capsys, start, end):
    output = tmp_path / 'out.csv'
    assert main(['export', 'actuator', str(bag), '--output', str(output),
                 '--start', start, '--end', end]) == 2
    one_line(capsys, 'bellows export: error:', f'--start {float(start):g} s',
             f'--end {float(end):g} s')
    assert not output.exists()


def test_a_time_that_is_not_a_finite_number_is_an_argument_error(bag, tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        main(['export', 'actuator', str(bag), '--output', str(tmp_path / 'o.csv'),
              '--end', 'nan'])
    assert stop.value.code == 2
    one_line(capsys, '--end', "'nan'")
    assert not (tmp_path / 'o.csv').exists()


def test_an_output_over_the_input_is_refused_and_the_input_kept(tmp_path, capsys):
    source = tmp_path / 'in.csv'
    source.write_text('t,x_c,x_s,p,f\n' + ''.join(
        f'{k * 1e-3!r},{0.01 + 1e-4 * math.sin(k)!r},0.002,{1.2e5 + k!r},{3.0 + 0.1 * k!r}\n'
        for k in range(50)))
    before = source.read_bytes()
    assert main(['export', 'actuator', str(source), '--output', str(source)]) == 2
    one_line(capsys, str(source), 'an input of this command')
    assert source.read_bytes() == before


def test_a_missing_recording_is_named_in_one_line(tmp_path, capsys):
    missing = tmp_path / 'no_such_bag'
    assert main(['export', 'segment', str(missing), '--output', str(tmp_path / 'o.csv')]) == 2
    one_line(capsys, str(missing))
    assert not (tmp_path / 'o.csv').exists()


def test_an_old_output_is_replaced_whole_or_kept_whole(bag, tmp_path, capsys):
    output = tmp_path / 'out.csv'
    output.write_text('an old export\n')
    # A span with no rows: refused, and the old file stays as it was.
    assert main(['export', 'actuator', str(bag), '--output', str(output),
                 '--start', '10', '--end', '11']) == 2
    one_line(capsys, str(bag), 'no rows with 10 s <= t <= 11 s')
    assert output.read_text() == 'an old export\n'
    assert main(['export', 'actuator', str(bag), '--output', str(output), '--end', '0.0095']) == 0
    header, table = read_csv(output)
    assert header == ['t', 'x_c', 'x_s', 'p', 'f'] and len(table) == 10
    assert sorted(p.name for p in tmp_path.iterdir()) == ['bag', 'out.csv']  # no temporary left


# The table identify reads: a bag of a simulated rig and its export read back alike.
def test_export_writes_the_table_identify_reads(tmp_path):
    record, _ = held_chamber_record(0.0, duration=1.0)
    bag = tmp_path / 'bag'
    write_record_bag(bag, record, every=2)
    out = tmp_path / 'bag.csv'
    assert main(['export', 'actuator', str(bag), '--output', str(out)]) == 0
    from_bag, from_csv = read_table(bag, 'actuator'), read_table(out, 'actuator')
    for name in ('t', 'x_c', 'x_s', 'p', 'f'):
        assert np.allclose(from_bag[name], from_csv[name], rtol=1e-12, atol=1e-12), name
    assert main(['export', 'actuator', str(bag), '--output', str(out)]) == 0  # replaced whole
    assert main(['export', 'actuator', str(out), '--output', str(out)]) == 2  # never its input
