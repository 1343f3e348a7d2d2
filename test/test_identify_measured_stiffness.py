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
The stiffness a record measured (identify/measured_stiffness.py): paper B's figure, per cycle.

One value per window of one spring period where the chamber held still and the spring covered
x_s_low..x_s_high: the secant slope (F(x_s_high) - F(x_s_low)) / (x_s_high - x_s_low) of a cubic
fit of the load cell's force (paper B, section IV-D). No model is involved; on a simulated rig it
is the plant's own static stiffness. A window too short to fit, or none measurable, is refused.
"""
import math

import numpy as np
import pytest

from bellows_ros.cli import main
from bellows_ros.config.actuator import load_actuator, load_actuator_params
from bellows_ros.errors import DataError
from bellows_ros.identify.measured_stiffness import HELD, measured_stiffness, MIN_WINDOW_SAMPLES
from bellows_ros.io.data import write_csv
from bellows_ros.io.table import Table
from bellows_ros.models.actuator import stiffness
from bellows_ros.models.actuator_plant import ActuatorPlant
from bellows_ros.models.stiffness_map import compression_for_stiffness

SPRING, PERIOD = 0.02, 4.0      # m, s: the test machine's spring motion
LOW, HIGH = 0.0, 0.012          # m: the spring range of the figure (paper B's 0-12 mm)


def held_chamber_record(x_c, duration=9.0, dt=1e-3):
    """Simulate a record (plant with sensor noise): chamber held at x_c, spring 0-20 mm."""
    config = load_actuator()
    plant = ActuatorPlant(config.model, config.plant, seed=3, x_c0=x_c)
    rows = {name: [] for name in ('t', 'x_c', 'x_s', 'p', 'f')}
    for i in range(int(round(duration / dt))):
        x_s = 0.5 * SPRING * (1.0 - math.cos(2.0 * math.pi * i * dt / PERIOD))
        sample = plant.step_nut(dt, x_c, x_s_imposed=x_s)
        for name in rows:
            rows[name].append(getattr(sample, name))
    return {name: np.array(values) for name, values in rows.items()}, plant.params


def read_table_from(record):
    """Return `record` (name -> array) as a Table, for write_csv."""
    names = list(record)
    return Table('record', names, record)


def rig(force, cycles=3, rate=500.0, x_c=None, period=PERIOD):
    """
    Return a Table of a rig: spring cycled 0-20 mm at `rate` Hz, f = force(x_s).

    `x_c(t)`: the chamber's compression (held at 10 mm unless given).
    """
    t = np.arange(int(round(cycles * period * rate)) + 1) / rate  # to the end of the last cycle
    x_s = 0.5 * SPRING * (1.0 - np.cos(2.0 * np.pi * t / period))
    chamber = np.full_like(t, 0.01) if x_c is None else x_c(t)
    return Table('rig.csv', ['t', 'x_c', 'x_s', 'p', 'f'],
                 {'t': t, 'x_c': chamber, 'x_s': x_s, 'p': np.full_like(t, 1.2e5),
                  'f': force(x_s)})


def test_stiffness_measured_from_the_load_cell_is_the_models(tmp_path, capsys):
    default = load_actuator_params()
    x_c = compression_for_stiffness(default, 1700.0)
    record, truth = held_chamber_record(x_c)
    table = tmp_path / 'held.csv'
    write_csv(table, read_table_from(record), {})
    assert main(['stiffness', str(table), '--setpoint', '1700']) == 0
    out = capsys.readouterr().out
    expected = stiffness(truth, x_c)  # the plant's own static physics, no effects
    measured = [float(line.split('stiffness')[1].split()[0]) for line in out.splitlines()
                if line.startswith('t ')]
    assert len(measured) == 2, out
    assert all(abs(k - expected) < 0.005 * expected for k in measured), (measured, expected)
    assert 'RMS' in out.splitlines()[-1]


def test_stiffness_refuses_a_record_without_a_held_cycle(tmp_path, capsys):
    record, _ = held_chamber_record(0.0, duration=3.0)  # shorter than one spring period
    table = tmp_path / 'short.csv'
    write_csv(table, read_table_from(record), {})
    assert main(['stiffness', str(table)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and 'short.csv' in err, err


def test_a_linear_spring_measures_its_rate_in_every_whole_window():
    windows = measured_stiffness(rig(lambda x: 2.0 + 1900.0 * x), LOW, HIGH, PERIOD)
    # three whole periods, three windows, each stamped at its middle, with the chamber's mean
    assert [w.t for w in windows] == pytest.approx([2.0, 6.0, 10.0])
    assert [w.k for w in windows] == pytest.approx([1900.0] * 3, rel=1e-9)
    assert [w.x_c for w in windows] == pytest.approx([0.01] * 3)


def test_a_record_that_ends_one_sample_before_its_last_period_ends_keeps_that_window():
    # Sampled at 0, dt, ..., 3 P - dt: the third period's samples are all there.
    whole = rig(lambda x: 1900.0 * x)
    cut = Table('rig.csv', whole.names, {name: whole[name][:-1] for name in whole.names})
    assert [w.t for w in measured_stiffness(cut, LOW, HIGH, PERIOD)] == \
        pytest.approx([2.0, 6.0, 10.0])
    # A window's start computed as k * window (0.07500000000000001 for 3 * 0.025) still takes
    # the sample at its start: x_s = 0 starts each of the fast rig's windows.
    fast = rig(lambda x: 1900.0 * x, cycles=4, rate=1000.0, period=0.025)
    assert len(measured_stiffness(fast, 0.0, HIGH, 0.025)) == 4


def test_the_stiffness_is_the_secant_over_the_range_not_a_local_slope():
    # A cubic force is fitted exactly: the result is (F(high) - F(low)) / (high - low), which for
    # this curve differs from the slope at either end or at the middle.
    def force(x):
        return 1500.0 * x + 4.0e6 * x ** 2 - 5.0e7 * x ** 3
    secant = (force(HIGH) - force(LOW)) / (HIGH - LOW)
    windows = measured_stiffness(rig(force, cycles=1), LOW, HIGH, PERIOD)
    assert len(windows) == 1 and windows[0].k == pytest.approx(secant, rel=1e-9)
    assert abs(secant - 1500.0) > 100.0  # not the slope at x_s = 0


def test_a_window_where_the_chamber_moved_or_the_spring_fell_short_is_skipped():
    def chamber(t):  # held in the first and third periods; moves 1 mm in the second
        return 0.01 + 1e-3 * ((t >= PERIOD) & (t < 2 * PERIOD)) * (t - PERIOD) / PERIOD
    windows = measured_stiffness(rig(lambda x: 1900.0 * x, x_c=chamber), LOW, HIGH, PERIOD)
    assert [round(w.t) for w in windows] == [2, 10]
    # a chamber that creeps by less than HELD in a window still counts as held
    creep = measured_stiffness(rig(lambda x: 1900.0 * x, x_c=lambda t: 0.01 + 0.5 * HELD * t
                                   / (3 * PERIOD)), LOW, HIGH, PERIOD)
    assert len(creep) == 3
    # the spring never reaches 25 mm: no window covers the range
    assert measured_stiffness(rig(lambda x: 1900.0 * x), LOW, 0.025, PERIOD) == []


@pytest.mark.parametrize('window, needle', [
    (0.0, 'window must be a finite time > 0 s, got 0.0'),
    (-4.0, 'window must be a finite time > 0 s'),
    (math.nan, 'window must be a finite time > 0 s, got nan'),
    (math.inf, 'window must be a finite time > 0 s, got inf'),
    ((MIN_WINDOW_SAMPLES - 1) / 500.0, "column 't': a window of 0.038 s holds fewer than 20 "
     'samples (a sample every 0.002 s)'),
])
def test_a_window_that_cannot_measure_is_refused(window, needle):
    with pytest.raises(DataError) as error:
        measured_stiffness(rig(lambda x: 1900.0 * x, cycles=1), LOW, HIGH, window)
    assert str(error.value).startswith('rig.csv: ') and needle in str(error.value)


def test_a_fast_rigs_short_window_is_measured():
    # A 25 ms spring period sampled at 1 kHz: 25 samples per window, over MIN_WINDOW_SAMPLES.
    # (From 2 mm: a window's first sample may be the one after the cycle's x_s = 0.)
    fast = rig(lambda x: 1900.0 * x, cycles=4, rate=1000.0, period=0.025)
    windows = measured_stiffness(fast, 0.002, HIGH, 0.025)
    assert len(windows) == 4 and [w.k for w in windows] == pytest.approx([1900.0] * 4)
