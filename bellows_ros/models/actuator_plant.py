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
The simulated dual-bellows actuator: drive dynamics, sensors and switchable physical effects.

What the simulated hardware and the tests run. Underneath is paper B's model (`actuator`); on top:

- drive (section II-A): duty (-1..1) -> armature voltage -> current (R-L circuit, back-EMF) ->
  torque -> rotor (inertia, viscous friction) -> 100:1 gearbox -> 1.27 mm lead screw -> chamber
  plate; magnetic encoder counts on the motor shaft; hard end stops at the chamber's travel limits.
  The lead screw is not back-drivable: the gas load on the plate only ever resists the motor (like
  friction) and cannot turn it.
- spring: compression imposed (a test machine) or the quasi-static position under a load force.
- sensors: pressure and force with white noise and quantisation.
- effects, each off unless named: every module of `models.actuator_effects` (parameters SI,
  defaults in the effect, overridden under `actuator.effects` in the YAML). Each effect's
  `plant_term` says what the plant steps: the plate behind the nut, the gas temperature and
  amount before the pressure is solved, the pressure reading; its `model_params` what it changes
  in paper B's static model (E_V, buckling). Without an effect the volumes are purely geometric
  (4) and the force is (7)-(12) alone: the doctor's baseline.

Each effect's strength (`STRENGTHS`, 0 = off) can change while the plant runs
(`set_strengths`): the new effects take over at the start of the next step, in the stepping
thread, as one immutable object; the state (gas amount, plate, motor, sensor) carries on.

With no effect the plant is exactly `actuator.evaluate(without_buckling(without_bulging(params)),
...)` plus sensor noise; `model_params(params, effect_parameters(plant, effects))` returns the
parameters the model needs for the same physics. Its own parameters (drive, sensors, effect
defaults) are `ActuatorPlantParams`, built with the model's by `bellows_ros.config.actuator`.
"""
from dataclasses import dataclass
import math
import random
from typing import NamedTuple

from bellows_ros.errors import ParameterError
from bellows_ros.models import effect_strengths
from bellows_ros.models.actuator import forward, gas_amount, p_ref_of_amount
from bellows_ros.models.actuator_drive import Drive
from bellows_ros.models.actuator_effects import BY_NAME, EFFECTS, NAMES, STRENGTHS
from bellows_ros.models.actuator_geometry import area, P_ATM

ACTUATOR_EFFECTS = NAMES
# K: the ambient temperature of a plant whose effects set none (heat exchange sets its own)
T_AMBIENT = 293.15
NOISE_KEYS = ('pressure_noise', 'pressure_quantum', 'force_noise', 'force_quantum')


@dataclass(frozen=True)
class Sensors:
    """Pressure and force sensors: white noise (standard deviation) and quantisation step."""

    pressure_noise: float
    pressure_quantum: float
    force_noise: float
    force_quantum: float


@dataclass(frozen=True)
class ActuatorPlantParams:
    """
    The simulated actuator's own parameters, SI units.

    drive: `Drive` (config/hardware.yaml, `hardware.actuator_board.drive.*`: the hardware's drive
    train, shared with the driver); sensors: `Sensors` (config/actuator.yaml,
    `actuator.sensors.*`); effects: ((effect, ((parameter, value), ...)), ...), the YAML's
    `actuator.effects.*`, over the effects' own defaults.
    """

    drive: Drive
    sensors: Sensors
    effects: tuple = ()

    def effect_defaults(self):
        """{effect name: {parameter: value}}: each effect's defaults, the YAML's over them."""
        defaults = {e.name: {key: p.default for key, p in e.parameters.items()} for e in EFFECTS}
        for name, items in self.effects:
            defaults.setdefault(name, {}).update(items)
        return defaults


@dataclass(frozen=True)
class _Effects:
    """The plant's effects immutable: swapped whole (`ActuatorPlant.set_strengths`)."""

    chosen: tuple   # ((effect, ((parameter, value), ...)), ...)
    params: object  # ActuatorParams with E_V and buckling as the effects say (`model_params`)
    terms: tuple    # ((effect, PlantTerm), ...) in the effects' order


class ActuatorSample(NamedTuple):
    """
    One sample of the simulated hardware (SI units).

    t s; encoder_counts: motor encoder (0 at x_c = 0); x_c: true plate compression m;
    x_s: spring compression m; p: measured pressure Pa abs; f: measured spring force N;
    at_lower_stop / at_upper_stop: the nut is on an end stop.
    """

    t: float
    encoder_counts: int
    x_c: float
    x_s: float
    p: float
    f: float
    at_lower_stop: bool
    at_upper_stop: bool


def effect_parameters(plant, effects):
    """
    Validate `effects` and fill in the YAML defaults of `plant` (ActuatorPlantParams).

    `effects`: None, an iterable of names, or {name: {parameter: value}} (as `--effect` gives).
    Returns {name: {parameter: float}}. An unknown effect or parameter, or a negative or non-finite
    value, raises ParameterError naming it.
    """
    if effects is None:
        return {}
    if not isinstance(effects, dict):
        effects = {name: {} for name in effects}
    defaults = plant.effect_defaults()
    chosen = {}
    for name, overrides in effects.items():
        if name not in BY_NAME:
            raise ParameterError(f"unknown actuator effect '{name}' (known: "
                                 f"{', '.join(NAMES)})")
        effect = BY_NAME[name]
        values = dict(defaults.get(name, {}))
        for key, value in (overrides or {}).items():
            if key not in values:
                raise ParameterError(f"effect '{name}': unknown parameter '{key}' "
                                     f"(known: {', '.join(sorted(values))})")
            values[key] = value
        for key, value in values.items():
            value = float(value)
            low = effect.parameters[key].low if key in effect.parameters else 0.0
            if not math.isfinite(value) or value < low:
                raise ParameterError(
                    f"effect '{name}': parameter '{key}' must be finite and >= {low:g}, "
                    f'got {value}')
            values[key] = value
        problem = effect.check(values)
        if problem:
            raise ParameterError(f"effect '{name}': {problem}")
        chosen[name] = values
    return chosen


def strengths_of(chosen):
    """Return {effect: strength} (`STRENGTHS`, 0 = off) of effects as `effect_parameters` gives."""
    return {name: chosen.get(name, {}).get(key, 0.0) for name, key in STRENGTHS.items()}


def with_strengths(chosen, strengths):
    """Return effects `chosen` with new strengths {effect: value}, 0 = off (effect_strengths)."""
    return effect_strengths.with_strengths(chosen, strengths, STRENGTHS, 'actuator')


def model_params(params, chosen=None):
    """
    Return parameters for which `actuator.evaluate` has the plant's static physics.

    E_V and buckling on or off. `chosen`: the effects as `effect_parameters` returns them (None: no
    effect).
    """
    chosen = chosen or {}
    for effect in EFFECTS:
        params = effect.model_params(params, chosen.get(effect.name))
    return params


class ActuatorPlant:
    """
    Simulated actuator stepped at a fixed or varying dt (see module docstring).

    Parameters
    ----------
    params : ActuatorParams
    plant : ActuatorPlantParams (drive, sensors, effect defaults)
    effects : None, iterable of names or {name: {parameter: value}} (see `effect_parameters`)
    noise : None (the YAML's `actuator.sensors`), False (no noise, no quantisation), or a dict
        overriding some of `NOISE_KEYS`
    seed : int, optional, for the sensor noise
    x_c0, x_s0 : initial chamber and spring compression, m (default: the design point)
    gas : gas amount sealed in, as design-point pressure p_ref (Pa); default the YAML's p_ref

    """

    def __init__(self, params, plant, effects=None, noise=None, seed=None, x_c0=None, x_s0=0.0,
                 gas=None):
        self._raw_params = params
        self.plant = plant
        drive = plant.drive
        self.counts_per_rev = int(drive.counts_per_rev)
        self.x_c_min, self.x_c_max = params.chamber.x_min, params.chamber.x_max
        self.max_speed = drive.max_speed
        self._drive = drive
        self._metres_per_rad = drive.lead / (2.0 * math.pi * drive.gear_ratio)
        self._noise = self._noise_settings(plant, noise)
        self._random = random.Random(seed)
        # State.
        x_c = params.x_c_ref if x_c0 is None else float(x_c0)
        if not self.x_c_min <= x_c <= self.x_c_max:
            raise ParameterError(f'initial chamber compression {x_c} m is outside '
                                 f'[{self.x_c_min}, {self.x_c_max}] m')
        self.t = 0.0
        # motor angle, rad (nut position through the drive)
        self._theta = x_c / self._metres_per_rad
        self._omega = 0.0
        self._current = 0.0
        self.x_c = x_c                               # plate, m
        self.x_s = float(x_s0)                       # spring, m
        # The gas: N = P V at ambient temperature (Pa·m³), its temperature and ambient (K).
        self.t_ambient = self.temperature = T_AMBIENT
        self._effects_now = self._pending = self._effects_of(effect_parameters(plant, effects))
        self.params = self._effects_now.params
        self.gas_amount = gas_amount(self.params, params.p_ref if gas is None else float(gas))
        p, force, k = forward(self.params, self.x_c, self.x_s, self.gas_amount)
        self._p, self._f, self._k = p, force, k
        self._terms = ()
        self._apply_effects(self._effects_now)

    def _effects_of(self, chosen):
        """Return the immutable `_Effects` of validated effect parameters (`effect_parameters`)."""
        terms = tuple((e.name, e.plant_term(chosen[e.name])) for e in EFFECTS if e.name in chosen)
        return _Effects(
            chosen=tuple((name, tuple(values.items())) for name, values in chosen.items()),
            params=model_params(self._raw_params, chosen),
            terms=tuple((name, term) for name, term in terms if term is not None))

    def _apply_effects(self, new):
        """
        Take `new` (`_Effects`), in the stepping thread: the gas, plate and sensor carry on.

        Each term starts from the plant's state and its effect's earlier term; a gas that no
        term heats is at ambient.
        """
        self._effects_now = new
        self.effects = {name: dict(values) for name, values in new.chosen}
        self.params = new.params
        previous = dict(self._terms)
        self._terms = new.terms
        self.t_ambient = T_AMBIENT
        for name, term in new.terms:
            term.start(self, previous.get(name))
        hooked = {hook: tuple(term for _, term in new.terms if hook in term.hooks())
                  for hook in ('plate', 'temperature', 'gas', 'sensor')}
        self._plate_terms, self._heat_terms = hooked['plate'], hooked['temperature']
        self._gas_terms, self._sensor_terms = hooked['gas'], hooked['sensor']
        if not self._heat_terms:
            self.temperature = self.t_ambient
        self._decay = (None, 0.0)

    def strengths(self):
        """Return {effect: strength} of the effects set (`STRENGTHS`, 0 = off)."""
        return strengths_of({name: dict(values) for name, values in self._pending.chosen})

    def set_strengths(self, strengths):
        """
        Set effect strengths {effect: value} (`STRENGTHS`; 0 = off); taken at the next step.

        An effect switched on takes its other parameters from the YAML (`actuator.effects`). May be
        called from another thread than `step`: the new effects are built here and swapped in as
        one object at the start of the next step, never half-way. A value the plant cannot use
        raises ParameterError naming it, and nothing changes.
        """
        self._pending = self.effects_for(strengths)

    def effects_for(self, strengths):
        """Return the effects set now with new strengths, checked (ParameterError), not taken."""
        chosen = {name: dict(values) for name, values in self._pending.chosen}
        return self._effects_of(effect_parameters(self.plant, with_strengths(chosen, strengths)))

    def _take_pending(self):
        pending = self._pending  # one read: a newer set_strengths waits for the next step
        if pending is not self._effects_now:
            self._apply_effects(pending)

    @staticmethod
    def _noise_settings(plant, noise):
        s = plant.sensors
        settings = {key: float(getattr(s, key)) for key in NOISE_KEYS}
        if noise is False:
            return dict.fromkeys(NOISE_KEYS, 0.0)
        for key, value in (noise or {}).items():
            if key not in settings:
                raise ParameterError(f"unknown noise parameter '{key}' (known: "
                                     f"{', '.join(NOISE_KEYS)})")
            settings[key] = float(value)
        return settings

    # --- state the controller and the tests may read ---------------------------------------------

    @property
    def x_nut(self):
        """Lead-screw nut position (what the encoder measures), m."""
        return self._theta * self._metres_per_rad

    @property
    def pressure(self):
        """True system pressure, Pa."""
        return self._p

    @property
    def force(self):
        """True spring force, N."""
        return self._f

    @property
    def gas(self):
        """Present gas amount as design-point pressure p_ref, Pa (drops with a leak)."""
        return p_ref_of_amount(self.params, self.gas_amount)

    def travel_time(self, x_from, x_to):
        """Return a lower bound on the time (s) the lead screw needs between two points."""
        return abs(x_to - x_from) / self.max_speed

    # --- simulation
    # -------------------------------------------------------------------------------

    def step(self, dt, duty, x_s_imposed=None, f_load=None):
        """
        Advance by `dt` (s) with motor duty in -1..1; the spring is imposed or loaded.

        Pass `x_s_imposed` (m) to move the spring like a test machine, or `f_load` (N) to load it
        (quasi-static: the spring settles where its force equals the load); neither keeps x_s.
        """
        if not dt > 0.0:
            raise ParameterError(f'time step must be > 0, got {dt}')
        self._take_pending()
        duty = -1.0 if duty < -1.0 else 1.0 if duty > 1.0 else float(duty)
        self._step_drive(dt, duty)
        return self._finish_step(dt, x_s_imposed, f_load)

    def step_nut(self, dt, x_nut, x_s_imposed=None, f_load=None):
        """
        Advance by `dt` (s) with the lead-screw nut moved to `x_nut` (m) kinematically.

        For replaying a measured chamber trajectory (`bellows simulate actuator --effect ...`): the
        motor is assumed to follow, the plate still sees the backlash and the end stops.
        """
        if not dt > 0.0:
            raise ParameterError(f'time step must be > 0, got {dt}')
        self._take_pending()
        x_nut = min(max(float(x_nut), self.x_c_min), self.x_c_max)
        new_theta = x_nut / self._metres_per_rad
        self._omega = (new_theta - self._theta) / dt
        self._theta = new_theta
        self._move_plate(x_nut)
        return self._finish_step(dt, x_s_imposed, f_load)

    def _finish_step(self, dt, x_s_imposed, f_load):
        """Finish a step once the plate has moved: spring imposed or loaded, gas, clock."""
        if x_s_imposed is not None:
            self.x_s = float(x_s_imposed)
        elif f_load is not None:
            self.x_s = self._spring_under_load(float(f_load))
        self._step_gas(dt)
        self.t += dt
        return self._sample(dt)

    @property
    def stiffness(self):
        """True dF/dx_s (N/m) at the present state (13)."""
        return self._k

    def _move_plate(self, nut):
        """Move the plate with the nut, unless an effect's term stands between them (a play)."""
        x_c = nut
        for term in self._plate_terms:
            x_c = term.plate(nut, self.x_c)
        self.x_c = min(max(x_c, self.x_c_min), self.x_c_max)

    def _step_drive(self, dt, duty):
        d = self._drive
        if self._decay[0] != dt:
            self._decay = (dt, math.exp(-d.resistance * dt / d.inductance))
        decay = self._decay[1]
        k = d.torque_constant
        # R-L armature, exact over the step for the present back-EMF.
        i_ss = (duty * d.supply_voltage - k * self._omega) / d.resistance
        self._current = i_ss + (self._current - i_ss) * decay
        torque = k * self._current
        # Gas load on the plate, reflected to the motor through a self-locking screw: it resists
        # motion in either direction and never drives the motor.
        # (10) for the chamber: the plate does the work (P - P_atm) dV_c [ours].
        area_c = area(self.params.chamber, self.x_c, self._p)[0]
        resist = abs((self._p - P_ATM) * area_c) * self._metres_per_rad / d.efficiency
        omega = self._omega
        if omega == 0.0 and abs(torque) <= resist:
            omega = 0.0
        else:
            direction = omega if omega != 0.0 else torque
            drag = resist if direction > 0.0 else -resist
            new = ((omega + dt * (torque - drag) / d.rotor_inertia)
                   / (1.0 + dt * d.viscous_friction / d.rotor_inertia))
            omega = 0.0 if new * direction < 0.0 else new   # friction stops, it does not reverse
        theta = self._theta + omega * dt
        low, high = self.x_c_min / self._metres_per_rad, self.x_c_max / self._metres_per_rad
        if theta <= low:
            theta, omega = low, 0.0
        elif theta >= high:
            theta, omega = high, 0.0
        self._theta, self._omega = theta, omega
        self._move_plate(theta * self._metres_per_rad)

    def _spring_under_load(self, f_load):
        x = self.x_s
        amount = self.gas_amount * self.temperature / self.t_ambient
        s = self.params.spring
        for _ in range(20):
            _, force, k = forward(self.params, self.x_c, x, amount)
            step = (force - f_load) / k if k > 0.0 else 0.0
            x = min(max(x - step, s.x_min), s.x_max)
            if abs(step) < 1e-9:
                break
        return x

    def _step_gas(self, dt):
        for term in self._heat_terms:
            term.temperature(self, dt)
        for term in self._gas_terms:
            term.gas(self, dt)
        amount = self.gas_amount * self.temperature / self.t_ambient
        self._p, self._f, self._k = forward(self.params, self.x_c, self.x_s, amount)

    def _sample(self, dt):
        n = self._noise
        p = self._p
        for term in self._sensor_terms:
            p = term.sensor(p, dt, self.t)
        p += (self._random.gauss(0.0, n['pressure_noise']) if n['pressure_noise'] else 0.0)
        f = self._f + (self._random.gauss(0.0, n['force_noise']) if n['force_noise'] else 0.0)
        if n['pressure_quantum']:
            p = round(p / n['pressure_quantum']) * n['pressure_quantum']
        if n['force_quantum']:
            f = round(f / n['force_quantum']) * n['force_quantum']
        nut = self._theta * self._metres_per_rad
        counts = int(round(self._theta / (2.0 * math.pi) * self.counts_per_rev))
        return ActuatorSample(self.t, counts, self.x_c, self.x_s, p, f,
                              nut <= self.x_c_min, nut >= self.x_c_max)

    def x_from_counts(self, counts):
        """Chamber compression (m) the encoder reading stands for (nut position)."""
        return counts / self.counts_per_rev * 2.0 * math.pi * self._metres_per_rad
