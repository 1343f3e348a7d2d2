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
papers/segment_experiments.py: paper A's bench experiments on the simulated segment.

The Fig. 10 scenario (docs/segment.md, "Calibration against paper A's Fig. 10": 74.5°, 4 bar
abs on chain 1, an excursion to -30° and back, |τ_ext| 6.7 then 9.1 N·m), the programmes of the
quasi-static and dynamic runs (moves, holds, pressure levels within paper A's ranges), and the
records' columns and units (rad, Pa abs, N·m, s). Noise-free where a value is checked.
"""
import math

import numpy as np
import pytest

from bellows_ros.config.segment import load_segment
from bellows_ros.models.segment_plant import FULL_MODEL, NO_NOISE, SegmentPlant
from bellows_ros.papers import segment_experiments as experiments

CONFIG = load_segment()
PARAMS, PLANT = CONFIG.model, CONFIG.plant
COLUMNS = ['t', 'psi', 'psi_dot', 'p1', 'p2', 'tau_ext', 'tau_motion']


def test_smooth_moves_go_between_levels_on_a_cosine():
    t = np.arange(0.0, 5.0, 0.25)
    out = experiments._smooth_moves([(1.0, 2.0), (3.0, 4.0)], [0.0, 1.0, -1.0], t)
    assert np.all(out[t < 1.0] == 0.0)                       # before the first move
    assert out[t == 1.5][0] == pytest.approx(0.5)            # half-way at mid-move
    assert out[t == 1.25][0] == pytest.approx(0.5 - 0.5 * math.cos(math.pi / 4))
    assert np.all(out[(t >= 2.0) & (t < 3.0)] == 1.0)        # held between the moves
    assert np.all(out[t >= 4.0] == -1.0)                     # and after the last
    assert np.all(np.diff(out[(t >= 3.0) & (t <= 4.0)]) < 0)  # one way within a move


def test_fig10_record_is_paper_a_scenario_and_gives_its_torques():
    record, before, after = experiments.fig10_record(PARAMS, PLANT, noise=NO_NOISE)
    assert list(record) == COLUMNS
    assert len(record['t']) == 18000 and record['t'][1] - record['t'][0] == pytest.approx(1e-3)
    # "before" at t = 6 s, "after" at the end, t = 18 s; both at rest at 74.5°, 4 bar abs.
    assert record['t'][before] == pytest.approx(6.0) and after == len(record['t']) - 1
    assert record['t'][after] == pytest.approx(18.0)
    for index in (before, after):
        assert math.degrees(record['psi'][index]) == pytest.approx(74.5)
        assert record['p1'][index] == pytest.approx(experiments.FIG10_P1)   # Pa abs
        assert record['p2'][index] == pytest.approx(PARAMS.p0)              # vented
        assert record['psi_dot'][index] == 0.0 and record['tau_motion'][index] == 0.0
    assert math.degrees(record['psi'].min()) == pytest.approx(-30.0)        # the excursion
    # Paper A measured 6.7 N·m before and 9.1 N·m after (docs/equations.md, Fig. 10).
    assert -record['tau_ext'][before] == pytest.approx(6.7, abs=0.01)
    assert -record['tau_ext'][after] == pytest.approx(9.1, abs=0.01)


def test_the_fig10_hysteresis_comes_from_the_excursion_and_the_physics():
    shallow, before, after = experiments.fig10_record(PARAMS, PLANT, noise=NO_NOISE,
                                                      excursion=0.0)
    assert shallow['psi'].min() == pytest.approx(0.0, abs=1e-12)
    # Not through the straight position: less of the stored strain is released (docs/segment.md).
    assert -shallow['tau_ext'][before] == pytest.approx(6.7, abs=0.01)
    assert 6.7 < -shallow['tau_ext'][after] < 9.0
    # Without paper A's physics the torque does not depend on the path.
    plain, before, after = experiments.fig10_record(PARAMS, PLANT, effects=(), noise=NO_NOISE)
    assert plain['tau_ext'][before] == pytest.approx(plain['tau_ext'][after], rel=1e-9)


def test_run_plant_records_what_the_plant_measured_along_the_imposed_path():
    plant = SegmentPlant(PARAMS, PLANT, (), NO_NOISE)
    path = np.linspace(0.0, 0.5, 50)
    record = experiments.run_plant(plant, 1e-2, np.full(50, 3e5), np.full(50, PARAMS.p0), path)
    assert list(record) == COLUMNS and all(len(v) == 50 for v in record.values())
    np.testing.assert_allclose(record['t'], np.arange(1, 51) * 1e-2)
    np.testing.assert_allclose(record['psi'], path)  # imposed, measured without noise


@pytest.mark.parametrize('make, move_range, hold_range', [
    (experiments.quasi_static_record, (2.0, 5.0), (0.5, 2.0)),
    (experiments.dynamic_record, (0.3, 1.5), (0.0, 0.5)),
])
def test_each_run_moves_as_paper_a_runs_within_their_ranges(make, move_range, hold_range):
    # The programme the record is driven by: the same seed draws the same programme.
    rng = np.random.default_rng(5)
    times, angles, _, p1, p2 = experiments._programme(rng, 30.0, move_range, hold_range, PARAMS)
    lengths = np.array([end - start for start, end in times])
    holds = np.array([b[0] - a[1] for a, b in zip(times[:-1], times[1:])])
    assert np.all((lengths >= move_range[0]) & (lengths <= move_range[1]))
    assert np.all((holds >= hold_range[0]) & (holds <= hold_range[1]))
    assert max(map(abs, angles)) <= 1.4                         # rad
    assert min(p1 + p2) >= PARAMS.p0 and max(p1 + p2) <= 7.0e5  # Pa abs, 7 bar at most
    record = make(PARAMS, PLANT, FULL_MODEL, NO_NOISE, seed=5, duration=30.0, dt=1e-2)
    again = make(PARAMS, PLANT, FULL_MODEL, NO_NOISE, seed=5, duration=30.0, dt=1e-2)
    other = make(PARAMS, PLANT, FULL_MODEL, NO_NOISE, seed=6, duration=30.0, dt=1e-2)
    assert list(record) == COLUMNS and len(record['t']) == 3000
    # The angle imposed is that programme's (noise-free: measured as imposed).
    np.testing.assert_allclose(record['psi'], experiments._smooth_moves(
        times, angles, np.arange(1, 3001) * 1e-2), atol=1e-12)
    assert all(np.array_equal(record[k], again[k]) for k in COLUMNS)  # deterministic
    assert not np.array_equal(record['psi'], other['psi'])
    assert np.abs(record['psi']).max() <= 1.4
    for chain in ('p1', 'p2'):
        assert PARAMS.p0 - 1.0 <= record[chain].min() and record[chain].max() <= 7.0e5 + 1.0


def test_a_pressure_schedule_of_its_own_holds_many_levels_over_the_whole_range():
    rng = np.random.default_rng(2)
    times, p1, p2 = experiments._pressure_schedule(rng, 120.0, (0.5, 2.0), PARAMS)
    ramps = np.array([end - start for start, end in times])
    assert np.all((ramps >= 0.05) & (ramps <= 1.0))   # steps and ramps, s
    levels = np.array(p1 + p2)
    assert levels.min() >= PARAMS.p0 and levels.max() <= PARAMS.p_max
    assert levels.max() > 7.0e5       # up to p_max, above the default programme's 7 bar
    # Both vented at times, and many levels in between.
    assert any(a == b == PARAMS.p0 for a, b in zip(p1, p2)) and len(set(p1)) > 30
    held = experiments.quasi_static_record(PARAMS, PLANT, (), NO_NOISE, seed=2, duration=30.0,
                                           dt=1e-2, pressure_hold=(0.5, 2.0))
    plain = experiments.quasi_static_record(PARAMS, PLANT, (), NO_NOISE, seed=2, duration=30.0,
                                            dt=1e-2)

    def levels_held(p):  # distinct values the pressure rests at for 0.2 s or more
        steady = np.all(np.abs(np.diff(np.lib.stride_tricks.sliding_window_view(p, 20))) < 1.0,
                        axis=1)
        return len(np.unique(np.round(p[:len(steady)][steady], -2)))
    assert levels_held(held['p1']) > 2 * levels_held(plain['p1'])
