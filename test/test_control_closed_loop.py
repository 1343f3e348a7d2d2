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
The arm controller closed around the simulated segment, in process (control/closed_loop.py).

Per 1 ms sample the plant is measured, the tracker's model steps, every `control_every`-th sample
the tracker commands pressures, and the valves take the newest command every `setpoint_every`
samples (the arm bus's set-point cycle), holding it in between. Deterministic for a seed. The
controller's gains and cycles are those of config/nodes_sim.yaml and config/arm.dbc.
"""
import math

import numpy as np
import pytest

from bellows_ros.config.segment import load_segment
from bellows_ros.control import angle_trajectory, closed_loop
from bellows_ros.io import params as param_files
from bellows_ros.models.segment import SegmentModel
from bellows_ros.models.segment_plant import FULL_MODEL

MOVE = angle_trajectory.Trajectory(0.0, ((0.3, 0.5, 0.5),))  # 0.3 rad in 0.5 s, hold 0.5 s


@pytest.fixture(scope='module')
def segment():
    return load_segment()


def run(segment, control_every=5, setpoint_every=1, seed=0, **options):
    model, plant, _ = segment
    gains, _ = closed_loop.controller_settings(model)
    return closed_loop.simulate(model, plant, gains, 'paper_a', MOVE, FULL_MODEL, seed=seed,
                                control_every=control_every, setpoint_every=setpoint_every,
                                **options)


def changes(values):
    """Sample indices k where values[k] differs from values[k - 1]."""
    return set(np.flatnonzero(np.diff(values) != 0) + 1)


def test_a_run_has_one_row_per_millisecond_of_the_trajectory(segment):
    tracked = run(segment)
    assert len(tracked.t) == 1000 and all(len(column) == 1000 for column in tracked)
    assert tracked.t[1] - tracked.t[0] == closed_loop.DT and tracked.t[-1] == pytest.approx(0.999)
    assert [tracked.psi_d[k] for k in (0, 250, 999)] == \
        [angle_trajectory.setpoint(MOVE, tracked.t[k])[0] for k in (0, 250, 999)]
    assert tracked.saturated.dtype == bool
    assert len(run(segment, duration=0.2).t) == 200  # `duration` cuts the trajectory short


def test_the_same_seed_gives_the_same_run_and_another_seed_another(segment):
    first, again, other = run(segment, seed=4), run(segment, seed=4), run(segment, seed=5)
    for name in closed_loop.TrackingRun._fields:
        assert np.array_equal(getattr(first, name), getattr(again, name)), name
    assert not np.array_equal(first.psi, other.psi)  # the plant's noise is drawn from the seed


def test_the_valves_hold_each_command_for_the_buses_cycle(segment):
    # control every sample, valves every 4th: the valves change only on the set-point cycle
    tracked = run(segment, control_every=1, setpoint_every=4)
    held = changes(tracked.p1_cmd) | changes(tracked.p2_cmd)
    assert held and all(k % 4 == 3 for k in held), sorted(held)[:10]


def test_the_tracker_commands_every_control_every_samples(segment):
    tracked = run(segment, control_every=5, setpoint_every=1)
    commanded = changes(tracked.p1_cmd) | changes(tracked.p2_cmd)
    assert len(commanded) > 50 and all(k % 5 == 0 for k in commanded), sorted(commanded)[:10]


def test_the_tracker_follows_the_move():
    tracked = closed_loop.track('paper_a', MOVE)
    error = tracked.psi_d - tracked.psi
    assert closed_loop.rms(error) < 0.03                 # rad, over the move and the hold
    assert abs(tracked.psi[-1] - 0.3) < 0.01


def test_the_controller_is_the_simulated_nodes(segment):
    model, plant, _ = segment
    gains, control_every = closed_loop.controller_settings(model)
    flat = param_files.read_file(param_files.default_file('nodes_sim'), 'arm_controller_node')
    assert (gains.kp, gains.ki, gains.kd) == (flat['pid.kp'], flat['pid.ki'], flat['pid.kd'])
    assert gains.base_pressure == model.p0 + flat['co_contraction']
    assert gains.lead == flat['feedforward_lead'] and control_every == flat['control_every']
    # the arm bus's 10 ms set-point cycle over 1 ms samples (config/arm.dbc, docs/arm_control.md)
    assert closed_loop.setpoint_every() == 10


def test_track_gives_the_tracker_the_simulated_segments_rigid_body_on_request(segment):
    model, plant, _ = segment
    seen = []

    def factory(params):
        seen.append(params)
        return SegmentModel(params)
    for rigid_body in (True, False):
        closed_loop.track('paper_a', MOVE, rigid_body=rigid_body, duration=0.01,
                          model_factory=factory)
    with_body, without = seen
    assert (with_body.dynamics_inertia, with_body.dynamics_damping,
            with_body.dynamics_gravity) == (plant.inertia, plant.damping, plant.gravity)
    assert without == model and closed_loop.with_rigid_body(model, plant) == with_body


def test_rms():
    assert closed_loop.rms([3.0, -4.0]) == pytest.approx(math.sqrt(12.5))
    assert math.isnan(closed_loop.rms(np.zeros(0)))  # an empty selection has no RMS, not 0
