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
Simulated arm segment: the driving-torque physics plus dynamics, valves, sensors, effects.

The effects are switchable. The simulated hardware and the tests use it as "the real
segment".

With no effects the plant *is* the doctor's baseline (docs/doctor.md): the previous model (34) with
constant friction (c_f only) and no natural curvature (Ψ_j0 = 0, k_s,p = 0). Each effect switches
on one piece of missing physics: every module of `models.segment_effects` (docs/effects.md), the
doctor's segment vocabulary (`SEGMENT_EFFECTS`). The full paper-A physics is those marked
`paper_a` together (`FULL_MODEL`). Unset effect parameters take the YAML values.
The strengths (`STRENGTHS`, 0 = off) can change while the plant runs (`set_strengths`): taken at
the start of the next step, in the stepping thread, as one immutable object; the state (angle,
pressures, strain memories) carries on.

Pressures follow the commands through a first-order valve/chamber lag (`segment.plant.valve_tau`).
With an imposed angle (test bench) the force-torque sensor reads
τ_ext = M Ψ̈ + C Ψ̇ + N(Ψ) - τ_drive (2); otherwise (2) is integrated (semi-implicit Euler) with
`tau_load` as τ_ext, using the plant's own M, C, N (`segment.plant.inertia/damping/gravity`) and
end stops at |Ψ| = `segment.plant.psi_limit`. Measured values carry Gaussian noise with the
standard deviations of `segment.plant.noise` unless `noise` overrides them.
"""
from collections import namedtuple
import dataclasses
from dataclasses import dataclass, fields
import math

import numpy as np

from bellows_ros.errors import ParameterError
from bellows_ros.models import effect_strengths
from bellows_ros.models.derivatives import rate
from bellows_ros.models.segment import motion_torque, SegmentModel, SegmentOutput
from bellows_ros.models.segment_effects import BY_NAME, driving_torque, EFFECTS, NAMES, STRENGTHS

SEGMENT_EFFECTS = NAMES
FULL_MODEL = tuple(effect.name for effect in EFFECTS if effect.paper_a)
NOISE_KEYS = ('p', 'psi', 'psi_dot', 'tau')
NO_NOISE = dict.fromkeys(NOISE_KEYS, 0.0)
# Longest step of the free-motion integration, s (a numerical setting, not physics: see `step`).
MAX_STEP = 1e-3


@dataclass(frozen=True)
class SegmentPlantParams:
    """
    The simulated segment's own parameters: `segment.plant.*` of config/segment.yaml.

    valve_tau s (valve/chamber lag); inertia kg·m², damping N·m·s/rad, gravity N·m (the true
    M, C, N of (2)); psi_limit rad and stop_stiffness N·m/rad (end stops); sensor_lag_tau s (the
    `sensor_lag` effect's default); noise_p Pa, noise_psi rad, noise_psi_dot rad/s, noise_tau N·m
    (sensor noise standard deviations). Field = dotted name below `segment.plant.` with '_'.
    """

    valve_tau: float
    inertia: float
    damping: float
    gravity: float
    psi_limit: float
    stop_stiffness: float
    sensor_lag_tau: float
    noise_p: float
    noise_psi: float
    noise_psi_dot: float
    noise_tau: float

    def replace(self, **changes):
        """Return a copy with some fields changed."""
        return dataclasses.replace(self, **changes)

    def flat(self):
        """Return flat ROS 2 names (`segment.plant.noise.p`, ...) -> values."""
        return {'segment.plant.' + PLANT_DOTTED[f.name]: getattr(self, f.name)
                for f in fields(self)}


# Field name -> dotted YAML name below `segment.plant.`.
PLANT_DOTTED = {f.name: (f.name.replace('_', '.', 1) if f.name.startswith('noise_') else f.name)
                for f in fields(SegmentPlantParams)}


def check_plant_params(plant, source='parameters'):
    """Raise ParameterError for plant values the simulation cannot use (names the parameter)."""
    def fail(name, why):
        raise ParameterError(f"{source}: parameter 'segment.plant.{PLANT_DOTTED[name]}' {why}")
    for name in ('valve_tau', 'inertia', 'psi_limit', 'stop_stiffness'):
        if not getattr(plant, name) > 0:
            fail(name, 'must be > 0')
    for name in ('noise_p', 'noise_psi', 'noise_psi_dot', 'noise_tau', 'sensor_lag_tau',
                 'damping'):  # negative: energy from nowhere
        if getattr(plant, name) < 0:
            fail(name, 'must be >= 0')


@dataclass(frozen=True)
class _SegmentEffects:
    """The plant's effects, immutable: swapped whole (`SegmentPlant.set_strengths`)."""

    effects: tuple     # ((effect, ((parameter, value), ...)), ...)
    physics: object    # SegmentParams of the true physics (`plant_physics`)
    model: object      # SegmentModel of `physics`, on the plant's strain memories
    torque: str        # the model output that is the driving torque: tau_prev (34), tau_drive
    lag: float         # s, 0 = off
    strengths: tuple   # ((effect, strength in use), ...) of the effects on that have one


SegmentSample = namedtuple('SegmentSample', 't psi psi_dot p1 p2 tau_ext')
SegmentSample.__doc__ = 'One sample: time s, Ψ rad, Ψ̇ rad/s, chain pressures Pa abs, τ_ext N·m.'


def check_effects(effects):
    """
    Validate an effects mapping {name: {param: float}}; return a normalised dict.

    A sequence of names takes all parameters from the YAML. Unknown names or parameters raise
    ParameterError.
    """
    if not isinstance(effects, dict):
        effects = {name: {} for name in (effects or ())}
    checked = {}
    for name, options in effects.items():
        if name not in BY_NAME:
            raise ParameterError(f"unknown segment effect '{name}' (known: "
                                 f"{', '.join(SEGMENT_EFFECTS)})")
        known = BY_NAME[name].parameters
        options = dict(options or {})
        for key, value in options.items():
            if key not in known:
                raise ParameterError(f"segment effect '{name}': unknown parameter '{key}' (known: "
                                     f"{', '.join(known) or 'none'})")
            if not math.isfinite(float(value)):
                raise ParameterError(f"segment effect '{name}': parameter '{key}' is not finite")
        checked[name] = {key: float(value) for key, value in options.items()}
        problem = BY_NAME[name].check(checked[name])
        if problem:
            raise ParameterError(f"segment effect '{name}': {problem}")
    return checked


def plant_physics(params, effects):
    """
    Return SegmentParams of the true physics for the switched-on `effects` (validated mapping).

    Missing physics is switched off (each effect's `off`: c_f,p = 0 without `pressure_friction`).
    Effect parameters override the YAML values; those of the plant's own (a sensor lag) are
    applied by `SegmentPlant`.
    """
    changes = {}
    for effect in EFFECTS:
        if effect.name not in effects:
            changes.update(effect.off)
            continue
        for key, value in effects[effect.name].items():
            parameter = effect.parameters[key]
            if not parameter.in_plant:
                changes[parameter.field] = value
    return params.replace(**changes)


class SegmentPlant:
    """
    The simulated segment. `step(...)` advances it by `dt` and returns the measured SegmentSample.

    `params` (SegmentParams) is the physics the effects start from, `plant` (SegmentPlantParams)
    the valves, dynamics, end stops and sensors.

    True state: `t`, `psi`, `psi_dot`, `psi_ddot`, `p1`, `p2` (chamber pressures), `tau_ext`,
    `tau_drive`, `tau_motion` (= M Ψ̈ + C Ψ̇ + N, true) and `outputs` (the model's
    `SegmentOutput` of the last step).
    """

    def __init__(self, params, plant, effects=None, noise=None, seed=None, psi0=0.0):
        self.params = params
        self.plant = plant
        self._effects_now = self._pending = self._effects_of(check_effects(effects),
                                                             SegmentModel)
        self._apply_effects(self._effects_now)
        sigma = {'p': plant.noise_p, 'psi': plant.noise_psi, 'psi_dot': plant.noise_psi_dot,
                 'tau': plant.noise_tau}
        for key, value in (noise or {}).items():
            if key not in sigma:
                raise ParameterError(f"segment plant noise: unknown key '{key}' (known: "
                                     f"{', '.join(NOISE_KEYS)})")
            if not value >= 0:
                raise ParameterError(f"segment plant noise: '{key}' must be >= 0")
            sigma[key] = float(value)
        self.sigma = np.array([sigma['psi'], sigma['psi_dot'], sigma['p'], sigma['p'],
                               sigma['tau']])
        self.rng = np.random.default_rng(seed)
        self.reset(psi0)

    def _effects_of(self, effects, model_of):
        """Return the immutable `_SegmentEffects` of validated `effects`; `model_of(physics)`."""
        physics = plant_physics(self.params, effects)
        on = [effect for effect in EFFECTS if effect.name in effects]
        strengths = []
        for effect in on:
            if effect.strength:
                parameter = effect.parameters[effect.strength]
                source = self.plant if parameter.in_plant else physics
                strengths.append((effect.name, effects[effect.name].get(
                    effect.strength, getattr(source, parameter.field))))
        return _SegmentEffects(
            effects=tuple((name, tuple(values.items())) for name, values in effects.items()),
            physics=physics, model=model_of(physics),
            torque=driving_torque(effects),   # (29) with contact hysteresis, else (34)
            lag=sum(e.plant_lag(effects[e.name], self.plant) for e in on),
            strengths=tuple(strengths))

    def _apply_effects(self, new):
        self._effects_now = new
        self.effects = {name: dict(values) for name, values in new.effects}
        self.physics, self.model = new.physics, new.model
        self.torque, self.lag = new.torque, new.lag

    def strengths(self, in_use=False):
        """
        Return {effect: strength} (`STRENGTHS`, 0 = off) of the effects set.

        in_use: of those the plant stepped with last (a change not taken yet left out).
        """
        chosen = self._effects_now if in_use else self._pending
        return {**dict.fromkeys(STRENGTHS, 0.0), **dict(chosen.strengths)}

    def set_strengths(self, strengths):
        """
        Set effect strengths {effect: value} (`STRENGTHS`; 0 = off); taken at the next step.

        An effect switched on takes its other parameters from the YAML. May be called from another
        thread than `step`: the new effects, their model carrying on the strain memories
        (`SegmentModel.carried_on`), are built here and swapped in as one object at the start of
        the next step. A value the plant cannot use raises ParameterError, and nothing changes.
        """
        self._pending = self.effects_for(strengths)

    def effects_for(self, strengths):
        """Return the effects set now with new strengths, checked (ParameterError), not taken."""
        effects = effect_strengths.with_strengths(dict(self._pending.effects), strengths,
                                                  STRENGTHS, 'segment')
        return self._effects_of(check_effects(effects), self._pending.model.carried_on)

    def reset(self, psi0=0.0):
        """Vented chambers, segment at rest at Ψ = psi0, empty strain memories."""
        p0 = self.params.p0
        self.t, self.psi, self.psi_dot, self.psi_ddot = 0.0, float(psi0), 0.0, 0.0
        self.p1 = self.p2 = self.sensed1 = self.sensed2 = p0
        self.tau_ext = self.tau_drive = self.tau_motion = 0.0
        self.outputs = SegmentOutput(*(0.0,) * len(SegmentOutput._fields))
        self.model.reset()
        self._noise, self._next = np.zeros((0, 5)), 0

    def _draw(self):
        if self._next >= len(self._noise):
            self._noise = self.rng.standard_normal((4096, 5)) * self.sigma
            self._next = 0
        row = self._noise[self._next]
        self._next += 1
        return row

    def _drive(self):
        self.outputs = self.model.step(self.psi, self.psi_dot, self.p1, self.p2)
        return getattr(self.outputs, self.torque)

    def _end_stop(self):
        """
        Torque of the end stops beyond |Ψ| = psi_limit: stiff spring, damping ratio 0.8, N·m.

        Needed because one pressurised chain alone has no equilibrium inside the range: its
        actuator torque grows with Ψ faster than the restoring torque falls.
        """
        p = self.plant
        over = abs(self.psi) - p.psi_limit
        if over <= 0.0:
            return 0.0
        damping = 1.6 * math.sqrt(p.stop_stiffness * p.inertia)
        return -math.copysign(p.stop_stiffness * over, self.psi) - damping * self.psi_dot

    def step(self, dt, p_cmd1, p_cmd2, psi_imposed=None, tau_load=None):
        """
        Advance by `dt` s with pressure commands (Pa abs).

        Impose Ψ (rad) or apply `tau_load` (N·m).

        A real-time caller that falls behind passes a long `dt`; the free motion is then integrated
        in equal sub-steps of at most MAX_STEP, because the explicit update of the stiff, damped
        end stop is stable only for steps well under 7 ms. An imposed angle is reached in one step.
        """
        pending = self._pending  # one read: a newer set_strengths waits for the next step
        if pending is not self._effects_now:
            self._apply_effects(pending)
        substeps = 1 if psi_imposed is not None else max(1, math.ceil(dt / MAX_STEP - 1e-9))
        for _ in range(substeps):
            self._advance(dt / substeps, p_cmd1, p_cmd2, psi_imposed, tau_load)
        n_psi, n_dot, n_p1, n_p2, n_tau = self._draw()
        return SegmentSample(self.t, self.psi + n_psi, self.psi_dot + n_dot, self.sensed1 + n_p1,
                             self.sensed2 + n_p2, self.tau_ext + n_tau)

    def _advance(self, dt, p_cmd1, p_cmd2, psi_imposed, tau_load):
        p = self.plant
        blend = 1.0 - math.exp(-dt / p.valve_tau)
        self.p1 += blend * (p_cmd1 - self.p1)
        self.p2 += blend * (p_cmd2 - self.p2)
        dynamics = (p.inertia, p.damping, p.gravity)
        if psi_imposed is not None:
            # The imposed path is piecewise linear in Ψ: its rates are the backward differences.
            velocity = rate(psi_imposed, self.psi, dt, self.psi_dot)
            self.psi_ddot = rate(velocity, self.psi_dot, dt, self.psi_ddot)
            self.psi, self.psi_dot = float(psi_imposed), velocity
            self.tau_drive = self._drive()
            self.tau_motion = motion_torque(*dynamics, self.psi, self.psi_dot, self.psi_ddot)
            self.tau_ext = self.tau_motion - self.tau_drive
        else:
            self.tau_drive = self._drive()
            self.tau_ext = 0.0 if tau_load is None else float(tau_load)
            # (2) solved for Ψ̈: M Ψ̈ = τ_ext + τ_drive + τ_stop - (C Ψ̇ + N(Ψ))
            psi = self.psi
            self.psi_ddot = (self.tau_ext + self.tau_drive + self._end_stop()
                             - motion_torque(*dynamics, psi, self.psi_dot, 0.0)) / p.inertia
            self.psi_dot += dt * self.psi_ddot
            self.psi += dt * self.psi_dot
            # Semi-implicit Euler: damping acts with the updated rate, gravity at the old angle.
            self.tau_motion = motion_torque(*dynamics, psi, self.psi_dot, self.psi_ddot)
        if self.lag > 0.0:
            follow = 1.0 - math.exp(-dt / self.lag)
            self.sensed1 += follow * (self.p1 - self.sensed1)
            self.sensed2 += follow * (self.p2 - self.sensed2)
        else:
            self.sensed1, self.sensed2 = self.p1, self.p2
        self.t += dt
