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
control/joint_trajectory.py: JTC's checks, interpolation and replacement rule, one joint.

The expected values are the textbook polynomials written out independently: the line, the
smoothstep 3s² − 2s³ (cubic, rest to rest) and the minimum-jerk 10s³ − 15s⁴ + 6s⁵ (quintic).
"""
from hypothesis import given, strategies as st
import pytest

from bellows_ros.control.joint_trajectory import (interpolate, Knot, parse, Path, Point, splice,
                                                  start_time, TrajectoryError)

JOINTS = ('segment_1', 'segment_2')


def test_linear_between_position_only_points():
    path = Path([Knot(1.0, 0.2), Knot(3.0, 1.2), Knot(4.0, 0.2)])
    assert path.sample(1.0) == pytest.approx((0.2, 0.5, 0.0))
    assert path.sample(1.5) == pytest.approx((0.45, 0.5, 0.0))
    assert path.sample(3.0)[0] == pytest.approx(1.2)
    assert path.sample(3.25) == pytest.approx((0.95, -1.0, 0.0))
    assert path.sample(10.0) == (0.2, 0.0, 0.0)  # after the end: hold the last position
    assert path.sample(0.0)[0] == 0.2            # before the start: the first knot
    assert path.sample(1.5)[0] == pytest.approx(0.45)  # sampling backwards finds its segment


def test_cubic_with_velocities_is_the_smoothstep_from_rest_to_rest():
    a, b = Knot(2.0, -0.5, 0.0), Knot(4.0, 0.5, 0.0)
    for s in (0.0, 0.25, 0.5, 0.8):
        psi, psi_dot, psi_ddot = interpolate(a, b, 2.0 + 2.0 * s)
        assert psi == pytest.approx(-0.5 + (3 * s ** 2 - 2 * s ** 3))
        assert psi_dot == pytest.approx((6 * s - 6 * s ** 2) / 2.0)
        assert psi_ddot == pytest.approx((6 - 12 * s) / 4.0)


def test_cubic_meets_the_given_velocities_at_both_ends():
    a, b = Knot(0.0, 0.1, 0.7), Knot(0.5, -0.3, -1.1)
    assert interpolate(a, b, 0.0)[:2] == pytest.approx((0.1, 0.7))
    assert interpolate(a, b, 0.5)[:2] == pytest.approx((-0.3, -1.1))


def test_quintic_with_accelerations_is_the_minimum_jerk_move():
    a, b = Knot(0.0, 0.0, 0.0, 0.0), Knot(1.0, 1.0, 0.0, 0.0)
    for s in (0.25, 0.5, 0.9):
        assert interpolate(a, b, s)[0] == pytest.approx(10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5)
    a, b = Knot(1.0, 0.3, -0.4, 2.0), Knot(1.7, -0.2, 0.5, -3.0)
    assert interpolate(a, b, 1.0) == pytest.approx((0.3, -0.4, 2.0))
    assert interpolate(a, b, 1.7) == pytest.approx((-0.2, 0.5, -3.0))


def test_one_knot_without_a_velocity_makes_the_segment_linear():
    """JTC: cubic only when both ends have velocities."""
    assert interpolate(Knot(0.0, 0.0, 5.0), Knot(1.0, 1.0), 0.5) == pytest.approx((0.5, 1.0, 0.0))


@given(st.floats(-1, 1), st.floats(-3, 3), st.floats(-1, 1), st.floats(-3, 3),
       st.floats(0.05, 5), st.floats(0, 1))
def test_interpolation_is_continuous_with_its_derivative(p0, v0, p1, v1, span, s):
    a, b = Knot(0.0, p0, v0), Knot(span, p1, v1)
    t, h = s * span, 1e-6 * span
    if 0.0 < t - h and t + h < span:
        slope = (interpolate(a, b, t + h)[0] - interpolate(a, b, t - h)[0]) / (2 * h)
        assert slope == pytest.approx(interpolate(a, b, t)[1], rel=1e-4, abs=1e-4)


def test_parse_splits_the_message_by_joint_name():
    knots = parse(['segment_2', 'segment_1'],
                  [Point(0.5, [0.1, 0.2], [1.0, 2.0]), Point(2.0, [0.3, 0.4], [0.0, 0.0])],
                  JOINTS)
    assert knots['segment_1'] == (Knot(0.5, 0.2, 2.0), Knot(2.0, 0.4, 0.0))
    assert knots['segment_2'] == (Knot(0.5, 0.1, 1.0), Knot(2.0, 0.3, 0.0))
    assert parse(['segment_1'], [Point(1.0, [0.5])], JOINTS) == {'segment_1': (Knot(1.0, 0.5),)}


@pytest.mark.parametrize('names, points, reason', [
    (['segment_1', 'elbow'], [Point(1.0, [0.0, 0.0])], "unknown joint 'elbow'"),
    ([], [Point(1.0, [])], 'no joint names'),
    (['segment_1'], [], 'no points'),
    (['segment_1', 'segment_1'], [Point(1.0, [0.0, 0.0])], 'named twice'),
    (['segment_1'], [Point(1.0, [0.0]), Point(1.0, [0.1])], 'not strictly increasing'),
    (['segment_1'], [Point(2.0, [0.0]), Point(1.0, [0.1])], 'point 0 at 2.0 s, point 1 at 1.0'),
    (['segment_1'], [Point(-1.0, [0.0])], 'time_from_start -1.0'),
    (['segment_1', 'segment_2'], [Point(1.0, [0.0])], '1 positions for 2 joints'),
    (['segment_1'], [Point(1.0, [0.0], [0.0, 1.0])], '2 velocities for 1 joints'),
    (['segment_1'], [Point(1.0, [0.0], [], [1.0, 1.0])], '2 accelerations'),
    (['segment_1'], [Point(1.0, [0.0], effort=[1.0])], 'effort given'),
    (['segment_1'], [Point(1.0, [float('nan')])], 'not finite'),
    (['segment_1'], [Point(1.0, [0.0], [0.5])], 'must end at rest'),
])
def test_parse_refuses_what_jtc_refuses(names, points, reason):
    with pytest.raises(TrajectoryError, match=reason.replace('(', r'\(')):
        parse(names, points, JOINTS)


def test_start_time_rules():
    assert start_time(0.0, 100.0, 5.0) == 100.0    # zero stamp: now
    assert start_time(103.0, 100.0, 5.0) == 103.0  # in the future: as stamped
    assert start_time(98.0, 100.0, 5.0) == 100.0   # started in the past, still running: from now
    with pytest.raises(TrajectoryError, match='before now'):
        start_time(90.0, 100.0, 5.0)


def test_a_new_trajectory_replaces_the_old_one_from_its_start_time():
    old = Path([Knot(0.0, 0.0), Knot(10.0, 1.0)])
    new = splice([Knot(2.0, -1.0)], start=6.0, now=3.0, before=old.sample, old=old)
    for t in (3.0, 4.5, 6.0):  # the old trajectory until the new one's start, no jump
        assert new.sample(t)[0] == pytest.approx(old.sample(t)[0])
    assert new.sample(7.0)[0] == pytest.approx(0.6 + 0.5 * (-1.0 - 0.6))
    assert new.sample(8.0)[0] == pytest.approx(-1.0)
    assert new.sample(20.0)[0] == -1.0  # the old one's end (1.0) is gone


def test_replacement_keeps_the_old_knots_before_the_start():
    old = Path([Knot(0.0, 0.0), Knot(1.0, 1.0), Knot(2.0, 0.0)])
    new = splice([Knot(1.0, 0.5)], start=1.5, now=0.5, before=old.sample, old=old)
    assert new.sample(1.0)[0] == pytest.approx(1.0)  # the old peak still comes
    assert new.sample(1.5)[0] == pytest.approx(0.5)
    assert new.sample(2.5)[0] == pytest.approx(0.5)


def test_a_start_now_bridges_from_the_present_set_point():
    hold = (0.3, 0.0, 0.0)
    path = splice([Knot(2.0, 0.7, 0.0)], start=5.0, now=5.0, before=lambda t: hold)
    assert path.start == 5.0
    assert path.sample(5.0)[:2] == pytest.approx(hold[:2])
    assert path.sample(6.0)[0] == pytest.approx(0.5)  # cubic, rest to rest: midway at mid time
    assert path.sample(7.0) == pytest.approx((0.7, 0.0, 0.0))


def test_a_first_point_at_time_zero_is_taken_at_once():
    path = splice([Knot(0.0, 0.7), Knot(1.0, 0.9)], start=5.0, now=5.0,
                  before=lambda t: (0.0, 0.0, 0.0))
    assert path.sample(5.0)[0] == 0.7


def test_a_future_start_leaves_the_present_source_until_then():
    path = splice([Knot(1.0, 0.7)], start=8.0, now=5.0, before=lambda t: (0.1 * t, 0.1, 0.0))
    assert path.start == 8.0  # the caller follows its own source before
    assert path.sample(8.0)[0] == pytest.approx(0.8)
