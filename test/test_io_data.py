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
Data tables (bellows_ros/io/data.py): CSV in, "the input plus outputs" out.

Every problem is one `DataError` naming the file, the line (header = line 1) and the column;
what is written reads back bit for bit, and a record read in chunks is checked across them.
"""
import math
import os

import numpy as np
import pytest

from bellows_ros.errors import DataError
from bellows_ros.io import data
from bellows_ros.io.table import Table


def write(path, text):
    path.write_text(text)
    return path


def segment_csv(path, rows=50, dt=0.01, p_scale=1.0):
    """Write a segment record (t, psi, p1, p2, tau_ext) in SI units: a slow bend, pressures."""
    t = np.arange(rows) * dt
    columns = [t, 0.3 * np.sin(t), (2e5 + 1e3 * t) * p_scale, (1.5e5 - 1e3 * t) * p_scale,
               0.01 * t]
    lines = [','.join(map(repr, row)) for row in zip(*(c.tolist() for c in columns))]
    return write(path, 't,psi,p1,p2,tau_ext\n' + '\n'.join(lines) + '\n')


@pytest.mark.parametrize('text, message', [
    ('', 'd.csv:1: empty file: expected a header row'),
    ('t,a\n', 'd.csv:2: no data rows after the header'),
    ('t,a\n0,1\n\n1\n', 'd.csv:4: expected 2 fields, found 1'),     # the blank line counts
    ('t,a\n0,1\n1,2,3\n', 'd.csv:3: expected 2 fields, found 3'),
    ('t,a\n0,1\n1,\n', "d.csv:3: column 'a': not a number: ''"),
    ('t,a\n0,1\n1,-inf\n', "d.csv:3: column 'a': -inf is not a finite number"),
    ('t,b\n0,1\n', "d.csv:1: missing column 'a' (header has: t, b)"),
])
def test_a_csv_mistake_is_one_error_naming_file_line_and_column(tmp_path, text, message):
    path = write(tmp_path / 'd.csv', text)
    with pytest.raises(DataError) as error:
        data.read_csv(path, ('t', 'a'))
    assert str(error.value) == f'{tmp_path}/{message}'


def test_an_input_that_is_no_regular_file_is_refused_before_it_is_read(tmp_path):
    # A FIFO would block a reader for ever: the refusal comes from its mode, before any open().
    fifo = tmp_path / 'in.csv'
    os.mkfifo(fifo)
    with pytest.raises(DataError, match='in.csv: is not a regular file'):
        data.read_csv(fifo, ('t',))
    with pytest.raises(DataError, match='in.csv: is not a regular file'):
        next(data.read_chunks(fifo, 'segment'))
    with pytest.raises(DataError, match='is a directory without metadata.yaml'):
        data.read_csv(tmp_path, ('t',))
    with pytest.raises(DataError, match=r'missing.csv: cannot read file \(No such file'):
        data.read_csv(tmp_path / 'missing.csv', ('t',))
    with pytest.raises(DataError, match='not a valid file name'):
        data.read_csv(str(tmp_path / 'a\0b.csv'), ('t',))


def test_what_is_written_reads_back_bit_for_bit(tmp_path):
    source = write(tmp_path / 'in.csv', 't,note,a\n0,first,1\n1,"x, y",2\n2,,3\n')
    table = data.read_csv(source, ('t', 'a'))
    awkward = np.array([1 / 3, 5e-324, -0.0])            # thirds, subnormal, negative zero
    data.write_csv(tmp_path / 'out.csv', table, {'b': awkward, 'c': np.array([1e300, 0.1, 7])})
    back = data.read_csv(tmp_path / 'out.csv', ('t', 'a', 'b', 'c'))
    assert back.names == ['t', 'note', 'a', 'b', 'c']   # the input's columns first, in order
    assert back.extras['note'] == ['first', 'x, y', '']  # text carried untouched
    assert back['b'].tobytes() == awkward.tobytes()       # -0.0 stays -0.0
    np.testing.assert_array_equal(back['c'], [1e300, 0.1, 7.0])
    # A value a model could not compute is written as nan, which no reader takes for a number.
    data.write_csv(tmp_path / 'nan.csv', table, {'b': np.array([1.0, math.inf, math.nan])})
    assert (tmp_path / 'nan.csv').read_text().splitlines()[2:] == ['1.0,"x, y",2.0,nan',
                                                                   '2.0,,3.0,nan']


def test_chunks_written_in_turn_make_one_file_with_one_header(tmp_path):
    first = Table('in', ['t', 'p'], {'t': np.array([0.0, 1.0]), 'p': np.array([5.0, 6.0])})
    second = Table('in', ['t', 'p'], {'t': np.array([2.0]), 'p': np.array([7.0])})
    with data.CsvOutput(tmp_path / 'o.csv') as output:
        # An output named like an input column replaces it in place (a re-run simulation).
        output.write(first, {'p': np.array([50.0, 60.0]), 'q': np.array([1.5, 2.5])})
        output.write(second, {'p': np.array([70.0]), 'q': np.array([3.5])})
    assert (tmp_path / 'o.csv').read_text() == ('t,p,q\n0.0,50.0,1.5\n1.0,60.0,2.5\n'
                                                '2.0,70.0,3.5\n')


def test_a_failure_half_way_leaves_the_old_output(tmp_path):
    out = write(tmp_path / 'o.csv', 'the old output\n')
    table = Table('in', ['t'], {'t': np.array([0.0, 1.0])})
    with pytest.raises(RuntimeError):
        with data.CsvOutput(out) as output:
            output.write(table, {})
            raise RuntimeError('the model failed on chunk 2')
    assert out.read_text() == 'the old output\n'
    assert [p.name for p in tmp_path.iterdir()] == ['o.csv']


def test_time_must_increase_across_chunks_and_the_error_names_the_files_line(tmp_path):
    path = segment_csv(tmp_path / 'r.csv', rows=10)
    lines = path.read_text().splitlines()
    # Row 7, the first of the third chunk, goes back behind row 6, the last of the second.
    lines[8] = '0.055' + lines[8][lines[8].index(','):]
    lines.insert(4, '')                                   # a blank line: line numbers shift
    write(path, '\n'.join(lines) + '\n')
    chunks = data.read_chunks(path, 'segment', rows=4)
    assert list(next(chunks).lines) == [2, 3, 4]          # lines 2..5, one blank
    assert list(next(chunks).lines) == [6, 7, 8, 9]
    with pytest.raises(DataError) as error:
        next(chunks)
    assert str(error.value) == f"{path}:10: column 't': not increasing (0.055 after 0.06)"


def test_a_span_keeps_the_rows_from_start_to_end_with_their_lines(tmp_path):
    path = segment_csv(tmp_path / 'r.csv', rows=50, dt=0.01)
    table = data.read_table(path, 'segment', span=(0.1, 0.2))
    np.testing.assert_allclose(table['t'], np.arange(10, 21) * 0.01)   # both ends kept
    assert table.line(0) == 12                                         # row 10, after the header
    with pytest.raises(DataError, match=r"column 't': no rows with 1 s <= t <= 2 s \(t runs "
                                        r'from 0 to 0.49 s\)'):
        data.read_table(path, 'segment', span=(1.0, 2.0))


def test_only_the_named_columns_are_held_to_their_units(tmp_path):
    # A simulation input may carry old output columns in any unit: they are replaced anyway.
    path = segment_csv(tmp_path / 'r.csv', p_scale=1e-3)          # pressures in kPa
    with pytest.raises(DataError, match="column 'p1'.*was the file written in hPa, kPa or bar"):
        data.read_table(path, 'segment')
    table = data.read_table(path, 'segment', required=('t', 'psi'))
    assert table['p1'][0] == pytest.approx(200.0)


def test_a_column_still_within_its_noise_never_moves(tmp_path):
    rng = np.random.default_rng(3)
    still = 0.02 + 1e-5 * rng.standard_normal(200)
    table = Table('r.csv', ['x'], {'x': still})
    with pytest.raises(DataError, match=r"r.csv: column 'x': never moves .*: it must vary"):
        data.check_moves(table, 'x', 'it must vary')
    data.check_moves(Table('r.csv', ['x'], {'x': still + np.linspace(0, 1e-3, 200)}), 'x', '')
    # Block means hide the noise: the raw rows' statistics decide (read_record's `stats`).
    means = Table('r.csv', ['x'], {'x': np.linspace(0.0, 1e-4, 20)})
    data.check_moves(means, 'x', '')                                   # alone, it moves
    raw = data.ColumnStats()
    for chunk in np.array_split(np.linspace(0.0, 1e-4, 200) + 1e-4 * rng.standard_normal(200), 3):
        raw.add(chunk)
    with pytest.raises(DataError, match='never moves'):
        data.check_moves(means, 'x', '', stats={'x': raw})


@pytest.mark.parametrize('text, lines', [('', 0), ('h\n', 0), ('h', 0), ('h\n1\n', 1),
                                         ('h\n1', 1), ('h\n1\n\n2\n', 3)])
def test_count_lines_counts_the_lines_after_the_header(tmp_path, text, lines):
    assert data.count_lines(write(tmp_path / 'c.csv', text)) == lines


def test_an_error_shows_a_cell_escaped_and_cut_short():
    assert data.shown('a\x1bb') == "'a\\x1bb'"
    assert data.shown('x' * 100) == repr('x' * data.SHOWN_CHARS) + '...'
