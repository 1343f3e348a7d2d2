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
Built-in angle trajectories for the arm controller: waypoints joined by smooth moves and holds.

A trajectory is a tuple of waypoints (Ψ_target rad, move_time s, hold_time s) starting from
`start` (rad): each move is a half-cosine from the previous target (zero velocity at both ends,
peak speed |ΔΨ| π / (2 T)), followed by a hold. Sampled by `setpoint(trajectory, t)` ->
(Ψ_d, Ψ̇_d, Ψ̈_d); before 0 and after the end it holds the first / last angle.
"""
from collections import namedtuple
import math

from bellows_ros.errors import ParameterError

Trajectory = namedtuple('Trajectory', 'start waypoints')

# Reversals (through the straight segment and back, and short ones), holds after each move, and
# peak speeds from 0.4 to 2.6 rad/s, inside |Ψ| <= 0.9 rad where the segment is held with one
# chain at under 2.5 bar abs (docs/arm_control.md). 33 s (`duration`).
REVERSALS = Trajectory(0.0, (
    (0.8, 3.0, 2.0),
    (-0.6, 3.0, 2.0),    # a reversal through Ψ = 0: chain 1's stored strain is released
    (0.8, 1.5, 2.0),     # back to 0.8 rad: same angle, other history
    (0.2, 1.0, 1.5),
    (0.9, 0.8, 1.5),
    (0.5, 0.5, 0.0),     # quick reversals without a hold
    (0.9, 0.5, 1.5),
    (-0.8, 1.2, 2.0),
    (-0.2, 0.8, 1.5),
    (-0.7, 0.6, 1.5),
    (0.0, 2.0, 2.6),
))
# Slow sine-like sweep for the README scenario (moves of 5 s, ±0.7 rad).
SWEEP = Trajectory(0.0, ((0.7, 3.0, 2.0), (-0.7, 5.0, 2.0), (0.7, 5.0, 2.0), (0.0, 3.0, 2.0)))
TRAJECTORIES = {'reversals': REVERSALS, 'sweep': SWEEP}


def by_name(name):
    """Return the built-in trajectory `name`; ParameterError names the known ones."""
    try:
        return TRAJECTORIES[name]
    except KeyError:
        raise ParameterError(f"unknown trajectory '{name}' (known: "
                             f"{', '.join(TRAJECTORIES)})") from None


def duration(trajectory):
    """Total time of the trajectory, s."""
    return sum(move + hold for _, move, hold in trajectory.waypoints)


def setpoint(trajectory, t):
    """(Ψ_d rad, Ψ̇_d rad/s, Ψ̈_d rad/s²) at time `t` s."""
    here, start = trajectory.start, 0.0
    for target, move, hold in trajectory.waypoints:
        if t < start + move:
            if t < start:
                break
            s = (t - start) / move
            half = 0.5 * (target - here)
            rate = math.pi / move
            c, s_ = math.cos(math.pi * s), math.sin(math.pi * s)
            return here + half * (1.0 - c), half * rate * s_, half * rate * rate * c
        here = target
        start += move
        if t < start + hold:
            break
        start += hold
    return here, 0.0, 0.0


def phases(trajectory, t):
    """
    Tell whether time `t` is in a 'hold' or a 'move', and whether a move reverses.

    For a move: whether it reverses the previous move's direction (True/False; None for holds).
    """
    here, start, direction = trajectory.start, 0.0, 0.0
    for target, move, hold in trajectory.waypoints:
        step = math.copysign(1.0, target - here)
        if start <= t < start + move:
            return 'move', direction != 0.0 and step != direction
        here, direction = target, step
        start += move
        if start <= t < start + hold:
            return 'hold', None
        start += hold
    return 'hold', None
