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
The data table both readers return (io/table.py), and the checks made on any table.

A `Table` keeps each row's file line (for errors) and the columns it does not compute with (to
write them back); selecting rows keeps all of it aligned. `check_increasing` names the first row
whose time does not increase, by file, line and column; `check_held` refuses a column that would
hold a channel's last value over a gap in it, naming the channel, the column, the times and the
`bellows export --start/--end` that keeps the recorded part. Through the `bellows` command: one
line, exit status 2.
"""
from hypothesis import given, settings, strategies as st
import numpy as np
import pytest

from bellows_ros.cli import main
from bellows_ros.errors import DataError
from bellows_ros.io.bag import _hold
from bellows_ros.io.table import check_held, check_increasing, COLUMNS, MAX_HELD_STEPS, Table

DT = 0.01   # s: the rows' step in the hand-made tables


def held_table(have, topic='/bellows/wrench', dt=DT):
    """Return a table of len(have) rows, dt apart; 'f' has a message of its own where `have`."""
    t = np.arange(len(have)) * dt
    stamps = t[have]
    # As a zero-order hold takes them: the last message before (the first one before it starts).
    index = np.clip(np.searchsorted(stamps, t, side='right') - 1, 0, len(stamps) - 1)
    age = np.abs(t - stamps[index])
    return Table('bag', ['t', 'f'], {'t': t, 'f': np.zeros(len(t))},
                 held={'f': (topic, age, dt)})


def refusal(table):
    with pytest.raises(DataError) as error:
        check_held(table)
    return str(error.value)


def test_a_table_gives_columns_rows_and_file_lines():
    table = Table('in.csv', ['t', 'a', 'note'], {'t': np.array([0.0, 1.0, 2.0]),
                                                 'a': np.array([5.0, 6.0, 7.0])},
                  extras={'note': ['x', 'y', 'z']}, lines=[2, 3, 5])
    assert len(table) == 3 and 'a' in table and 'note' not in table
    assert list(table['a']) == [5.0, 6.0, 7.0]
    assert table.line(2) == 5  # a blank line 4 in the file
    assert Table('bag', ['t'], {'t': np.zeros(2)}).line(1) is None  # a bag has no lines


def test_selected_rows_keep_their_lines_extras_and_held_ages():
    age = np.array([0.0, 0.5, 0.0, 0.7])
    table = Table('in.csv', ['t', 'f', 'note'], {'t': np.arange(4.0), 'f': np.arange(4.0) * 2},
                  extras={'note': ['a', 'b', 'c', 'd']}, lines=[2, 3, 4, 6],
                  held={'f': ('/bellows/wrench', age, 0.1)})
    part = table.rows(np.array([False, True, False, True]))
    assert list(part['t']) == [1.0, 3.0] and list(part['f']) == [2.0, 6.0]
    assert part.extras == {'note': ['b', 'd']} and part.lines == [3, 6]
    topic, part_age, step = part.held['f']
    assert topic == '/bellows/wrench' and list(part_age) == [0.5, 0.7] and step == 0.1
    assert table.rows(np.ones(4, bool)).lines == table.lines


def test_time_that_does_not_increase_is_named_by_file_line_and_column():
    table = Table('in.csv', ['t'], {'t': np.array([0.0, 0.5, 1.0, 1.0, 0.2])},
                  lines=[2, 3, 4, 6, 7])
    with pytest.raises(DataError) as error:
        check_increasing(table)
    # the first offending row, equal time included, by its file line (a blank line 5)
    assert str(error.value) == "in.csv:6: column 't': not increasing (1 after 1)"
    check_increasing(Table('in.csv', ['t'], {'t': np.array([0.0, 1e-9, 2.0])}))
    bag = Table('bag', ['x'], {'x': np.array([3.0, 2.0])})
    with pytest.raises(DataError, match=r"^bag: column 'x': not increasing \(2 after 3\)$"):
        check_increasing(bag, 'x')


def test_a_channel_that_starts_late_points_to_the_start():
    have = np.arange(100) >= 30
    line = refusal(held_table(have))
    assert line.startswith("bag: column 'f': /bellows/wrench starts late: no message before "
                           't = 0.3 s: its last value would stand in for the measurement'), line
    assert line.endswith('(`bellows export` with `--start 0.3`)'), line


def test_a_channel_that_stops_early_points_to_the_end():
    have = np.arange(100) < 60
    line = refusal(held_table(have))
    assert '/bellows/wrench stops early: no message after t = 0.59 s (the record runs to 0.99 ' \
        's)' in line, line
    assert line.endswith('(`bellows export` with `--end 0.59`)'), line


def test_a_hole_names_both_sides_and_counts_the_other_holes():
    have = np.ones(200, bool)
    have[50:70] = False
    have[120:140] = False
    line = refusal(held_table(have))
    assert 'has no message from t = 0.49 s to 0.7 s (and 1 more gaps)' in line, line
    assert line.endswith('with `--end 0.49`, `--start 0.7`)'), line


def test_a_few_held_rows_and_tables_without_channels_pass():
    have = np.ones(100, bool)
    have[40:40 + int(MAX_HELD_STEPS)] = False  # exactly the limit: still the channel's own pace
    check_held(held_table(have, dt=0.125))     # (a step binary fractions hold exactly)
    have[40:41 + int(MAX_HELD_STEPS)] = False  # one more: a gap
    with pytest.raises(DataError, match='has no message from'):
        check_held(held_table(have, dt=0.125))
    check_held(Table('in.csv', ['t'], {'t': np.arange(3.0)}))  # a CSV holds nothing
    check_held(held_table(np.ones(5, bool)).rows(np.zeros(5, bool)))  # no rows


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 199), st.integers(1, 30)), max_size=3),
       st.sampled_from([1e-3, 5e-3, 2e-2]))
def test_a_channel_is_refused_iff_it_is_silent_longer_than_the_limit(holes, dt):
    """Any holes at any place (start, middle, end): refused exactly when one is over the limit."""
    n = 200
    have = np.ones(n, bool)
    for start, length in holes:
        have[start:start + length] = False
    if have.sum() < n // 2:   # the channel's own median step stays the rows' step
        return
    stamps = (np.arange(n) * dt * 1e9).astype(np.int64) + 5 * 10 ** 9
    _, (age, step) = _hold(stamps, stamps[have], np.arange(n, dtype=float)[have, None])
    table = Table('bag', ['t', 'f'], {'t': (stamps - stamps[0]) * 1e-9, 'f': np.zeros(n)},
                  held={'f': ('/bellows/wrench', age, step)})
    runs, run = [], 0
    for row in have:
        run = 0 if row else run + 1
        runs.append(run)
    longest = max(runs)
    # a hole at the start counts from the first message back
    first = int(np.argmax(have))
    if longest <= MAX_HELD_STEPS and first <= MAX_HELD_STEPS:
        check_held(table)
    else:
        with pytest.raises(DataError, match="column 'f': /bellows/wrench .*bellows export"):
            check_held(table)


def actuator_csv(path, rows):
    """Write an actuator CSV of `rows` (t, x_c, x_s, p, f each) after the header."""
    path.write_text(','.join(COLUMNS['actuator'][0]) + '\n'
                    + ''.join(','.join(map(str, row)) + '\n' for row in rows))
    return path


def test_a_bad_table_given_to_the_command_is_one_line_and_status_2(tmp_path, capsys):
    good = [(k * 1e-3, 0.01, 0.002, 1.2e5, 3.0) for k in range(30)]
    backwards = actuator_csv(tmp_path / 'back.csv', good[:20] + [good[5]] + good[20:])
    short = tmp_path / 'short.csv'
    short.write_text('t,x_c,x_s,p\n0,0.01,0.002,1.2e5\n')
    for path, needle in [(backwards, f"{backwards}:22: column 't': not increasing "
                                     '(0.005 after 0.019)'),
                         (short, f"{short}:1: missing column 'f' (header has: t, x_c, x_s, "
                                 'p)')]:  # COLUMNS' required ones
        assert main(['stiffness', str(path)]) == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert lines == [f'bellows stiffness: error: {needle}'], lines
