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
Built-in angle trajectories (control/angle_trajectory.py): half-cosine moves joined by holds.

Each move goes from the previous target to its own in move_time s with zero velocity at both
ends and peak speed |ΔΨ| π / (2 T); then the angle holds for hold_time s. Before 0 and after the
end the first / last angle holds. `phases` tells moves from holds and whether a move reverses.
(Smoothness and the derivatives' consistency of the built-ins: test_control_angle_tracking.py.)
"""
import math

import pytest

from bellows_ros.control.angle_trajectory import (duration, phases, REVERSALS, setpoint, SWEEP,
                                                  Trajectory)

# From 0.2 rad: up to 0.8 in 2 s, hold 1 s, on up to 1.0 in 0.5 s (no hold), back down to 0.0
# in 1 s, hold 0.5 s.
STEPS = Trajectory(0.2, ((0.8, 2.0, 1.0), (1.0, 0.5, 0.0), (0.0, 1.0, 0.5)))


def test_a_move_is_a_half_cosine_from_rest_to_rest():
    delta, move = 0.6, 2.0
    rate = math.pi / move
    assert setpoint(STEPS, 0.0) == pytest.approx((0.2, 0.0, 0.5 * delta * rate ** 2))
    psi, psi_dot, psi_ddot = setpoint(STEPS, 1.0)  # half-way: half the way, the peak speed
    assert psi == pytest.approx(0.5) and psi_ddot == pytest.approx(0.0, abs=1e-12)
    assert psi_dot == pytest.approx(delta * math.pi / (2 * move))
    psi, psi_dot, psi_ddot = setpoint(STEPS, 2.0 - 1e-9)  # arriving: at rest, decelerating
    assert psi == pytest.approx(0.8) and psi_dot == pytest.approx(0.0, abs=1e-8)
    assert psi_ddot == pytest.approx(-0.5 * delta * rate ** 2)
    # a quarter of the way in time is (1 - cos(pi / 4)) / 2 of the way in angle
    assert setpoint(STEPS, 0.5)[0] == pytest.approx(0.2 + delta * (1 - math.cos(math.pi / 4)) / 2)


def test_holds_before_between_and_after_the_moves():
    assert setpoint(STEPS, -5.0) == (0.2, 0.0, 0.0)   # before 0: the start
    assert setpoint(STEPS, 2.5) == (0.8, 0.0, 0.0)    # the hold after the first move
    assert setpoint(STEPS, 3.0)[0] == pytest.approx(0.8)  # the next move starts from there
    assert setpoint(STEPS, duration(STEPS) + 10.0) == (0.0, 0.0, 0.0)
    assert setpoint(STEPS, 3.5)[0] == pytest.approx(1.0)  # a move with no hold: straight on
    assert setpoint(STEPS, 3.5)[1] == pytest.approx(0.0, abs=1e-12)


def test_the_duration_is_every_move_and_hold():
    assert duration(STEPS) == pytest.approx(2.0 + 1.0 + 0.5 + 0.0 + 1.0 + 0.5)
    # docs/arm_control.md: 'reversals: 33 s, 11 moves' (the module's comment says 40 s)
    assert duration(REVERSALS) == pytest.approx(33.0) and len(REVERSALS.waypoints) == 11
    assert duration(Trajectory(0.3, ())) == 0.0
    assert setpoint(Trajectory(0.3, ()), 1.0) == (0.3, 0.0, 0.0)


def test_phases_tell_moves_holds_and_reversals():
    assert phases(STEPS, -1.0) == ('hold', None)
    assert phases(STEPS, 0.5) == ('move', False)   # the first move reverses nothing
    assert phases(STEPS, 2.5) == ('hold', None)
    assert phases(STEPS, 3.2) == ('move', False)   # on up after a hold: the same direction
    assert phases(STEPS, 4.0) == ('move', True)    # back down: a reversal
    assert phases(STEPS, 4.8) == ('hold', None)
    assert phases(STEPS, 100.0) == ('hold', None)


@pytest.mark.parametrize('trajectory', [REVERSALS, SWEEP], ids=['reversals', 'sweep'])
def test_each_built_in_moves_peak_at_its_stated_speed(trajectory):
    # peak |Ψ̇| = |ΔΨ| π / (2 T) at each move's midpoint, within the 0.4-2.6 rad/s REVERSALS
    # promises (SWEEP's are slower: moves of 3-5 s)
    here, start = trajectory.start, 0.0
    for target, move, hold in trajectory.waypoints:
        peak = abs(target - here) * math.pi / (2 * move)
        assert abs(setpoint(trajectory, start + 0.5 * move)[1]) == pytest.approx(peak)
        assert peak <= 2.6 and (trajectory is SWEEP or peak >= 0.4), (target, move)
        here, start = target, start + move + hold
