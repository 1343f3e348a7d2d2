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

"""Angle tracker and built-in trajectories: the parts the bench and the node share."""
import dataclasses
import math

import pytest

from bellows_ros.config.segment import load_segment_params
from bellows_ros.control import angle_trajectory
from bellows_ros.control.angle_tracking import AngleTracker, TrackingGains
from bellows_ros.errors import ParameterError

P = load_segment_params()
GAINS = TrackingGains(40.0, 640.0, 2.0, 20.0, 20.0, P.p0, 0.05)


@pytest.mark.parametrize('name', sorted(angle_trajectory.TRAJECTORIES))
def test_trajectory_is_smooth_and_consistent(name):
    trajectory = angle_trajectory.by_name(name)
    total = angle_trajectory.duration(trajectory)
    h = 1e-4
    edges, start = [], 0.0  # Ψ̈ jumps where a move starts or ends
    for _, move, hold in trajectory.waypoints:
        edges += [start, start + move]
        start += move + hold
    previous = angle_trajectory.setpoint(trajectory, 0.0)
    for k in range(1, int(total / 0.01)):
        t = k * 0.01
        psi, psi_dot, psi_ddot = angle_trajectory.setpoint(trajectory, t)
        assert abs(psi - previous[0]) < 0.05  # continuous (peak speed < 5 rad/s)
        ahead, behind = (angle_trajectory.setpoint(trajectory, t + s * h) for s in (1, -1))
        assert psi_dot == pytest.approx((ahead[0] - behind[0]) / (2 * h), abs=1e-3)
        if min(abs(t - edge) for edge in edges) > 2 * h:
            assert psi_ddot == pytest.approx((ahead[1] - behind[1]) / (2 * h), abs=2e-2)
        previous = (psi, psi_dot)
    assert angle_trajectory.setpoint(trajectory, total + 1.0) == \
        (trajectory.waypoints[-1][0], 0.0, 0.0)
    assert angle_trajectory.phases(trajectory, total - 0.01) == ('hold', None)


def test_reversals_trajectory_has_reversals_holds_and_speeds():
    trajectory = angle_trajectory.REVERSALS
    t = [k * 0.01 for k in range(int(angle_trajectory.duration(trajectory) / 0.01))]
    kinds = [angle_trajectory.phases(trajectory, s) for s in t]
    assert kinds.count(('move', True)) > 300 and kinds.count(('hold', None)) > 1000
    speeds = [abs(angle_trajectory.setpoint(trajectory, s)[1]) for s in t]
    assert max(speeds) > 2.0 and max(abs(angle_trajectory.setpoint(trajectory, s)[0])
                                     for s in t) <= 0.9


def test_unknown_trajectory_names_the_known_ones():
    with pytest.raises(ParameterError, match='reversals, sweep'):
        angle_trajectory.by_name('zigzag')


def test_command_leaves_the_contact_memory_alone():
    tracker = AngleTracker(P, GAINS, 'paper_a')
    for k in range(500):
        tracker.observe(0.5 * k / 499, 0.5, P.p0 + 1.5e5 * k / 499, P.p0, 1e-3)
    memory = tracker.model.memory1
    before = (memory.n, memory.total, list(memory.profile))
    out = tracker.command(0.6, 0.3, 0.0, 0.5, 5e-3, ahead=(0.615, 0.3, 0.0))
    assert (memory.n, memory.total, list(memory.profile)) == before
    assert P.p0 <= out.p2 <= out.p1 <= P.p_max  # a positive error asks chain 1 for more


def test_feedback_only_uses_no_model_terms():
    """`none`: the PID torque through the constant g0 alone — no rigid-body terms, no lead."""
    with_dynamics = P.replace(dynamics_inertia=0.5, dynamics_damping=3.0)
    plain = AngleTracker(P, GAINS, 'none')
    dynamic = AngleTracker(with_dynamics, GAINS, 'none')
    for tracker in (plain, dynamic):
        tracker.observe(0.1, 0.0, P.p0, P.p0, 1e-3)
    a = plain.command(0.2, 1.0, 5.0, 0.1, 5e-3, ahead=(0.25, 1.0, 5.0))
    b = dynamic.command(0.2, 1.0, 5.0, 0.1, 5e-3)
    assert a == b
    feedback = GAINS.kp * 0.1 + GAINS.ki * 0.1 * 5e-3 + GAINS.kd * (1.0 - plain.velocity)
    assert a.tau == pytest.approx(feedback)
    assert a.p1 - P.p0 == pytest.approx(feedback / plain.g0)
    assert not math.isnan(a.p1)


def test_bad_feedforward_and_gains_are_refused():
    with pytest.raises(ParameterError, match='feedforward'):
        AngleTracker(P, GAINS, 'paper_b')
    with pytest.raises(ParameterError, match='base_pressure'):
        AngleTracker(P, TrackingGains(40.0, 640.0, 2.0, 20.0, 20.0, 8e5), 'paper_a')


def test_retune_takes_new_gains_and_keeps_the_state():
    """A live gain change: the next command uses the new gains; integral and memory are kept."""
    tracker = AngleTracker(P, GAINS, 'none')
    tracker.observe(0.1, 0.0, P.p0, P.p0, 1e-3)
    tracker.command(0.2, 0.0, 0.0, 0.1, 5e-3)
    integral, velocity = tracker.integral, tracker.velocity
    stiffer = dataclasses.replace(GAINS, kp=2 * GAINS.kp, base_pressure=P.p0 + 1e5)
    tracker.retune(stiffer, 'paper_a')
    assert (tracker.integral, tracker.velocity) == (integral, velocity)
    assert tracker.gains == stiffer and tracker.feedforward == 'paper_a'
    fresh = AngleTracker(P, stiffer, 'paper_a')
    assert tracker.g0 == pytest.approx(fresh.g0)  # the slope at the new base pressure
    with pytest.raises(ParameterError, match='base_pressure'):
        tracker.retune(dataclasses.replace(GAINS, base_pressure=8e5), 'none')
    assert tracker.gains == stiffer  # a refused change leaves the tracker as it was
