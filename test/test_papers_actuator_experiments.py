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
papers/actuator_experiments.py: paper B's programmes and records on the simulated actuator.

The chamber's programme (steps, ramps at 0.2/0.4/0.8 of the lead screw's top speed, holds; or
only compressing), the spring's (triangle cycles, fast 50 ms compressions), the record's columns
and the ranges it keeps to (m, Pa, N, s), its refusals, and the volume test's sealed runs
(paper B, Fig. 4, 8). The seeded record's shape and encoder quantisation are
test_models_actuator_plant.py's.
"""
import numpy as np
import pytest

from bellows_ros.config.actuator import load_actuator
from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator_plant import ActuatorPlant
from bellows_ros.papers import actuator_experiments as experiments

CONFIG = load_actuator()
PARAMS, PLANT = CONFIG.model, CONFIG.plant
MAX_SPEED = ActuatorPlant(PARAMS, PLANT).max_speed   # m/s, the lead screw's
DT = 1e-3


def test_the_chamber_programme_steps_ramps_and_holds_within_its_span():
    ref = experiments.chamber_programme(np.random.default_rng(1), 60000, DT, 0.02, -0.02, 0.04,
                                        MAX_SPEED)
    assert len(ref) == 60000 and ref[0] == 0.02
    assert -0.02 <= ref.min() and ref.max() <= 0.04             # m
    speed = np.abs(np.diff(ref)) / DT
    steps = speed > MAX_SPEED                                   # a target at once
    ramps = (speed > 0) & ~steps
    assert steps.any() and ramps.any() and (speed == 0).any()   # steps, ramps, holds
    # Each ramp at one of 0.2, 0.4, 0.8 of the top speed (a whole number of samples: a little
    # faster).
    nearest = np.array([0.2, 0.4, 0.8])[np.argmin(np.abs(
        speed[ramps, None] / MAX_SPEED - [0.2, 0.4, 0.8]), axis=1)]
    np.testing.assert_allclose(speed[ramps] / MAX_SPEED, nearest, rtol=0.05)
    again = experiments.chamber_programme(np.random.default_rng(1), 60000, DT, 0.02, -0.02, 0.04,
                                          MAX_SPEED)
    np.testing.assert_array_equal(ref, again)                   # seeded


def test_a_monotone_programme_only_compresses_and_ends_held_at_the_top():
    ref = experiments.chamber_programme(np.random.default_rng(1), 60000, DT, 0.0, -0.02, 0.04,
                                        MAX_SPEED, monotone=True)
    assert ref[0] == 0.0 and np.diff(ref).min() >= 0.0
    assert ref[-1] == 0.04 and np.abs(np.diff(ref)).max() / DT <= 0.85 * MAX_SPEED  # no step


def test_the_spring_programme_compresses_within_its_amplitudes_and_fast_at_times():
    x_s = experiments.spring_programme(np.random.default_rng(1), 60000, DT)
    assert len(x_s) == 60000 and x_s[0] == 0.0
    assert x_s.min() == 0.0 and x_s.max() <= 0.020                      # m, never stretched
    # Triangle cycles are at most 2 x 20 mm per 1 s period; a fast compression rises in 50 ms.
    assert np.abs(np.diff(x_s)).max() / DT > 0.008 / 0.05 - 1e-9
    low = experiments.spring_programme(np.random.default_rng(1), 20000, DT, (0.002, 0.004))
    assert low.max() <= 0.004 and low.max() > 0.0


@pytest.mark.parametrize('duration, dt', [(0.0, 1e-3), (1.0, 0.0), (-1.0, 1e-3),
                                          (float('nan'), 1e-3), (1.0, float('nan'))])
def test_a_duration_or_step_that_is_not_positive_is_refused(duration, dt):
    with pytest.raises(ParameterError, match='duration and dt must be > 0'):
        experiments.actuator_record(PARAMS, PLANT, duration=duration, dt=dt)


def test_the_record_keeps_to_its_chamber_and_spring_ranges():
    record = experiments.actuator_record(PARAMS, PLANT, noise=False, seed=4, duration=20.0,
                                         x_c_range=(0.0, 0.01), x_c0=0.005,
                                         spring_range=(0.002, 0.004))
    assert list(record) == ['t', 'x_c', 'x_s', 'p', 'f']
    np.testing.assert_allclose(record['t'], np.arange(20000) * DT, atol=1e-9)  # s, from 0
    # The chamber, held by the PD loop on the encoder, stays about its targets' span.
    assert -0.0005 <= record['x_c'].min() and record['x_c'].max() <= 0.0105
    assert 0.0 <= record['x_s'].min() and record['x_s'].max() <= 0.004
    assert np.all(record['p'] > 0.0) and np.all(np.isfinite(record['f']))
    # Monotone: the chamber never goes back (a compression sweep).
    sweep = experiments.actuator_record(PARAMS, PLANT, noise=False, seed=4, duration=5.0,
                                        x_c0=0.0, monotone=True)
    assert np.diff(sweep['x_c']).min() >= 0.0 and sweep['x_c'][-1] > 0.005


def test_the_volume_test_is_its_sealed_runs_one_after_another():
    gases = (0.92, 1.0, 1.08)
    series = experiments.volume_test_series(PARAMS, PLANT, gases=gases, noise=False, seed=3,
                                            duration=0.4)
    assert list(series) == ['t', 'x_c', 'x_s', 'p', 'f', 'run']
    assert len(series['t']) == 1200
    np.testing.assert_allclose(series['t'], np.arange(1200) * DT, atol=1e-9)  # one clock
    np.testing.assert_array_equal(series['run'], np.repeat([0.0, 1.0, 2.0], 400))
    # Each run: `actuator_record` with its own gas (a fraction of p_ref), seed and start, the
    # starts spread over -20..40 mm in a seeded order.
    starts = np.linspace(-0.020, 0.040, len(gases))
    order = np.random.default_rng(3).permutation(len(gases))
    for index, fraction in enumerate(gases):
        run = experiments.actuator_record(PARAMS, PLANT, ('wall_bulging', 'buckling'), False,
                                          3 + 7 * index, 0.4, gas=fraction * PARAMS.p_ref,
                                          x_c0=starts[order[index]])
        part = series['run'] == index
        for name in ('x_c', 'x_s', 'p', 'f'):
            np.testing.assert_array_equal(series[name][part], run[name])
    first = [series['x_c'][series['run'] == k][0] for k in range(len(gases))]
    assert sorted(first) == pytest.approx(list(starts), abs=1e-6)
