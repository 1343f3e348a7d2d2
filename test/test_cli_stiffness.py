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
`bellows stiffness DATA [--params P] [--window S] [--setpoint K]` (cli/stiffness.py).

Over a made-up test-machine record (the chamber held, the spring cycled 0-12 mm every 4 s, the
load cell reading F = F0 + K x_s + C x_s^2) the command prints one line per cycle: its mid time
(s), the chamber compression (mm) and the stiffness (N/m), the mean slope of F over the spring
range of the parameters (`actuator.stiffness.x_s_low/x_s_high`), so K + C (x_s_high + x_s_low);
with `--setpoint`, the error of each cycle and their RMS. A record with no measurable cycle, and
an option outside its range, are one line and exit status 2.
"""
import math

import numpy as np
import pytest

from bellows_ros.cli import main

K, C, F0 = 1800.0, 5.0e3, 0.4   # N/m, N/m², N
PERIOD = 4.0   # s, of the spring motion
X_C = 0.01   # m: the chamber held


def spring_record(path, cycles=3, amplitude=0.012, x_c=None, rate=100.0):
    """Write a CSV of `cycles` spring cycles 0..amplitude (m) at `rate` Hz; return its path."""
    t = np.arange(round(cycles * PERIOD * rate) + 1) / rate
    x_s = 0.5 * amplitude * (1.0 - np.cos(2.0 * math.pi * t / PERIOD))
    x_c = np.full_like(t, X_C) if x_c is None else x_c(t)
    f = F0 + K * x_s + C * x_s ** 2
    rows = np.column_stack([t, x_c, x_s, np.full_like(t, 1.2e5), f])
    lines = [','.join(map(repr, row)) + '\n' for row in rows.tolist()]
    path.write_text('t,x_c,x_s,p,f\n' + ''.join(lines))
    return path


def cycles(out):
    """(mid time s, x_c mm, stiffness N/m, error N/m or None) of each cycle line printed."""
    found = []
    for line in out.splitlines():
        if line.startswith('t '):
            words = line.split()
            error = float(words[10]) if 'error' in words else None
            found.append((float(words[1]), float(words[4]), float(words[7]), error))
    return found


def one_line(capsys):
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'Traceback' not in err, err
    return err


def test_each_spring_cycle_gives_its_stiffness_over_0_to_12_mm(tmp_path, capsys):
    record = spring_record(tmp_path / 'rig.csv')
    assert main(['stiffness', str(record)]) == 0
    out = capsys.readouterr().out
    measured = cycles(out)
    assert [row[:2] for row in measured] == [(2.0, 10.0), (6.0, 10.0), (10.0, 10.0)]
    # the mean slope of F over 0..12 mm: K + C * 0.012
    assert all(row[2] == pytest.approx(K + C * 0.012, abs=0.1) for row in measured), out
    assert all(row[3] is None for row in measured) and 'RMS' not in out


def test_the_setpoint_adds_each_cycles_error_and_their_rms(tmp_path, capsys):
    record = spring_record(tmp_path / 'rig.csv')
    assert main(['stiffness', str(record), '--setpoint', '1900']) == 0
    out = capsys.readouterr().out
    k = K + C * 0.012
    assert [row[3] for row in cycles(out)] == pytest.approx([k - 1900.0] * 3, abs=0.1)
    assert out.splitlines()[-1] == (f'stiffness error against 1900 N/m over 3 cycles: '
                                    f'RMS {abs(k - 1900.0):.1f} N/m')


def test_the_spring_range_is_the_parameters(tmp_path, capsys):
    record = spring_record(tmp_path / 'rig.csv')
    params = tmp_path / 'range.yaml'
    params.write_text('/**:\n  ros__parameters:\n    actuator:\n      stiffness:\n'
                      '        x_s_low: 0.002\n        x_s_high: 0.006\n')
    assert main(['stiffness', str(record), '--params', str(params)]) == 0
    # the slope over 2..6 mm of F0 + K x + C x^2
    assert [row[2] for row in cycles(capsys.readouterr().out)] == \
        pytest.approx([K + C * 0.008] * 3, abs=0.1)


def test_a_cycle_where_the_chamber_moved_is_left_out(tmp_path, capsys):
    # the chamber travels 1 mm during the second cycle (4..8 s): not a test-machine cycle
    record = spring_record(tmp_path / 'rig.csv',
                           x_c=lambda t: X_C + 1e-3 * np.clip((t - 4.0) / 4.0, 0.0, 1.0))
    assert main(['stiffness', str(record)]) == 0
    measured = cycles(capsys.readouterr().out)
    assert [row[0] for row in measured] == [2.0, 10.0]
    assert [row[1] for row in measured] == [10.0, 11.0]


def test_the_window_is_one_period_of_the_spring_motion(tmp_path, capsys):
    # half-period windows each see the spring sweep 0..12 mm once, up or down
    record = spring_record(tmp_path / 'rig.csv')
    assert main(['stiffness', str(record), '--window', '2']) == 0
    measured = cycles(capsys.readouterr().out)
    assert [row[0] for row in measured] == [1.0, 3.0, 5.0, 7.0, 9.0, 11.0]
    assert [row[2] for row in measured] == pytest.approx([K + C * 0.012] * 6, abs=0.1)


def test_a_record_with_no_measurable_cycle_is_one_line_naming_it(tmp_path, capsys):
    record = spring_record(tmp_path / 'short_stroke.csv', amplitude=0.006)
    assert main(['stiffness', str(record)]) == 2
    assert one_line(capsys) == (f'bellows stiffness: error: {record}: no window of 4 s where '
                                'the chamber held still and the spring covered 0-12 mm\n')


def test_a_window_of_too_few_samples_is_refused_naming_the_file(tmp_path, capsys):
    record = spring_record(tmp_path / 'rig.csv')   # 100 Hz: 0.1 s holds 10 samples
    assert main(['stiffness', str(record), '--window', '0.1']) == 2
    err = one_line(capsys)
    assert str(record) in err and 'holds fewer than 20 samples' in err, err


@pytest.mark.parametrize('option, text', [
    ('--window', '0'), ('--window', '-4'), ('--window', 'nan'), ('--window', '4000'),
    ('--setpoint', '0.5'), ('--setpoint', 'inf'), ('--setpoint', '2e6'), ('--setpoint', 'x'),
])
def test_an_option_outside_its_range_is_one_line_and_exit_2(tmp_path, capsys, option, text):
    with pytest.raises(SystemExit) as stopped:
        main(['stiffness', str(tmp_path / 'never_read.csv'), option, text])
    assert stopped.value.code == 2
    assert f'argument {option}' in one_line(capsys)
