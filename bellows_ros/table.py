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

The readers: CSV (`bellows_ros.data`) and rosbag2 (`bellows_ros.bag`); also the columns of
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
                     None if self.lines is None else [self.lines[i] for i in where])


def check_increasing(table, name='t'):
    """Time (or any column) must strictly increase."""
    column = table[name]
    bad = np.flatnonzero(np.diff(column) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise DataError(table.path, f'not increasing ({column[i]:g} after {column[i - 1]:g})',
                        table.line(i), name)
