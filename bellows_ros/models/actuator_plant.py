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
- effects, each off unless named (parameters SI, defaults under `actuator.effects` in the YAML):
  `air_leak` (conductance, m³/(s·Pa)): laminar flow through a restriction to ambient,
      dN/dt = -P · conductance · (P - P_atm) · T_amb/T   (N = P·V in Pa·m³ at ambient temperature);
  `heat_exchange` (time_constant s, gamma, t_ambient K): the gas heats on compression
      (adiabatic over each step, T V^(γ-1) = const) and relaxes to ambient through the walls,
      dT/dt = -(T - T_amb)/time_constant;
  `wall_bulging` (scale): the volume error E_V (5, 6) of the YAML times `scale`; without it the
      plant's volumes are purely geometric (4), the doctor's baseline;
  `sensor_lag` (time_constant s): first-order lag of the pressure sensor;
  `backlash` (width m): dead band between the lead-screw nut (what the encoder sees) and the plate;
  `buckling` (scale): the spring buckles under pressure and compression, `actuator.buckling_force`
      with the YAML's `actuator.buckling` parameters and the stiffness loss times `scale`; without
      it the force is paper B's (7)-(12) alone, the doctor's force baseline.

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
from bellows_ros.models.actuator import (forward, gas_amount, p_ref_of_amount, scaled_buckling,
                                         scaled_bulging, total_volume, without_buckling,
                                         without_bulging)
from bellows_ros.models.actuator_drive import Drive
from bellows_ros.models.actuator_geometry import area, P_ATM

ACTUATOR_EFFECTS = ('air_leak', 'heat_exchange', 'wall_bulging', 'sensor_lag', 'backlash',
                    'buckling')
# The parameter of each effect that says how strong it is, 0 = off (`ActuatorPlant.set_strengths`):
# a heat-exchange time constant of 0 is instant exchange, the isothermal gas of the baseline.
STRENGTHS = {'air_leak': 'conductance', 'heat_exchange': 'time_constant',
             'wall_bulging': 'scale', 'sensor_lag': 'time_constant', 'backlash': 'width',
             'buckling': 'scale'}
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
    `actuator.sensors.*`); effects: ((effect, ((parameter, value), ...)), ...), the defaults of
    `actuator.effects.*`.
    """

    drive: Drive
    sensors: Sensors
    effects: tuple = ()

    def effect_defaults(self):
        """{effect name: {parameter: value}} from the YAML."""
        return {name: dict(items) for name, items in self.effects}


@dataclass(frozen=True)
class _Effects:
    """The plant's effects immutable: swapped whole (`ActuatorPlant.set_strengths`)."""

    chosen: tuple   # ((effect, ((parameter, value), ...)), ...)
    params: object  # ActuatorParams with E_V and buckling as the effects say (`model_params`)
    leak: float
    heat_tau: object  # s, None = off
    gamma: float
    t_amb: float
    lag_tau: float
    half_play: float


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
        if name not in ACTUATOR_EFFECTS:
            raise ParameterError(f"unknown actuator effect '{name}' (known: "
                                 f"{', '.join(ACTUATOR_EFFECTS)})")
        values = dict(defaults.get(name, {}))
        for key, value in (overrides or {}).items():
            if key not in values:
                raise ParameterError(f"effect '{name}': unknown parameter '{key}' "
                                     f"(known: {', '.join(sorted(values))})")
            values[key] = value
        for key, value in values.items():
            value = float(value)
            if not math.isfinite(value) or value < 0.0:
                raise ParameterError(
                    f"effect '{name}': parameter '{key}' must be finite and >= 0, got {value}")
            values[key] = value
        chosen[name] = values
    if 'heat_exchange' in chosen and chosen['heat_exchange']['time_constant'] <= 0.0:
        raise ParameterError("effect 'heat_exchange': parameter 'time_constant' must be > 0")
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
    if 'wall_bulging' in chosen:
        params = scaled_bulging(params, chosen['wall_bulging']['scale'])
    else:
        params = without_bulging(params)
    if 'buckling' in chosen:
        if params.buckling is None:
            raise ParameterError("effect 'buckling': the parameters have no actuator.buckling "
                                 'section')
        return scaled_buckling(params, chosen['buckling']['scale'])
    return without_buckling(params)


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
        self._effects_now = self._pending = self._effects_of(effect_parameters(plant, effects))
        self._apply_effects(self._effects_now)
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
        self._x_c = x_c                              # plate
        self._x_s = float(x_s0)
        self._gas = gas_amount(self.params,
                               params.p_ref if gas is None else float(gas))  # N = P V at T_amb
        self._temperature = self._t_amb
        p, force, k = forward(self.params, self._x_c, self._x_s, self._gas)
        self._p, self._f, self._k = p, force, k
        self._p_sensor = p
        self._volume = (total_volume(self.params, self._x_c, self._x_s, p) if self._heat_tau
                        else None)

    def _effects_of(self, chosen):
        """Return the immutable `_Effects` of validated effect parameters (`effect_parameters`)."""
        heat = chosen.get('heat_exchange')
        return _Effects(
            chosen=tuple((name, tuple(values.items())) for name, values in chosen.items()),
            params=model_params(self._raw_params, chosen),
            leak=chosen.get('air_leak', {}).get('conductance', 0.0),
            heat_tau=heat['time_constant'] if heat else None,
            gamma=heat['gamma'] if heat else 1.4,
            t_amb=heat['t_ambient'] if heat else 293.15,
            lag_tau=chosen.get('sensor_lag', {}).get('time_constant', 0.0),
            half_play=0.5 * chosen.get('backlash', {}).get('width', 0.0))

    def _apply_effects(self, new):
        """Take `new` (`_Effects`), in the stepping thread; heat exchange off = gas at ambient."""
        self._effects_now = new
        self.effects = {name: dict(values) for name, values in new.chosen}
        self.params = new.params
        self._leak, self._heat_tau, self._lag_tau = new.leak, new.heat_tau, new.lag_tau
        self._gamma, self._t_amb, self._half_play = new.gamma, new.t_amb, new.half_play
        self._exp_cache = (None, 0.0, 0.0, 0.0)
        if hasattr(self, '_gas'):  # a change while running: the state carries on
            if not self._heat_tau:
                self._temperature = self._t_amb
            self._volume = (total_volume(self.params, self._x_c, self._x_s, self._p)
                            if self._heat_tau else None)

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
    def temperature(self):
        """Gas temperature, K (stays at ambient without `heat_exchange`)."""
        return self._temperature

    @property
    def gas(self):
        """Present gas amount as design-point pressure p_ref, Pa (drops with `air_leak`)."""
        return p_ref_of_amount(self.params, self._gas)

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
        self._update_exp(dt)
        x_nut = min(max(float(x_nut), self.x_c_min), self.x_c_max)
        new_theta = x_nut / self._metres_per_rad
        self._omega = (new_theta - self._theta) / dt
        self._theta = new_theta
        self._move_plate(x_nut)
        return self._finish_step(dt, x_s_imposed, f_load)

    def _finish_step(self, dt, x_s_imposed, f_load):
        """Finish a step once the plate has moved: spring imposed or loaded, gas, clock."""
        if x_s_imposed is not None:
            self._x_s = float(x_s_imposed)
        elif f_load is not None:
            self._x_s = self._spring_under_load(float(f_load))
        self._step_gas(dt)
        self.t += dt
        return self._sample(dt)

    @property
    def stiffness(self):
        """True dF/dx_s (N/m) at the present state (13)."""
        return self._k

    def _update_exp(self, dt):
        if self._exp_cache[0] != dt:
            d = self._drive
            self._exp_cache = (dt, math.exp(-d.resistance * dt / d.inductance),
                               1.0 - math.exp(-dt / self._lag_tau) if self._lag_tau > 0.0 else 1.0,
                               math.exp(-dt / self._heat_tau) if self._heat_tau else 1.0)

    def _move_plate(self, nut):
        """Backlash as a play operator: the plate moves only when the nut pushes it."""
        h = self._half_play
        if nut - self._x_c > h:
            self._x_c = nut - h
        elif self._x_c - nut > h:
            self._x_c = nut + h
        self._x_c = min(max(self._x_c, self.x_c_min), self.x_c_max)

    def _step_drive(self, dt, duty):
        d = self._drive
        self._update_exp(dt)
        decay = self._exp_cache[1]
        k = d.torque_constant
        # R-L armature, exact over the step for the present back-EMF.
        i_ss = (duty * d.supply_voltage - k * self._omega) / d.resistance
        self._current = i_ss + (self._current - i_ss) * decay
        torque = k * self._current
        # Gas load on the plate, reflected to the motor through a self-locking screw: it resists
        # motion in either direction and never drives the motor.
        # (10) for the chamber: the plate does the work (P - P_atm) dV_c [ours].
        area_c = area(self.params.chamber, self._x_c, self._p)[0]
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
        x = self._x_s
        amount = self._gas * self._temperature / self._t_amb
        s = self.params.spring
        for _ in range(20):
            _, force, k = forward(self.params, self._x_c, x, amount)
            step = (force - f_load) / k if k > 0.0 else 0.0
            x = min(max(x - step, s.x_min), s.x_max)
            if abs(step) < 1e-9:
                break
        return x

    def _step_gas(self, dt):
        if self._heat_tau:
            # Volume at the new geometry (E_V at the last pressure; the Newton solve below is
            # exact), needed only for the adiabatic temperature change.
            volume_new = total_volume(self.params, self._x_c, self._x_s, self._p)
            t = self._temperature * (self._volume / volume_new) ** (self._gamma - 1.0)
            self._temperature = self._t_amb + (t - self._t_amb) * self._exp_cache[3]
            self._volume = volume_new
        if self._leak:
            self._gas -= (dt * self._p * self._leak * (self._p - P_ATM) * self._t_amb
                          / self._temperature)
        amount = self._gas * self._temperature / self._t_amb
        self._p, self._f, self._k = forward(self.params, self._x_c, self._x_s, amount)

    def _sample(self, dt):
        n = self._noise
        self._p_sensor += (self._p - self._p_sensor) * self._exp_cache[2]
        p = self._p_sensor + (self._random.gauss(0.0, n['pressure_noise'])
                              if n['pressure_noise'] else 0.0)
        f = self._f + (self._random.gauss(0.0, n['force_noise']) if n['force_noise'] else 0.0)
        if n['pressure_quantum']:
            p = round(p / n['pressure_quantum']) * n['pressure_quantum']
        if n['force_quantum']:
            f = round(f / n['force_quantum']) * n['force_quantum']
        nut = self._theta * self._metres_per_rad
        counts = int(round(self._theta / (2.0 * math.pi) * self.counts_per_rev))
        return ActuatorSample(self.t, counts, self._x_c, self._x_s, p, f,
                              nut <= self.x_c_min, nut >= self.x_c_max)

    def x_from_counts(self, counts):
        """Chamber compression (m) the encoder reading stands for (nut position)."""
        return counts / self.counts_per_rev * 2.0 * math.pi * self._metres_per_rad
