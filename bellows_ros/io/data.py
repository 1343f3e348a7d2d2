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
Measured and simulated data files (docs/interfaces.md "Data files").

CSV with a header row, SI units, one row per sample. Every problem is reported as a `DataError`
naming the file, the line (header = line 1) and the column. Extra columns are carried along
untouched so that `bellows simulate` can write "the input plus outputs".

A directory is read as a rosbag2 recording (see `bellows_ros.io.bag`). Both readers return a
`bellows_ros.io.table.Table`; this module imports the bag reader, never the other way round.
"""
import csv
from dataclasses import dataclass, field
import io
import math
from pathlib import Path
import re
import sys

import numpy as np
from tqdm import tqdm

from bellows_ros.errors import DataError
from bellows_ros.io.outputs import atomic_file
from bellows_ros.io.table import check_held, check_increasing, COLUMNS, Table

BOM = b'\xef\xbb\xbf'  # the UTF-8 byte-order mark spreadsheets write
# A number as a CSV reader should take it: ASCII decimal, optional sign, fraction and exponent,
# blanks around it (spreadsheets pad). Python's float() also takes `1_000`, `infinity`, `nan` and
# other scripts' digits ('١'), which no instrument writes: a cell like that is a mistake to name.
NUMBER = re.compile(r'[ \t]*[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?[ \t]*')
# The bytes a file of such numbers can hold: anything else sends a file to the careful reader.
_NUMERIC_BYTES = re.compile(rb'[^0-9eE+\-., \t\r\n]')
# Rows per chunk of a streamed record (`read_chunks`): about 30 MB while a chunk is run and
# written (its numbers, then their text), whatever the record's length.
CHUNK_ROWS = 20_000
# Most rows `read_record` hands a fit: a longer record is read in chunks and block-averaged down to
# at most this many rows (identify, diagnose). Up to this many lines after the header the record
# is the file's rows themselves, as `read_table` reads them.
FIT_ROWS = 100_000
# A time step this many times a chunk's median step starts a new block of `read_record` (records
# joined end to end, a gap): no block averages across it.
BLOCK_GAP_STEPS = 10.0

# Pressure columns of each system: absolute, in Pa.
PRESSURES = {'segment': ('p1', 'p2'), 'actuator': ('p',)}
# No bellows works near vacuum, and ambient air is at least ~50 kPa (5000 m above sea level): a
# pressure column that never reaches 20 kPa abs was written in hPa, kPa or bar (ambient is
# 1013 hPa = 101.3 kPa = 1.013 bar; 7.5 bar is 7500 hPa), and read as Pa it would be fitted
# without complaint.
MIN_PLAUSIBLE_PRESSURE = 2e4
# A value below 30 kPa abs in a column that does reach pressure is a gauge (relative) reading:
# its ambient reads 0. Pneumatic bellows are driven above ambient and vent to it.
MIN_ABSOLUTE_PRESSURE = 3e4
# The segment's bending angle cannot pass a half turn; larger values are degrees.
MAX_ANGLE = math.pi
# s; the longest typical sample step a record of these devices can have. The models describe
# valves and gas that settle in tens of ms, and devices sample at 100 Hz to 1 kHz; a record at
# 2 Hz shows none of it. A time column written in ms turns a 1 kHz step into 1.0 and a 100 Hz
# one into 10: the median step is the test (a pause in a record moves the median not at all).
MAX_SAMPLE_PERIOD = 0.5
# A measured rate column (psi_dot) against the rate of its own angle over t: 1 when both are in
# SI units, 1000 with t in ms, 57 with psi_dot in deg/s. Noise only pulls the least-squares ratio
# towards 0, so above 10 a unit is wrong. Compared over RATE_WINDOWS windows of the record; it
# catches t in ms at any rate (a 5 kHz record in ms steps by 0.2, under MAX_SAMPLE_PERIOD).
MAX_RATE_RATIO = 10.0
RATE_WINDOWS = 100


# Limits of what a file may make a reader do (every one names itself when it is reached):
# - a line (the header or a row) of the careful reader: a record's row is under 1 kB; 1 MiB is
#   already a binary file or a missing line end;
MAX_LINE_BYTES = 1 << 20
# - a file read whole (`read_table`: export, stiffness): 1 GiB of text is ~10 million rows,
#   hours at 1 kHz, and several GiB of memory; a longer record is cut first (`export
#   --start/--end`) or given to a command that streams it (simulate, identify, diagnose);
MAX_TABLE_BYTES = 1 << 30
# - a streamed record (`read_chunks`, `read_record`): 200 million rows, over two days at 1 kHz.
MAX_RECORD_ROWS = 200_000_000
# What an error shows of a cell or a name: enough to find it, never a screenful of a binary file.
SHOWN_CHARS = 40


def shown(text):
    """`text` as an error shows it: its repr (control bytes escaped), cut to SHOWN_CHARS."""
    text = str(text)
    cut = text[:SHOWN_CHARS]
    return repr(cut) + ('...' if len(text) > SHOWN_CHARS else '')


def check_input_file(path):
    """Refuse, before reading, an input that is no regular file (a FIFO, /dev/zero, a socket)."""
    import stat
    path = Path(path)
    try:
        mode = path.stat().st_mode
    except OSError as exc:
        raise DataError(path, f'cannot read file ({exc.strerror})') from None
    except ValueError:  # a NUL byte in the name
        raise DataError(repr(str(path)), 'not a valid file name') from None
    if stat.S_ISDIR(mode):
        raise DataError(path, 'is a directory without metadata.yaml: not a CSV file nor a '
                              'rosbag2 recording')
    if not stat.S_ISREG(mode):
        raise DataError(path, 'is not a regular file (a device, FIFO or socket): an input is '
                              'read from a file, whose end is known')
    return path


def _check_text(path, raw):
    """Refuse bytes that are no CSV text (a NUL, or not UTF-8) before they reach a message."""
    nul = raw.find(b'\0')
    if nul >= 0:
        raise DataError(path, f'not a CSV text file (binary data: a NUL byte at offset {nul})')
    try:
        raw.decode()
    except UnicodeDecodeError as exc:
        if exc.start < len(raw) - 4:  # a block may end inside a character: only that is allowed
            raise DataError(path, f'not a CSV text file (bytes that are not UTF-8 at offset '
                                  f'{exc.start})') from None


def read_csv(path, required, optional=()):
    """
    Read a CSV file, checking that `required` columns exist and hold finite numbers.

    Returns a `Table`. Raises `DataError` on a missing file, a missing column, a short row, a
    non-number, NaN or infinity, binary data, and a file over MAX_TABLE_BYTES.
    """
    path = check_input_file(path)
    size = path.stat().st_size
    if size > MAX_TABLE_BYTES:
        raise DataError(path, f'{size / 2 ** 30:.1f} GiB: over the {MAX_TABLE_BYTES >> 30} GiB '
                              'this command reads whole (data.MAX_TABLE_BYTES); cut the record '
                              '(`bellows export --start/--end`) or split it')
    try:
        with open(path, 'rb') as stream:
            raw = stream.read(MAX_TABLE_BYTES + 1)
    except OSError as exc:
        raise DataError(path, f'cannot read file ({exc.strerror})') from None
    if len(raw) > MAX_TABLE_BYTES:
        raise DataError(path, f'over the {MAX_TABLE_BYTES >> 30} GiB this command reads whole '
                              '(data.MAX_TABLE_BYTES)')
    raw = raw.removeprefix(BOM)
    _check_text(path, raw)
    return _parse(path, raw, required, optional)


def _parse(path, raw, required, optional, skipped=0):
    """Parse CSV bytes (header line, then rows) into a Table; `skipped` lines came before."""
    fast = _read_numeric(path, raw, required, optional, skipped)
    if fast is not None:
        return fast
    reader = csv.reader(io.StringIO(raw.decode(errors='replace'), newline=''))
    # The csv module's own field limit (128 KiB) would name no line; a line over MAX_LINE_BYTES
    # is found first, with its line.
    long_line = _long_line(raw)
    if long_line is not None:
        raise DataError(path, f'a line longer than {MAX_LINE_BYTES >> 20} MiB '
                              '(data.MAX_LINE_BYTES): not a record of samples',
                        line=long_line + skipped)
    try:
        header, rows, lines = _split_rows(path, reader, required, skipped)
    except csv.Error as exc:  # e.g. a field longer than the csv module's limit
        raise DataError(path, str(exc), line=reader.line_num + skipped) from None
    values, extras = {}, {}
    for index, name in enumerate(header):
        cells = [row[index] for row in rows]
        if name in required or name in optional:
            values[name] = _parse_column(path, name, cells, lines)
        else:
            extras[name] = cells
    return Table(str(path), header, values, extras, lines)


def _long_line(raw):
    """1-based line of the first line of `raw` longer than MAX_LINE_BYTES, or None."""
    if len(raw) <= MAX_LINE_BYTES:
        return None
    start, line = 0, 1
    while start < len(raw):
        end = raw.find(b'\n', start)
        end = len(raw) if end < 0 else end
        if end - start > MAX_LINE_BYTES:
            return line
        start, line = end + 1, line + 1
    return None


def _split_rows(path, reader, required, skipped=0):
    """Header (checked against `required`) and the non-blank rows of a CSV with their lines."""
    header = next(reader, None)
    if not header:
        raise DataError(path, 'empty file: expected a header row', line=1)
    header = [name.strip() for name in header]
    duplicate = next((name for i, name in enumerate(header) if name in header[:i]), None)
    if duplicate is not None:
        # Which of the two is meant cannot be known; taking either would be a silent guess.
        raise DataError(path, f'column {shown(duplicate)} appears twice in the header', line=1)
    for name in required:
        if name not in header:
            names = ', '.join(header)
            names = names if len(names) <= 3 * SHOWN_CHARS else shown(names)
            raise DataError(path, f"missing column '{name}' (header has: {names})", line=1)
    rows, lines = [], []
    for row in reader:
        if not row or all(not cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            raise DataError(path, f'expected {len(header)} fields, found {len(row)}',
                            line=reader.line_num + skipped)
        rows.append(row)
        lines.append(reader.line_num + skipped)
    if not rows:  # line 2: where the first data row belongs (as read_chunks says it)
        raise DataError(path, 'no data rows after the header', line=2)
    return header, rows, lines


def _read_numeric(path, raw, required, optional, skipped=0):
    """
    Fast path for the common file: every column wanted, all finite numbers, no blank lines.

    NumPy's C parser reads a 600 000-row record several times faster than the csv module. Anything
    unusual returns None, and the careful reader in `read_csv` finds and names the problem.
    """
    first, _, body = raw.partition(b'\n')
    header = [name.strip() for name in first.decode(errors='replace').split(',')]
    if any(name not in required and name not in optional for name in header) \
            or any(name not in header for name in required) or len(set(header)) < len(header):
        return None
    rows = body.rstrip(b'\r\n').count(b'\n') + 1 if body.strip() else 0
    if rows == 0:
        return None  # loadtxt would warn about the empty body before the careful reader's error
    if _NUMERIC_BYTES.search(body):
        return None  # a byte no plain number has: the careful reader names the cell
    try:
        # comments=None: a '#' in a cell is an error for both readers, never a silent cut.
        array = np.loadtxt(io.BytesIO(body), delimiter=',', dtype=float, ndmin=2, comments=None)
    except ValueError:
        return None
    if array.shape != (rows, len(header)) or not np.isfinite(array).all():
        return None
    values = {name: np.ascontiguousarray(array[:, i]) for i, name in enumerate(header)}
    return Table(str(path), header, values, {}, range(skipped + 2, skipped + rows + 2))


def _parse_column(path, name, cells, lines):
    match = NUMBER.fullmatch
    for cell, line in zip(cells, lines):
        if not match(cell):
            text = cell.strip()
            problem = (f'{text} is not a finite number' if text.lower().lstrip('+-') in
                       ('nan', 'inf', 'infinity') else f'not a number: {shown(text)}')
            raise DataError(path, problem, line, name)
    column = np.array(cells, dtype=float)
    bad = ~np.isfinite(column)
    if bad.any():
        first = int(np.argmax(bad))
        raise DataError(path, f'{column[first]} is not a finite number', lines[first], name)
    return column


def check_range(table, name, low, high, unit=''):
    """Every value of column `name` must lie in [low, high]."""
    column = table[name]
    bad = np.flatnonzero((column < low) | (column > high))
    if bad.size:
        i = int(bad[0])
        raise DataError(table.path,
                        f'{column[i]:g} {unit} is outside [{low:g}, {high:g}] {unit}'
                        .replace('  ', ' '),
                        table.line(i), name)


def check_moves(table, name, why, stats=None):
    """
    Column `name` must move beyond its own noise, or the record cannot show `why`.

    The noise is read from the data: sample-to-sample differences of white noise of deviation s
    have deviation s·√2, and a still signal's range is then within a few s. A range under ten
    times that is taken as a column that never moves. `stats` (`Record.stats`, raw rows of a
    block-averaged record) replaces the table's own column: averaging would hide the noise.
    """
    if stats is not None and name in stats:
        if stats[name].diffs < 2:
            return
        noise, spread = stats[name].noise, stats[name].spread
    else:
        column = table[name]
        if len(column) < 3:
            return
        noise = float(np.std(np.diff(column))) / math.sqrt(2.0)
        spread = float(np.ptp(column))
    if spread <= 10.0 * noise:
        raise DataError(table.path, f'never moves (range {spread:.3g}, within 10x its own noise '
                        f'{noise:.2g}): {why}', column=name)


def read_chunks(path, system, required=None, rows=None):
    """
    Yield a `system` file as Tables of at most `rows` rows (CHUNK_ROWS), for a record of any size.

    Each chunk is checked as `read_table` checks a whole file (columns, numbers, units), and time
    increases across chunks too; line numbers in errors are the file's. A rosbag2 directory
    comes in one Table. `progress` bars the bytes read on stderr when it is a terminal.
    """
    if Path(path).is_dir():
        yield read_table(path, system, required)
        return
    rows = rows or CHUNK_ROWS
    required, optional = _columns(system, required)
    path = check_input_file(path)
    try:
        stream = path.open('rb')
    except OSError as exc:
        raise DataError(path, f'cannot read file ({exc.strerror})') from None
    with stream, tqdm(total=path.stat().st_size, unit='B', unit_scale=True, disable=None,
                      file=sys.stderr, leave=False, desc=path.name) as bar:
        header = _bounded_lines(path, stream, 1, 0)
        header = header[0].removeprefix(BOM) if header else b''
        skipped, last, any_rows = 0, None, False
        while True:
            block = _bounded_lines(path, stream, rows, skipped + 1)
            if not block:
                break
            if skipped + len(block) > MAX_RECORD_ROWS:
                raise DataError(path, f'over {MAX_RECORD_ROWS:,} rows (data.MAX_RECORD_ROWS): '
                                      'split the record', line=MAX_RECORD_ROWS + 2)
            _check_text(path, header + b''.join(block))
            bar.update(sum(map(len, block)) + (len(header) if skipped == 0 else 0))
            if not any(line.strip() for line in block):  # blank lines only: nothing to parse
                skipped += len(block)
                continue
            table = _parse(path, header + b''.join(block), required, optional, skipped)
            skipped += len(block)
            _check_chunk(table, system, required, last)
            last = float(table['t'][-1])
            any_rows = True
            yield table
    if not any_rows:
        raise DataError(path, 'no data rows after the header' if header.strip() else
                        'empty file: expected a header row', line=2 if header.strip() else 1)


def _bounded_lines(path, stream, count, before):
    """Up to `count` lines of `stream`, each at most MAX_LINE_BYTES; `before`: lines read."""
    lines = []
    for _ in range(count):
        try:
            line = stream.readline(MAX_LINE_BYTES + 1)
        except OSError as exc:  # EIO of a failing disk or a dropped mount, half-way through
            raise DataError(path, f'cannot read file ({exc.strerror})',
                            line=before + len(lines) + 1) from None
        if not line:
            break
        if len(line) > MAX_LINE_BYTES:
            raise DataError(path, f'a line longer than {MAX_LINE_BYTES >> 20} MiB '
                                  '(data.MAX_LINE_BYTES): not a record of samples',
                            line=before + len(lines) + 1)
        lines.append(line)
    return lines


@dataclass
class ColumnStats:
    """Range and sample-to-sample differences of one column over every raw row, chunk by chunk."""

    low: float = math.inf
    high: float = -math.inf
    diffs: int = 0
    total: float = 0.0     # sum of the differences
    squares: float = 0.0   # sum of their squares
    last: float = None

    def add(self, column):
        """Take the next rows of the column (the difference across the chunk boundary too)."""
        steps = np.diff(column if self.last is None else np.r_[self.last, column])
        self.low, self.high = min(self.low, float(column.min())), max(self.high,
                                                                      float(column.max()))
        self.diffs += len(steps)
        self.total += float(steps.sum())
        self.squares += float(np.dot(steps, steps))
        self.last = float(column[-1])

    @property
    def spread(self):
        return self.high - self.low

    @property
    def noise(self):
        """np.std(np.diff(column)) / √2 of the whole column, as `check_moves` takes it."""
        mean = self.total / self.diffs
        return math.sqrt(max(self.squares / self.diffs - mean * mean, 0.0) / 2.0)


@dataclass
class Record:
    """
    What `read_record` gives: the table to fit, and what the raw rows said.

    `table`: the file's rows (`factor` 1) or block means of `factor` consecutive rows (fewer at a
    gap, a change of `run`, and the record's end), each block's line the line of its first row;
    `rows`: data rows of the file; `stats`: `ColumnStats` of every numeric column over the raw
    rows; `chunks`: what `per_chunk` returned for each raw chunk.
    """

    table: Table
    rows: int
    factor: int
    stats: dict = field(default_factory=dict)
    chunks: list = field(default_factory=list)


def count_lines(path):
    """Lines after the header of a file (blank ones too), read in blocks: bounded memory."""
    lines, tail = 0, b'\n'
    with open(path, 'rb') as stream:
        for block in iter(lambda: stream.read(1 << 24), b''):
            lines += block.count(b'\n')
            tail = block[-1:]
    return max(0, lines + (tail != b'\n') - 1)


def read_record(path, system, required=None, per_chunk=None, max_rows=None):
    """
    Read a `system` file of any length for a fit, in bounded memory: returns a `Record`.

    A file of at most `max_rows` (FIT_ROWS) lines after the header gives its rows, the numbers
    `read_table` gives. A longer one is read in chunks (`read_chunks`: every check of each chunk,
    time increasing across them, errors naming the file's line, a progress bar) and each block of
    `factor` = ceil(lines / max_rows) consecutive rows is replaced by its mean: an anti-alias
    filter and decimator in one (plain subsampling would alias the noise), which also divides
    white noise's variance by `factor`. A block never spans a time step over BLOCK_GAP_STEPS
    median steps nor a change of `run` (separately sealed fills). Whatever the noise, read it off
    the raw rows (`Record.stats`, `per_chunk`: called on each raw chunk), never the block means.
    A rosbag2 directory is read whole (`read_table`).
    """
    max_rows = max_rows or FIT_ROWS
    if Path(path).is_dir():
        table = read_table(path, system, required)
        return _whole(table, per_chunk)
    check_input_file(path)
    try:
        lines = count_lines(path)
    except OSError as exc:
        raise DataError(path, f'cannot read file ({exc.strerror})') from None
    if lines > MAX_RECORD_ROWS:  # said before any work, not after hours of reading
        raise DataError(path, f'{lines:,} lines: over {MAX_RECORD_ROWS:,} rows '
                              '(data.MAX_RECORD_ROWS); split the record')
    factor = max(1, math.ceil(lines / max_rows))
    stats, chunks, rows = {}, [], 0
    parts, pending = [], None
    for table in read_chunks(path, system, required):
        rows += len(table)
        for name, column in table.values.items():
            stats.setdefault(name, ColumnStats()).add(column)
        if per_chunk is not None:
            chunks.append(per_chunk(table))
        if factor == 1:
            parts.append((table.values, list(table.lines)))
            continue
        values, lines_of = dict(table.values), np.asarray(table.lines)
        if pending is not None:
            values = {name: np.r_[pending[0][name], values[name]] for name in values}
            lines_of = np.r_[pending[1], lines_of]
        starts = _block_starts(values, factor)
        done = starts[-1] if len(values['t']) - starts[-1] < factor else len(values['t'])
        pending = ({name: column[done:] for name, column in values.items()}, lines_of[done:])
        starts = starts[starts < done]
        if len(starts):
            parts.append(_block_means(values, lines_of, starts, done))
    if pending is not None and len(pending[1]):
        parts.append(_block_means(pending[0], pending[1], np.array([0]), len(pending[1])))
    names = list(parts[0][0])
    values = {name: np.concatenate([part[0][name] for part in parts]) for name in names}
    row_lines = [line for part in parts for line in part[1]]
    return Record(Table(str(path), names, values, {}, row_lines), rows, factor, stats, chunks)


def _whole(table, per_chunk):
    stats = {}
    for name, column in table.values.items():
        stats.setdefault(name, ColumnStats()).add(column)
    return Record(table, len(table), 1, stats, [per_chunk(table)] if per_chunk else [])


def _block_starts(values, factor):
    """First row of each block of `factor` rows, a new block at a gap or a change of `run`."""
    t = values['t']
    steps = np.diff(t)
    breaks = np.flatnonzero(steps > BLOCK_GAP_STEPS * np.median(steps)) + 1 if len(t) > 2 \
        else np.array([], int)
    if 'run' in values:
        breaks = np.union1d(breaks, np.flatnonzero(np.diff(values['run']) != 0) + 1)
    edges = np.r_[0, breaks, len(t)].astype(int)
    return np.concatenate([np.arange(a, b, factor) for a, b in zip(edges[:-1], edges[1:])
                           if b > a])


def _block_means(values, lines, starts, end):
    """Means of the rows from each of `starts` to the next (the last to `end`), and first lines."""
    counts = np.diff(np.r_[starts, end])
    means = {name: np.add.reduceat(column[:end], starts) / counts
             for name, column in values.items()}
    return means, [int(line) for line in lines[starts]]


def _check_chunk(table, system, required, last):
    check_increasing(table, 't')
    if last is not None and not table['t'][0] > last:
        raise DataError(table.path, f"not increasing ({table['t'][0]:g} after {last:g})",
                        table.line(0), 't')
    check_units(table, system, required)


def _columns(system, required):
    mandatory, optional = COLUMNS[system]
    required = mandatory if required is None else tuple(required)
    return required, tuple(name for name in mandatory + optional if name not in required)


def read_table(path, system, required=None, span=None):
    """
    Read a `system` ('segment' or 'actuator') file: CSV, or a rosbag2 directory.

    `required` narrows the required columns of a CSV (e.g. a simulation input has no measured
    torque); the system's other columns are then optional. A bag always yields the full set, and
    is refused where a channel has a gap its last value would fill (`table.check_held`).
    `span` = (start, end), s: keep only the rows with start <= t <= end, before those checks
    (`bellows export --start/--end`); DataError if none is left.
    """
    if Path(path).is_dir():
        from bellows_ros.io.bag import read_bag_table
        table = _span(read_bag_table(path, system), span)
        check_held(table)
        check_units(table, system)
        return table
    required, optional = _columns(system, required)
    table = read_csv(path, required, optional)
    check_increasing(table, 't')
    table = _span(table, span)
    check_units(table, system, required)
    return table


def _span(table, span):
    if span is None:
        return table
    start, end = span
    t = table['t']
    kept = table.rows((t >= start) & (t <= end))
    if not len(kept):
        raise DataError(table.path, f'no rows with {start:g} s <= t <= {end:g} s (t runs '
                                    f'from {t[0]:g} to {t[-1]:g} s)', column='t')
    return kept


def check_units(table, system, names=None):
    """
    Refuse columns whose values can only mean another unit: kPa or bar, degrees, ms.

    Only the columns in `names` (default: all of the system's) are checked; a simulation input may
    carry old output columns that are replaced anyway.
    """
    names = COLUMNS[system][0] if names is None else names
    for name in PRESSURES[system]:
        if name in names and name in table:
            highest = float(np.max(table[name]))
            if highest < MIN_PLAUSIBLE_PRESSURE:
                raise DataError(
                    table.path, f'every value is below {MIN_PLAUSIBLE_PRESSURE:g} Pa (largest '
                    f'{highest:g}): pressures are absolute, in Pa - was the file written in '
                    'hPa, kPa or bar?', column=name)
            low = np.flatnonzero(table[name] < MIN_ABSOLUTE_PRESSURE)
            if low.size:
                first = int(low[0])
                raise DataError(
                    table.path, f'{table[name][first]:g} Pa is below {MIN_ABSOLUTE_PRESSURE:g} '
                    'Pa: pressures are absolute (ambient is about 101325 Pa) - was the file '
                    'written as gauge pressure?', table.line(first), name)
    if 't' in table and len(table) > 2:
        step = float(np.median(np.diff(table['t'])))
        if step > MAX_SAMPLE_PERIOD:
            raise DataError(
                table.path, f'the median time step is {step:g} s (a sample every {step:g} s): '
                f'the devices sample at 2 Hz or faster, times are in s - was the file written '
                'in ms?', column='t')
    _check_rate_units(table)
    if system == 'segment' and 'psi' in table:
        beyond = np.flatnonzero(np.abs(table['psi']) > MAX_ANGLE)
        if beyond.size:
            first = int(beyond[0])
            raise DataError(
                table.path, f"{table['psi'][first]:g} is beyond a half turn: angles are in rad - "
                'was the file written in degrees?', table.line(first), 'psi')


def _check_rate_units(table):
    """Refuse a measured psi_dot that disagrees with the angle's change over t (ms or deg/s)."""
    if 't' in table and len(table) > 2 and 'psi' in table and 'psi_dot' in table:
        steps = np.diff(table['t'])
        # The angle change over each of ~100 windows against the integral of psi_dot over t: over
        # a window the angle's noise is small beside its motion (single differences would
        # drown in it), and over a hundredth of the record a rate offset stays small too.
        integral = np.concatenate([[0.0], np.cumsum(
            0.5 * (table['psi_dot'][1:] + table['psi_dot'][:-1]) * steps)])
        every = max(1, len(table) // RATE_WINDOWS)
        moved, integrated = np.diff(table['psi'][::every]), np.diff(integral[::every])
        power = float(np.dot(moved, moved))
        ratio = float(np.dot(moved, integrated)) / power if power > 0.0 else 0.0
        if ratio > MAX_RATE_RATIO:
            raise DataError(table.path, f'psi_dot is {ratio:.3g} times the rate of psi over t: '
                            'time is in s and rates in rad/s - was t written in ms, or psi_dot '
                            'in deg/s?', column='t')


def write_csv(path, table, outputs):
    """Write the input `table` (all its columns, in order), then `outputs` (name -> array)."""
    with CsvOutput(path) as output:
        output.write(table, outputs)


class CsvOutput:
    """
    Write "the input plus outputs" chunk by chunk: `with CsvOutput(path) as out: out.write(..)`.

    The rows go to a temporary file beside `path`, which replaces it only when the block ends
    without an error (outputs.atomic_file): a failure half-way leaves the old file, or none.
    """

    def __init__(self, path):
        self.path = path
        self.names = None

    def __enter__(self):
        self._file = atomic_file(self.path, 'w', newline='')
        try:
            self._writer = csv.writer(self._file.__enter__())
        except OSError as exc:
            raise DataError(self.path, f'cannot write file ({exc.strerror})') from None
        return self

    def write(self, table, outputs):
        """Write the rows of `table` (every column, in order), then `outputs` (name -> array)."""
        if self.names is None:
            self.names = list(table.names) + [n for n in outputs if n not in table.names]
            self._writer.writerow(self.names)
        columns = []
        for name in self.names:
            if name in outputs:
                columns.append(_texts(outputs[name]))
            elif name in table.values:
                columns.append(_texts(table.values[name]))
            else:
                columns.append(table.extras[name])
        try:
            self._writer.writerows(zip(*columns))
        except OSError as exc:
            raise DataError(self.path, f'cannot write file ({exc.strerror})') from None

    def __exit__(self, *error):
        try:
            return self._file.__exit__(*error)
        except OSError as exc:
            raise DataError(self.path, f'cannot write file ({exc.strerror})') from None


def _texts(column):
    """Return a column as CSV cells: the shortest text that reads back as the float; nan else."""
    values = np.asarray(column, dtype=float)
    if np.isfinite(values).all():
        return list(map(repr, values.tolist()))
    return [_format(value) for value in values.tolist()]


def _format(value):
    return repr(float(value)) if math.isfinite(value) else 'nan'
