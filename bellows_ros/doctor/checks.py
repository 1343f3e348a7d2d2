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
Checking the data the doctor is given (a table in memory: it reads no file).

Two kinds of verdict: a `DataError` when the data cannot be diagnosed at all (too short, unevenly
sampled, the input never moves), and per cause a reason why this record cannot separate that cause
("not identifiable from this data"), so that the doctor skips it instead of guessing. Messages name
the data by the table's `path` (the file it was read from, or the name an in-memory caller gave).
"""
from dataclasses import dataclass

import numpy as np

from bellows_ros.doctor.scoring import block_masks
from bellows_ros.errors import DataError
from bellows_ros.io.data import check_range
from bellows_ros.io.table import check_increasing, COLUMNS, Table
from bellows_ros.models.actuator_geometry import P_ATM
from bellows_ros.models.segment_effects import EFFECTS as SEGMENT_EFFECTS

MIN_SAMPLES = 200
MIN_DURATION = 5.0        # s
MAX_JITTER = 0.05         # relative std of the sampling interval above which data is resampled
MAX_GAP = 10.0            # a gap this many sampling intervals long is an error


@dataclass
class Record:
    """Evenly sampled columns of one record. `factor` > 1 for a block-averaged copy."""

    system: str
    path: str
    dt: float
    columns: dict
    factor: int = 1
    resampled: bool = False

    def __getitem__(self, name):
        return self.columns[name]

    def __contains__(self, name):
        return name in self.columns

    def __len__(self):
        return len(self.columns['t'])

    @property
    def duration(self):
        return float(self.columns['t'][-1] - self.columns['t'][0])

    def decimated(self, factor):
        """
        Return the block means of `factor` consecutive samples.

        An anti-alias filter and a decimator in one: it also divides white noise variance by
        `factor`.
        """
        if factor <= 1:
            return self
        n = len(self) // factor * factor
        columns = {name: column[:n].reshape(-1, factor).mean(axis=1)
                   for name, column in self.columns.items()}
        return Record(self.system, self.path, self.dt * factor, columns, self.factor * factor,
                      self.resampled)


def as_table(data, system, source='<arrays>'):
    """
    Return `data` as a `Table`: a `Table` as the readers give it, or a mapping column -> array.

    A mapping must hold the system's required columns (`table.COLUMNS`) as 1-D arrays of one
    length; `source` names it in error messages. Time must increase, as the file readers require.
    """
    if isinstance(data, Table):
        return data
    required, optional = COLUMNS[system]
    for name in required:
        if name not in data:
            raise DataError(source, 'missing', column=name)
    values = {name: np.asarray(data[name], float) for name in required + optional
              if name in data}
    lengths = {len(column) if column.ndim == 1 else -1 for column in values.values()}
    if len(lengths) != 1 or -1 in lengths:
        raise DataError(source, 'the columns must be 1-D arrays of one length')
    for name, column in values.items():
        if not np.all(np.isfinite(column)):
            raise DataError(source, f'{column[~np.isfinite(column)][0]} is not a finite number',
                            column=name)
    table = Table(str(source), list(values), values)
    check_increasing(table, 't')
    return table


def checked_record(table, system, factor=1):
    """
    Check a `system` table (`as_table`) and return it as an evenly sampled `Record`.

    `factor` > 1: the table's rows are block means of that many raw rows (`data.read_record`).
    """
    path = table.path
    if len(table) < MIN_SAMPLES:
        raise DataError(path, f'only {len(table)} samples; the doctor needs at least '
                              f'{MIN_SAMPLES} to fit on some blocks of time and score on others')
    columns = {name: np.asarray(table[name], float) for name in table.values}
    t = columns['t']
    duration = t[-1] - t[0]
    if duration < MIN_DURATION:
        raise DataError(path, f'record lasts {duration:.3g} s; the doctor needs at least '
                              f'{MIN_DURATION:g} s (held-out blocks of time must each contain '
                              'motion)')
    steps = np.diff(t)
    dt = float(np.median(steps))
    worst = int(np.argmax(steps))
    if steps[worst] > MAX_GAP * dt:
        raise gap_error(table, worst + 1, t[worst], t[worst + 1], dt)
    check_ranges(table, system)
    resampled = bool(np.std(steps) > MAX_JITTER * dt)
    if resampled:
        # Stamped samples from a bag arrive with jitter; the filters of the causes need a fixed
        # step.
        grid = t[0] + dt * np.arange(int(duration / dt) + 1)
        columns = {name: np.interp(grid, t, column) for name, column in columns.items()}
        columns['t'] = grid
    record = Record(system, str(path), dt, columns, factor, resampled=resampled)
    _check_excitation(record)
    return record


def check_ranges(table, system):
    """Every pressure, compression and angle within what a device of `system` can show."""
    if system == 'actuator':
        check_range(table, 'p', 1e3, 2e6, 'Pa')
        for name in ('x_c', 'x_s'):
            check_range(table, name, -0.2, 0.2, 'm')
    else:
        for name in ('p1', 'p2'):
            check_range(table, name, 1e3, 2e6, 'Pa')
        check_range(table, 'psi', -np.pi, np.pi, 'rad')


def gap_error(table, row, last, first, dt):
    """Return the DataError of a gap in `table` before data row `row`: t = `last`, then `first`."""
    return DataError(table.path, f'gap of {first - last:.3g} s in the time column after t = '
                                 f'{last:.6g} s (sampling interval {dt:.3g} s); split the record '
                                 f'at the gap (`bellows export ... --end {last:.6g}`, '
                                 f'`--start {first:.6g}`) and give each part on its own',
                     table.line(row), 't')


class RawChecks:
    """
    The checks of `checked_record` that block means would hide, on each raw chunk of a record.

    For a record read as block means (`data.read_record`): call it on every raw chunk, in order.
    Ranges (`check_ranges`) and gaps: a step over MAX_GAP of the chunk's median step (the step
    from the previous chunk's last row included).
    """

    def __init__(self, system):
        self.system, self.last = system, None

    def __call__(self, table):
        t = np.asarray(table['t'], float)
        before = 0 if self.last is None else 1
        steps = np.diff(t if self.last is None else np.r_[self.last, t])
        if len(steps) > 1:
            dt = float(np.median(steps))
            worst = int(np.argmax(steps))
            if steps[worst] > MAX_GAP * dt:
                after = t[worst - before] if worst - before >= 0 else self.last
                raise gap_error(table, worst + 1 - before, after, t[worst + 1 - before], dt)
        self.last = float(t[-1])
        check_ranges(table, self.system)


def _check_excitation(record):
    if record.system == 'actuator':
        if np.ptp(record['x_c']) < 1e-4:
            raise DataError(record.path, "column 'x_c': not identifiable from this data: the "
                                         'air-chamber compression never changes by 0.1 mm, so the '
                                         'model has no input')
    else:
        if np.ptp(record['psi']) < np.radians(1.0):
            raise DataError(record.path, "column 'psi': not identifiable from this data: the "
                                         'segment angle never changes by 1 degree')


def pressure_coverage(record, ambient, share=0.5):
    """
    Tell why not every fold's training rows reach `share` of the highest chain pressure.

    None if they all do (gauge pressures).

    The segment models' pressure coefficients are shared by both chains (Σ_j σ_j p_j [...], (34),
    (29)), so what a fold refit can learn is set by the highest gauge pressure either chain holds
    in its training rows. A record pressurised only in the blocks one fold holds out (a rig that
    pressurises in the last 2 s) leaves that fold's pressure coefficients to the noise: its
    held-out score measures an extrapolation, and comparing causes on it names whichever
    extrapolates least.
    """
    gauge = np.maximum(record['p1'], record['p2']) - ambient
    top = float(gauge.max())
    for fold, (train, _) in enumerate(block_masks(len(record))):
        reached = float(gauge[train].max())
        if reached < share * top:
            held = np.flatnonzero(~train & (gauge > share * top))
            t = record['t']
            return (f'the chains reach {top / 1e5:.2f} bar gauge but, without the blocks fold '
                    f'{fold} holds out, only {reached / 1e5:.2f} bar (the higher pressures lie in '
                    f't = {t[held[0]]:.1f}-{t[held[-1]]:.1f} s); the held-out score would measure '
                    'an extrapolation in pressure')
    return None


def identifiability(record, ambient=P_ATM):
    """
    For each segment cause: None if this record can separate it, else the reason why not.

    `record` is the (decimated) record, `ambient` the ambient pressure (Pa) gauge pressures are
    taken from: the segment's p0 (paper A). Each effect states its own condition
    (`structural_reason`). The actuator's causes are judged by what the model says the record
    can show (`actuator_causes.identifiability`): none here.
    """
    if record.system == 'actuator':
        return {}
    reasons = {effect.name: effect.structural_reason(record, ambient)
               for effect in SEGMENT_EFFECTS}
    # Every segment cause acts through the chain pressures: none can be scored on held-out
    # blocks that only one fold's refit has not seen pressurised.
    uncovered = pressure_coverage(record, ambient)
    if uncovered:
        reasons = {cause: reason or uncovered for cause, reason in reasons.items()}
    return reasons
