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
Joint trajectories as ros2_controllers' joint_trajectory_controller (JTC) runs them: pure maths.

The arm controller takes a trajectory_msgs/JointTrajectory on `~/joint_trajectory`; this module
holds its rules, one joint (one segment angle Ψ, rad) at a time, on the controller's clock (s):

- `parse` checks a message's content as JTC's `validate_trajectory_msg` does (joint names known
  and not repeated, at least one point, `time_from_start` strictly increasing, one position per
  joint in every point, velocities and accelerations empty or one per joint, no effort, zero
  velocity at the last point) and splits it into one list of `Knot`s per joint. A joint the
  message does not name keeps what it follows (JTC with partial goals allowed).
- `start_time`: a `header.stamp` of zero means "now"; a trajectory that would end in the past is
  refused; a start in the past counts from now (JTC's trajectory replacement).
- `splice` builds a joint's new `Path`: what the joint followed goes on until the new start time
  (the old path's own knots), a bridge knot there takes its position, velocity and acceleration,
  then come the new points at start + time_from_start. So a new trajectory replaces the rest of
  the old one from its start time on, without a jump.
- `Path.sample(t)`: between two knots JTC's interpolation: linear in position when either knot
  lacks a velocity, cubic (position and velocity at both ends) when both have one, quintic when
  both also have an acceleration. After the last knot the path holds its position.
"""
from dataclasses import dataclass
import math
from typing import Callable, Dict, Optional, Sequence, Tuple


class TrajectoryError(ValueError):
    """A trajectory message the controller refuses; the text says why, in one line."""


@dataclass(frozen=True)
class Knot:
    """One joint's path point: time t (s), position (rad), velocity (rad/s), accel. (rad/s²)."""

    t: float
    position: float
    velocity: Optional[float] = None
    acceleration: Optional[float] = None


@dataclass(frozen=True)
class Point:
    """A JointTrajectoryPoint as plain numbers: time_from_start (s) and one value per joint."""

    time_from_start: float
    positions: Sequence[float]
    velocities: Sequence[float] = ()
    accelerations: Sequence[float] = ()
    effort: Sequence[float] = ()


def parse(joint_names: Sequence[str], points: Sequence[Point],
          known: Sequence[str]) -> Dict[str, Tuple[Knot, ...]]:
    """
    Check a trajectory and return {joint: knots}, knot times = time_from_start (s).

    `known`: the joints this controller drives. TrajectoryError names the first fault.
    """
    if not joint_names:
        raise TrajectoryError('no joint names')
    for name in joint_names:
        if name not in known:
            raise TrajectoryError(f"unknown joint '{name}' (this controller drives "
                                  f"{', '.join(known)})")
        if list(joint_names).count(name) > 1:
            raise TrajectoryError(f"joint '{name}' named twice")
    if not points:
        raise TrajectoryError('no points')
    n = len(joint_names)
    previous = None
    for i, point in enumerate(points):
        where = f'point {i}'
        if not math.isfinite(point.time_from_start) or point.time_from_start < 0.0:
            raise TrajectoryError(f'{where}: time_from_start {point.time_from_start} s')
        if previous is not None and point.time_from_start <= previous:
            raise TrajectoryError(f'time_from_start is not strictly increasing: point {i - 1} '
                                  f'at {previous} s, point {i} at {point.time_from_start} s')
        previous = point.time_from_start
        if len(point.positions) != n:
            raise TrajectoryError(f'{where}: {len(point.positions)} positions for {n} joints')
        for field in ('velocities', 'accelerations'):
            if len(getattr(point, field)) not in (0, n):
                raise TrajectoryError(f'{where}: {len(getattr(point, field))} {field} for {n} '
                                      'joints (give none or one per joint)')
        if len(point.effort):
            raise TrajectoryError(f'{where}: effort given (the segments follow angles only)')
        values = (*point.positions, *point.velocities, *point.accelerations)
        if not all(math.isfinite(v) for v in values):
            raise TrajectoryError(f'{where}: a value is not finite')
    last = points[-1].velocities
    for name, velocity in zip(joint_names, last):
        if velocity != 0.0:
            raise TrajectoryError(f"joint '{name}': velocity {velocity} rad/s at the last point "
                                  '(a trajectory must end at rest)')
    return {name: tuple(Knot(p.time_from_start, p.positions[j],
                             p.velocities[j] if len(p.velocities) else None,
                             p.accelerations[j] if len(p.accelerations) else None)
                        for p in points)
            for j, name in enumerate(joint_names)}


def start_time(stamp: float, now: float, duration: float) -> float:
    """
    Return when a trajectory starts (s): its `stamp`, or `now` for a stamp of 0 or in the past.

    `duration`: the last point's time_from_start (s). TrajectoryError for a nonzero stamp whose
    trajectory ends before `now`.
    """
    if stamp == 0.0:
        return now
    if stamp + duration < now:
        raise TrajectoryError(f'starts at {stamp:.6f} s and ends at {stamp + duration:.6f} s, '
                              f'before now ({now:.6f} s)')
    return max(stamp, now)


class Path:
    """One joint's path: knots at strictly increasing times, interpolated as JTC does."""

    def __init__(self, knots: Sequence[Knot]):
        if not knots:
            raise ValueError('a path needs a knot')
        if any(b.t <= a.t for a, b in zip(knots, knots[1:])):
            raise ValueError('knot times must increase strictly')
        self.knots = tuple(knots)
        self._index = 0  # the segment the last sample fell in: samples mostly move forward

    @property
    def start(self) -> float:
        return self.knots[0].t

    @property
    def end(self) -> float:
        return self.knots[-1].t

    def sample(self, t: float) -> Tuple[float, float, float]:
        """Return (Ψ, Ψ̇, Ψ̈) at `t` s (rad, rad/s, rad/s²); after the end it holds."""
        knots = self.knots
        if t >= knots[-1].t:
            return knots[-1].position, 0.0, 0.0
        if t < knots[0].t:
            first = knots[0]
            return first.position, first.velocity or 0.0, first.acceleration or 0.0
        i = self._index if knots[self._index].t <= t else 0
        while knots[i + 1].t <= t:
            i += 1
        self._index = i
        return interpolate(knots[i], knots[i + 1], t)


def interpolate(a: Knot, b: Knot, t: float) -> Tuple[float, float, float]:
    """(position, velocity, acceleration) at `t` between knots a and b: JTC's polynomials."""
    T, s = b.t - a.t, t - a.t
    if a.velocity is None or b.velocity is None:
        slope = (b.position - a.position) / T
        return a.position + slope * s, slope, 0.0
    if a.acceleration is None or b.acceleration is None:
        c = _cubic(a.position, a.velocity, b.position, b.velocity, T)
    else:
        c = _quintic(a.position, a.velocity, a.acceleration, b.position, b.velocity,
                     b.acceleration, T)
    position = sum(k * s ** n for n, k in enumerate(c))
    velocity = sum(n * k * s ** (n - 1) for n, k in enumerate(c) if n >= 1)
    acceleration = sum(n * (n - 1) * k * s ** (n - 2) for n, k in enumerate(c) if n >= 2)
    return position, velocity, acceleration


def _cubic(p0, v0, p1, v1, T):
    """Coefficients c0..c3 of the cubic through (p0, v0) at 0 and (p1, v1) at T."""
    return (p0, v0, (3.0 * (p1 - p0) - (2.0 * v0 + v1) * T) / T ** 2,
            (2.0 * (p0 - p1) + (v0 + v1) * T) / T ** 3)


def _quintic(p0, v0, a0, p1, v1, a1, T):
    """Coefficients c0..c5 of the quintic through (p0, v0, a0) at 0 and (p1, v1, a1) at T."""
    h = p1 - p0
    return (p0, v0, 0.5 * a0,
            (20.0 * h - (8.0 * v1 + 12.0 * v0) * T - (3.0 * a0 - a1) * T ** 2) / (2.0 * T ** 3),
            (-30.0 * h + (14.0 * v1 + 16.0 * v0) * T + (3.0 * a0 - 2.0 * a1) * T ** 2)
            / (2.0 * T ** 4),
            (12.0 * h - 6.0 * (v1 + v0) * T - (a0 - a1) * T ** 2) / (2.0 * T ** 5))


def splice(knots: Sequence[Knot], start: float, now: float,
           before: Callable[[float], Tuple[float, float, float]],
           old: Optional[Path] = None) -> Path:
    """
    Return a joint's path for new `knots` (times from `start`), taking over from what it follows.

    `before(t)` -> (Ψ, Ψ̇, Ψ̈) is what the joint follows now; `old` its path, if that is one. The
    result runs from `now` (an old path: its knots up to `start` are kept) or from `start` (the
    caller follows `before` until then), through a bridge knot at `start` with `before(start)`,
    to the new knots at start + time_from_start. A first knot at time_from_start 0 replaces the
    bridge (the joint is sent there at once, as JTC does).
    """
    lead = []
    if old is not None and now < start:
        lead.append(Knot(now, *before(now)))
        lead.extend(k for k in old.knots if now < k.t < start)
    new = [Knot(start + k.t, k.position, k.velocity, k.acceleration) for k in knots]
    if new[0].t > start:
        lead.append(Knot(start, *before(start)))
    return Path(lead + new)
