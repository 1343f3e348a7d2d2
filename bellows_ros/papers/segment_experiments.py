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
Experiments on the simulated segment, like paper A's test-bench measurements.

The angle is imposed by an external force, the pressures set by a pressure controller, the
torque read from a force-torque sensor.

Each returns the segment data columns `t, psi, p1, p2, tau_ext, psi_dot` plus `tau_motion`
(M Ψ̈ + C Ψ̇ + N of the plant, which a bench computes from the known mechanics) as a dict of arrays
of *measured* values. Deterministic for a given seed.
"""
import math

import numpy as np

from bellows_ros.models.segment_plant import SegmentPlant

FIG10_PSI = math.radians(74.5)     # angle of the Fig. 10 scenario, rad
FIG10_P1 = 4.0e5                   # chain-1 pressure of the Fig. 10 scenario, Pa abs
FIG10_EXCURSION = math.radians(-30.0)  # lowest angle of the external excursion (our choice), rad


def run_plant(plant, dt, p_cmd1, p_cmd2, psi_path):
    """Drive `plant` with command arrays and an imposed angle path; returns the measured record."""
    names = ('t', 'psi', 'psi_dot', 'p1', 'p2', 'tau_ext')
    rows = [plant.step(dt, a, b, psi_imposed=c) + (plant.tau_motion,)
            for a, b, c in zip(np.asarray(p_cmd1, float).tolist(),
                               np.asarray(p_cmd2, float).tolist(),
                               np.asarray(psi_path, float).tolist())]
    table = np.array(rows, float)
    record = {name: table[:, k] for k, name in enumerate(names)}
    record['tau_motion'] = table[:, len(names)]
    return record


def _smooth_moves(times, levels, t):
    """Piecewise moves between `levels` at `times` (start, end pairs) with a cosine profile."""
    out = np.full_like(t, levels[0])
    for (start, end), before, after in zip(times, levels[:-1], levels[1:]):
        inside = (t >= start) & (t < end)
        shape = 0.5 - 0.5 * np.cos(np.pi * (t[inside] - start) / (end - start))
        out[inside] = before + (after - before) * shape
        out[t >= end] = after
    return out


def _programme(rng, duration, move_range, hold_range, params):
    """
    Build a random angle/pressure programme like paper A's identification runs.

    The angle moves anywhere in |Ψ| ≤ 1.4 rad with holds; at most holds new chain pressures (one
    chain up to 7 bar abs, the other lower, sometimes both vented), ramped so that some ramps
    overlap the next move.
    """
    p0, top = params.p0, 7.0e5
    angle_times, angles = [], [0.0]
    pressure_times, pressures1, pressures2 = [], [p0], [p0]
    now = 0.5
    while now < duration:
        move = rng.uniform(*move_range)
        angle_times.append((now, now + move))
        angles.append(rng.uniform(-1.4, 1.4))
        now += move + rng.uniform(*hold_range)
        if rng.random() < 0.7:
            ramp = rng.uniform(0.2, 1.0)
            start = now - 0.5 * ramp
            pressure_times.append((start, start + ramp))
            if rng.random() < 0.15:
                high = low = p0
            else:
                high, low = rng.uniform(p0, top), rng.uniform(p0, p0 + 0.5 * (top - p0))
            chain = rng.integers(2)
            pressures1.append(high if chain == 0 else low)
            pressures2.append(low if chain == 0 else high)
    return angle_times, angles, pressure_times, pressures1, pressures2


def _pressure_schedule(rng, duration, hold_range, params):
    """
    Build chain pressures on their own clock, like paper A's "simultaneous variation".

    ("... of the angle of curvature and pressure".) After each hold (`hold_range`, s) new levels
    are reached by a step or a ramp at one of several speeds (0.05-1 s). Levels cover the whole
    range p0..p_max: one chain pressurised and the other vented or lower (as in Fig. 10), both
    pressurised at once, or both vented; so every chain holds many pressures, low ones included.
    """
    p0, top = params.p0, params.p_max
    times, pressures1, pressures2 = [], [p0], [p0]
    now = 0.5
    while now < duration:
        ramp = rng.uniform(0.05, 1.0)
        times.append((now, now + ramp))
        kind = rng.random()
        if kind < 0.1:
            high = low = p0
        elif kind < 0.4:
            high, low = rng.uniform(p0, top), rng.uniform(p0, top)
        else:
            high, low = rng.uniform(p0,
                                    top), rng.choice([p0, rng.uniform(p0, p0 + 0.5 * (top - p0))])
        first = rng.integers(2) == 0
        pressures1.append(high if first else low)
        pressures2.append(low if first else high)
        now += ramp + rng.uniform(*hold_range)
    return times, pressures1, pressures2


def _record(params, plant_params, effects, noise, seed, duration, dt, move_range, hold_range,
            pressure_hold=None):
    rng = np.random.default_rng(seed)
    t = np.arange(1, int(round(duration / dt)) + 1) * dt
    angle_times, angles, pressure_times, p1, p2 = _programme(rng, duration, move_range,
                                                             hold_range, params)
    if pressure_hold is not None:
        pressure_times, p1, p2 = _pressure_schedule(rng, duration, pressure_hold, params)
    psi = _smooth_moves(angle_times, angles, t)
    cmd1 = _smooth_moves(pressure_times, p1, t)
    cmd2 = _smooth_moves(pressure_times, p2, t)
    plant = SegmentPlant(params, plant_params, effects, noise,
                         seed=None if seed is None else seed + 7919)
    return run_plant(plant, dt, cmd1, cmd2, psi)


def quasi_static_record(params, plant, effects=None, noise=None, seed=None, duration=60.0,
                        dt=1e-3, pressure_hold=None):
    """
    Run slow excursions (2-5 s per move, |Ψ| ≤ 1.4 rad) like paper A's identification runs.

    With reversals, holds, and pressure steps and ramps on both chains (up to 7 bar abs).

    By default the pressures change only between angle moves (a few levels in 30 s). With
    `pressure_hold` = (shortest, longest) hold in s, they follow their own schedule instead
    (`_pressure_schedule`: many levels over p0..p_max, steps and ramps at several speeds), which is
    what a pressure-dependent effect needs to be told from a smooth function of the pressure.
    """
    return _record(params, plant, effects, noise, seed, duration, dt, (2.0, 5.0), (0.5, 2.0),
                   pressure_hold)


def dynamic_record(params, plant, effects=None, noise=None, seed=None, duration=30.0, dt=1e-3):
    """
    Run faster motion at several speeds (0.3-1.5 s per move, short holds), changing pressures.

    Like paper A's dynamic validation (Fig. 12).
    """
    return _record(params, plant, effects, noise, seed, duration, dt, (0.3, 1.5), (0.0, 0.5))


def fig10_record(params, plant_params,
                 effects=('contact_hysteresis', 'pressure_friction', 'natural_curvature'),
                 noise=None, seed=None, dt=1e-3, excursion=FIG10_EXCURSION):
    """
    Paper A's Fig. 10 scenario on the bench, returns (record, before_index, after_index).

    Vented segment moved from 0 to Ψ = 74.5° (2 s), hold; chain 1 ramped to 4 bar abs (1 s), chain
    2 vented; hold to t = 6 s ("before"); external excursion down to `excursion` (default -30°, our
    choice) in 4 s and back to 74.5° in 4 s; hold to t = 18 s ("after"). `effects` is a tuple of
    names or a mapping (see `SegmentPlant`); default: the full paper-A physics.
    """
    p0 = params.p0
    t = np.arange(1, int(round(18.0 / dt)) + 1) * dt
    psi = _smooth_moves([(0.0, 2.0), (8.0, 12.0), (12.0, 16.0)],
                        [0.0, FIG10_PSI, excursion, FIG10_PSI], t)
    cmd1 = _smooth_moves([(3.0, 4.0)], [p0, FIG10_P1], t)
    cmd2 = np.full_like(t, p0)
    plant = SegmentPlant(params, plant_params, effects, noise, seed=seed)
    record = run_plant(plant, dt, cmd1, cmd2, psi)
    before = int(round(6.0 / dt)) - 1
    return record, before, len(t) - 1
