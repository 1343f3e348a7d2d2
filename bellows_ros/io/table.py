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
The in-memory data table both file readers return, and the checks made on any table.

The readers: CSV (`bellows_ros.io.data`) and rosbag2 (`bellows_ros.io.bag`); also the columns of
each system's files.

It imports neither reader, so the readers depend on it and not on each other
(docs/interfaces.md "Data files").
"""
from dataclasses import dataclass, field

import numpy as np

from bellows_ros.errors import DataError

# Required and optional columns of each system's files.
COLUMNS = {
    'segment': (('t', 'psi', 'p1', 'p2', 'tau_ext'), ('psi_dot', 'tau_motion')),
    # `run` numbers separate sealed runs of one record (used by `bellows identify actuator`).
    'actuator': (('t', 'x_c', 'x_s', 'p', 'f'), ('run',)),
}


@dataclass
class Table:
    """
    Columns of one data file.

    `values` holds float arrays for the columns the caller asked for (required, and optional ones
    present); `extras` holds every other column as text, in file order, so it can be written back
    unchanged. `lines` gives the file line of each row, for error messages (None for non-CSV
    sources).
    """

    path: str
    names: list
    values: dict
    extras: dict = field(default_factory=dict)
    lines: list = None
    # Columns aligned from another channel (a rosbag2 topic): column -> (topic, age, step): the
    # age (s) of the channel's message each row takes, and the step (s) within which a message
    # counts as this row's own. A row older than MAX_HELD_STEPS steps holds a value over a gap
    # in the channel, and `check_held` refuses it.
    held: dict = None

    def line(self, row):
        """File line of data row `row` (0-based); None where rows have no lines (rosbag2)."""
        return None if self.lines is None else self.lines[row]

    def __len__(self):
        return len(next(iter(self.values.values())))

    def __getitem__(self, name):
        return self.values[name]

    def __contains__(self, name):
        return name in self.values

    def rows(self, keep):
        """Return a `Table` of the rows where the boolean array `keep` is true, lines kept."""
        keep = np.asarray(keep, bool)
        where = np.flatnonzero(keep)
        return Table(self.path, self.names, {k: v[keep] for k, v in self.values.items()},
                     {k: [cells[i] for i in where] for k, cells in self.extras.items()},
                     None if self.lines is None else [self.lines[i] for i in where],
                     None if self.held is None else
                     {k: (topic, age[keep], step) for k, (topic, age, step) in self.held.items()})


def check_increasing(table, name='t'):
    """Time (or any column) must strictly increase."""
    column = table[name]
    bad = np.flatnonzero(np.diff(column) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise DataError(table.path, f'not increasing ({column[i]:g} after {column[i - 1]:g})',
                        table.line(i), name)


# A channel silent this many sample steps (or its own steps, if it is slower) is a gap in it, as a
# time gap of that length is one in the record (doctor.checks.MAX_GAP).
MAX_HELD_STEPS = 10.0


def _runs(mask):
    """(first, last) row of each run of True in `mask`."""
    edges = np.diff(np.r_[0, mask.astype(np.int8), 0])
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1))


def check_held(table):
    """
    Refuse a table in which a column would hold a channel's last value over a gap in it.

    Names the channel, the column and the times (t, s, of the messages around the gap), and the
    `bellows export --start/--end` that keeps a part where every row has its own message. A
    channel that starts late, stops early or falls silent in between is never filled in: no
    result is computed from a held value.
    """
    if not table.held or not len(table):
        return
    t = table['t']
    for name, (topic, age, step) in table.held.items():
        age = np.asarray(age, float)
        runs = _runs(age > MAX_HELD_STEPS * step)
        if not runs:
            continue
        own = np.flatnonzero(age < step)   # rows stamped with a message of their own
        first, last = runs[0]
        before = own[own < first]
        after = own[own > last]
        if not len(before) and not len(after):
            what, hint = 'has no message in these rows', 'a part where it has messages'
        elif not len(before):
            what = f'starts late: no message before t = {t[after[0]]:.6g} s'
            hint = f'`--start {t[after[0]]:.6g}`'
        elif not len(after):
            what = (f'stops early: no message after t = {t[before[-1]]:.6g} s (the record runs '
                    f'to {t[-1]:.6g} s)')
            hint = f'`--end {t[before[-1]]:.6g}`'
        else:
            what = (f'has no message from t = {t[before[-1]]:.6g} s to {t[after[0]]:.6g} s'
                    + (f' (and {len(runs) - 1} more gaps)' if len(runs) > 1 else ''))
            hint = f'`--end {t[before[-1]]:.6g}`, `--start {t[after[0]]:.6g}`'
        raise DataError(table.path, f'{topic} {what}: its last value would stand in for the '
                        f'measurement; take the part where it was recorded (`bellows export` '
                        f'with {hint})', column=name)
