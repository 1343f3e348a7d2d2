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
The stiffness a record measured: paper B's figure from the load cell, one value per spring cycle.

Paper B measures the stiffness on a test machine that compresses the spring with the air chamber
held: the average slope of the force over spring 0-12 mm (section IV-D; `actuator.x_s_low`,
`x_s_high`). `measured_stiffness` does the same on a record `t, x_c, x_s, p, f` (CSV or rosbag2,
e.g. the simulated rig with `sim_actuator_node spring.amplitude` > 0): it cuts the record into
windows of `window` s (one spring period), keeps the windows where the chamber held still and the
spring covered the range, fits F(x_s) by a cubic (the load cell's noise averages out) and returns
(F(x_s_high) - F(x_s_low)) / (x_s_high - x_s_low). No model is involved: this is what the
controller's model is judged against (docs/workflow.md).
"""
import math
from typing import NamedTuple

import numpy as np

from bellows_ros.errors import DataError

# The chamber counts as held when its compression varies by less than this within a window, m.
HELD = 2e-4


class StiffnessWindow(NamedTuple):
    """One spring cycle: mid time s, mean chamber compression m, stiffness N/m."""

    t: float
    x_c: float
    k: float


# Samples a window needs for the cubic fit of F(x_s) to average the load cell's noise.
MIN_WINDOW_SAMPLES = 20


def measured_stiffness(table, x_s_low, x_s_high, window):
    """
    Return a `StiffnessWindow` per window of `window` s where the stiffness is measurable.

    A window shorter than MIN_WINDOW_SAMPLES median steps is refused (it measures nothing, and
    a window of nanoseconds would cut the record into billions); each window's rows are found by
    bisection, so the cost grows with the rows, not with rows times windows.
    """
    t, x_c, x_s, f = (np.asarray(table[n], dtype=float) for n in ('t', 'x_c', 'x_s', 'f'))
    if not (math.isfinite(window) and window > 0):
        raise DataError(table.path, f'window must be a finite time > 0 s, got {window}')
    step = float(np.median(np.diff(t))) if len(t) > 1 else math.inf
    if not window >= MIN_WINDOW_SAMPLES * step:
        raise DataError(table.path, f'a window of {window:g} s holds fewer than '
                        f'{MIN_WINDOW_SAMPLES} samples (a sample every {step:g} s): give '
                        'one period of the spring motion', column='t')
    result = []
    # A window is whole when its samples reach to one step before its end: a record of N spring
    # periods sampled to N P - dt has N windows. Each window's rows are those within half a step
    # of [start, start + window), so a start computed as 0.07500000000000001 still takes the
    # sample at 0.075.
    count = int(math.floor((t[-1] + step - t[0]) / window + 1e-9)) if len(t) > 1 else 0
    starts = t[0] + window * np.arange(count)
    firsts = np.searchsorted(t, starts - 0.5 * step, side='left')
    ends = np.searchsorted(t, starts + window - 0.5 * step, side='left')
    for start, first, end in zip(starts, firsts, ends):
        rows = slice(first, end)
        if end - first < MIN_WINDOW_SAMPLES or np.ptp(x_c[rows]) > HELD:
            continue
        xs = x_s[rows]
        if xs.min() > x_s_low + 1e-4 or xs.max() < x_s_high - 1e-4:
            continue
        fit = np.polynomial.Polynomial.fit(xs, f[rows], 3)
        k = (fit(x_s_high) - fit(x_s_low)) / (x_s_high - x_s_low)
        result.append(StiffnessWindow(float(start + 0.5 * window), float(x_c[rows].mean()),
                                      float(k)))
    return result
