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
The physical range of every number in config/segment.yaml, actuator.yaml and hardware.yaml.

`load(name, path)` reads a file as `io.params.load` does and refuses a value outside its
range, in one line naming the file, the parameter and the range: a unit mistake (a length in mm,
a pressure in bar) or a typo is never computed with. Every range also bounds what the value can
make the package do: no count, grid or loop derived from a parameter can grow without limit
(`segment.geometry.n_lambda` sizes the strain profile walked every sample; the spring's travel
bounds the rest-point search; `actuator.force.e_f` and the pressures keep E_F's exponential
finite).

The ranges are those of devices, not of the default one: bellows from millimetres to tens of
centimetres, supplies up to 10 bar gauge, motors from a few volts to tens of volts. Relations
between parameters (p_max > p0, r_big > r_small, a travel inside the geometry) are checked where
the objects are built (`config.segment`, `config.actuator`, `config.hardware`, the models).
`test/test_core_refusals.py` holds every number of the three files to an entry here.
"""
from typing import NamedTuple

from bellows_ros.errors import ParameterError
from bellows_ros.io import params as param_files
from bellows_ros.io.data import MAX_ANGLE  # a half turn: no segment bends further
from bellows_ros.models.limits import (AMBIENT_RANGE, MAX_CONVOLUTIONS, MAX_LENGTH,
                                       MAX_PROFILE_SAMPLES, TIME_CONSTANT)


class Range(NamedTuple):
    """Closed range [low, high] in `unit`; `hint` is added to the error (a likely unit mistake)."""

    low: float
    high: float
    unit: str
    hint: str = ''


# Absolute pressure, Pa: pneumatic supplies and soft bellows stay at or below 10 bar gauge
# (industrial air 6-10 bar); 1.1 MPa abs leaves every real set-point inside.
MAX_PRESSURE = 1.1e6
# Below 10 kPa abs a sealed bellows collapses under the ambient air: no working gas is that thin.
MIN_GAS_PRESSURE = 1e4
# Lengths of a bellows, a rib or a travel, m: from a millimetre (miniature bellows) to a metre
# (`models.limits.MAX_LENGTH`: the largest soft-robot segments are tens of centimetres).
LENGTH = (1e-3, MAX_LENGTH)
TRAVEL = (-MAX_LENGTH, MAX_LENGTH)
# Coefficients fitted by linear least squares with no physical scale of their own (the columns
# of (29), (34), F_MTS): bounded only so that every product with a state stays finite.
COEFFICIENT = (-1e9, 1e9)
# Torques and torque slopes of an arm segment: paper A's are ~1 N·m; a thousand times that is
# beyond any soft segment.
TORQUE = (-1e4, 1e4)
# Driver periods and timeouts, s: below 1 ms a timer busy-loops the node; above a minute nobody
# waits for a watchdog or a reconnect.
PERIOD = (1e-3, 60.0)

RANGES = {
    # --- config/segment.yaml (paper A)
    'segment.p0': Range(*AMBIENT_RANGE, 'Pa abs', 'an ambient pressure: was it written in bar '
                        'or kPa?'),
    'segment.p_max': Range(AMBIENT_RANGE[0], MAX_PRESSURE, 'Pa abs', 'was it written in bar?'),
    'segment.geometry.l0': Range(*LENGTH, 'm', 'was it written in mm?'),
    'segment.geometry.s0': Range(*LENGTH, 'm', 'was it written in mm?'),
    'segment.geometry.sa_max': Range(*LENGTH, 'm', 'was it written in mm?'),
    # Samples of the strain profile (28), a list walked in every step (`models.limits`).
    'segment.geometry.n_lambda': Range(1, MAX_PROFILE_SAMPLES, 'samples'),
    # Membrane stress resultants: shear modulus 0.1-10 MPa of elastomers times 0.1-10 mm of wall,
    # fabric-reinforced walls a hundred times more.
    'segment.ogden.mu': Range(1.0, 1e7, 'N/m'),
    # > 2 (Appendix B); Ogden exponents of rubbers reported in the literature stay below 30.
    'segment.ogden.gamma': Range(2.0, 30.0, '1'),
    'segment.restoring.k_s': Range(*TORQUE, 'N·m/rad'),
    'segment.restoring.k_sp': Range(*TORQUE, 'N·m/rad'),
    # tanh steepness in the scaled pressure (0..1): beyond 1e3 it is a step.
    'segment.restoring.c_psi0': Range(-1e3, 1e3, '1'),
    'segment.restoring.c_psi0_p': Range(-MAX_ANGLE, MAX_ANGLE, 'rad'),
    'segment.friction.c_f': Range(*TORQUE, 'N·m'),
    'segment.friction.c_fp': Range(*TORQUE, 'N·m'),
    'segment.friction.c_vel': Range(0.0, 1e6, 's/rad'),
    'segment.actuator.theta': Range(*COEFFICIENT, 'N·m'),
    'segment.previous.theta': Range(*COEFFICIENT, 'N·m'),
    # M, C, N of (2): a segment of up to ~10 kg at up to 1 m.
    'segment.dynamics.inertia': Range(0.0, 100.0, 'kg·m²'),
    'segment.dynamics.damping': Range(0.0, 1e4, 'N·m·s/rad'),
    'segment.dynamics.gravity': Range(*TORQUE, 'N·m'),
    'segment.plant.valve_tau': Range(*TIME_CONSTANT, 's'),
    'segment.plant.inertia': Range(1e-6, 100.0, 'kg·m²'),
    'segment.plant.damping': Range(0.0, 1e4, 'N·m·s/rad'),
    'segment.plant.gravity': Range(*TORQUE, 'N·m'),
    'segment.plant.psi_limit': Range(1e-3, MAX_ANGLE, 'rad', 'was it written in degrees?'),
    'segment.plant.stop_stiffness': Range(1e-3, 1e7, 'N·m/rad'),
    'segment.plant.sensor_lag_tau': Range(0.0, TIME_CONSTANT[1], 's'),
    'segment.plant.noise.p': Range(0.0, 1e5, 'Pa'),
    'segment.plant.noise.psi': Range(0.0, 1.0, 'rad'),
    'segment.plant.noise.psi_dot': Range(0.0, 100.0, 'rad/s'),
    'segment.plant.noise.tau': Range(0.0, 1e3, 'N·m'),
    'segment.identify.input_cutoff': Range(0.0, 1e5, 'Hz'),  # 0 = off; above any record's rate
    # --- config/actuator.yaml (paper B)
    'actuator.gas.p_ref': Range(MIN_GAS_PRESSURE, MAX_PRESSURE, 'Pa abs', 'was it written in '
                                'bar or kPa?'),
    'actuator.gas.x_c_ref': Range(*TRAVEL, 'm'),
    'actuator.gas.v_tube': Range(0.0, 0.01, 'm³'),  # up to 10 L of tubing and reservoir
    'actuator.force.f_mts': Range(*COEFFICIENT, 'N/m^k'),
    # E_F = C1 exp(C2 P + C3 dh + C4) (11): with P <= MAX_PRESSURE and dh <= 0.2 m the exponent
    # stays below 220 + 400 + 50 < 709, so E_F is finite on every state.
    'actuator.force.e_f': [Range(-1e4, 1e4, 'N'), Range(-2e-4, 2e-4, '1/Pa'),
                           Range(-2e3, 2e3, '1/m'), Range(-50.0, 50.0, '1')],
    # k_b: up to the axial stiffness of the stiffest bellows wall of any size here (the doctor's
    # fit stops at the spring's own wall tube, 17 kN/m: config/actuator.yaml, docs/doctor.md).
    'actuator.buckling.stiffness_loss': Range(0.0, 1e6, 'N/m'),
    # p_cr: from an onset at ambient (its width delta p_cr below any pressure sensor's noise) to
    # beyond any supply (compression alone sets the onset); the doctor fits over all of it.
    'actuator.buckling.critical_pressure': Range(1e2, MAX_PRESSURE, 'Pa gauge'),
    # x_cr: from an onset at the start of the travel to beyond any travel (pressure alone).
    'actuator.buckling.critical_compression': Range(1e-4, 1.0, 'm'),
    'actuator.buckling.onset_width': Range(1e-3, 1.0, '1'),  # a step .. the whole critical load
    'actuator.stiffness.x_s_low': Range(*TRAVEL, 'm'),
    'actuator.stiffness.x_s_high': Range(*TRAVEL, 'm'),
    'actuator.sensors.pressure_noise': Range(0.0, 1e5, 'Pa'),
    'actuator.sensors.pressure_quantum': Range(0.0, 1e5, 'Pa'),
    'actuator.sensors.force_noise': Range(0.0, 1e3, 'N'),
    'actuator.sensors.force_quantum': Range(0.0, 1e3, 'N'),
    # --- config/hardware.yaml
    'hardware.actuator_board.baud': Range(1200, 1.2e7, 'bit/s'),
    'hardware.actuator_board.stale_timeout': Range(*PERIOD, 's'),
    'hardware.actuator_board.reconnect_interval': Range(*PERIOD, 's'),
    'hardware.actuator_board.heartbeat_period': Range(*PERIOD, 's'),
    'hardware.actuator_board.command_timeout': Range(*PERIOD, 's'),
    'hardware.actuator_board.duty_max': Range(0.0, 1.0, '1'),
    'hardware.actuator_board.end_stop_margin': Range(0.0, 0.1, 'm'),
    # DC gear motors from miniature (3 V) to 48 V industrial, any lead screw.
    'hardware.actuator_board.drive.supply_voltage': Range(1.0, 100.0, 'V'),
    'hardware.actuator_board.drive.resistance': Range(1e-3, 1e3, 'Ω'),
    'hardware.actuator_board.drive.inductance': Range(1e-7, 1.0, 'H'),  # R dt / L: never 0
    'hardware.actuator_board.drive.torque_constant': Range(1e-4, 10.0, 'N·m/A'),
    'hardware.actuator_board.drive.rotor_inertia': Range(1e-10, 1e-2, 'kg·m²'),
    'hardware.actuator_board.drive.viscous_friction': Range(0.0, 1.0, 'N·m·s/rad'),
    'hardware.actuator_board.drive.gear_ratio': Range(1.0, 1e4, '1'),
    'hardware.actuator_board.drive.counts_per_rev': Range(1, 1e6, 'counts'),
    'hardware.actuator_board.drive.lead': Range(1e-4, 0.1, 'm', 'was it written in mm?'),
    'hardware.actuator_board.drive.efficiency': Range(0.0, 1.0, '1'),
    'hardware.arm_bus.bitrate': Range(1e4, 8e6, 'bit/s'),  # CAN 10 kbit/s to CAN FD 8 Mbit/s
    'hardware.arm_bus.n_segments': Range(1, 64, 'segments'),  # the DBC limits it further
    'hardware.arm_bus.stale_timeout': Range(*PERIOD, 's'),
    'hardware.arm_bus.command_timeout': Range(*PERIOD, 's'),
}
# Both bellows of paper B (air chamber and spring) have the same kind of geometry.
for _bellows in ('air_chamber', 'spring'):
    RANGES.update({
        f'actuator.{_bellows}.r_big': Range(*LENGTH, 'm', 'was it written in mm?'),
        f'actuator.{_bellows}.r_small': Range(*LENGTH, 'm', 'was it written in mm?'),
        f'actuator.{_bellows}.wall': Range(0.0, 0.1, 'm', 'was it written in mm?'),
        f'actuator.{_bellows}.h0': Range(*LENGTH, 'm', 'was it written in mm?'),
        f'actuator.{_bellows}.n': Range(1, MAX_CONVOLUTIONS, 'convolutions'),
        f'actuator.{_bellows}.x_min': Range(*TRAVEL, 'm', 'was it written in mm?'),
        f'actuator.{_bellows}.x_max': Range(*TRAVEL, 'm', 'was it written in mm?'),
        # E_V (5), m³: a volume error beyond a litre is no bellows of this size range.
        f'actuator.{_bellows}.e_v': Range(-1e-3, 1e-3, 'm³'),
    })
BUCKLING_BOUNDS = 'actuator.buckling.bounds.'


def range_of(name):
    """`Range` (or one per item of a list) of parameter `name`, or None for a string parameter."""
    if name.startswith(BUCKLING_BOUNDS):  # the doctor's fit bounds of a buckling parameter
        return RANGES.get('actuator.buckling.' + name[len(BUCKLING_BOUNDS):])
    return RANGES.get(name)


def check_ranges(flat, source, more=None):
    """
    Raise ParameterError for the first value of `flat` (dotted names) outside its range.

    `more`: {name: Range} of the parameters whose range lives with their physics (the actuator's
    effects: `config.actuator.EFFECT_RANGES`), which the driver's configuration never loads.
    """
    for name, value in flat.items():
        rule = range_of(name) or (more or {}).get(name)
        if rule is None or isinstance(value, (str, bool)):
            continue
        items = value if isinstance(value, (list, tuple)) else [value]
        for index, item in enumerate(items):
            if isinstance(item, (str, bool)):
                continue  # a value of the wrong kind: `params.overlay` names it
            each = rule[min(index, len(rule) - 1)] if isinstance(rule, list) else rule
            if not each.low <= item <= each.high:
                which = f' item {index + 1}' if isinstance(value, (list, tuple)) else ''
                hint = f' ({each.hint})' if each.hint else ''
                raise ParameterError(
                    f"{source}: parameter '{name}'{which} is {item:g}, outside its physical "
                    f'range {each.low:g}..{each.high:g} {each.unit}{hint}')


# Sections of a file whose names its defaults do not list: each actuator effect's parameters are
# the effect's own (`models.actuator_effects`), which `config.actuator` checks by name and range.
OPEN_SECTIONS = {'actuator': ('actuator.effects.',)}


def load(name, params_path=None, more=None):
    """Load a parameter file as `params.load` does, every value checked against its range."""
    return param_files.load(name, params_path,
                            check=lambda flat, source: check_ranges(flat, source, more),
                            open_sections=OPEN_SECTIONS.get(name, ()))


# --- the `bellows` command's numbers: the same table as the nodes' parameters -------------------
# `--effect NAME:k=v` takes the range of the parameter it sets: `config.actuator.effect_range`,
# `config.segment.effect_range`; the simulated nodes' live strengths take the same.
# Options of the `bellows` command that take a number, with the reason of each range.
OPTIONS = {
    # one period of the spring motion: from a fast test rig (10 ms) to an hour; a shorter window
    # than 20 samples measures nothing (`measured_stiffness` says so)
    'stiffness.window': Range(0.01, 3600.0, 's'),
    # a spring's stiffness: soft foam springs to steel, N/m
    'stiffness.setpoint': Range(1.0, 1e6, 'N/m'),
    # a recording: from a millisecond to thirty days (a bag beyond that outgrows any reader)
    'record.duration': Range(1e-3, 30 * 86400.0, 's'),
}


def _outside(rule, value):
    hint = f' ({rule.hint})' if rule.hint else ''
    return f'{value:g} is outside its range {rule.low:g}..{rule.high:g} {rule.unit}{hint}'


def check_effects(effects, effect_range):
    """
    Raise ParameterError for an `--effect` value ({effect: {key: float}}) outside its range.

    `effect_range(effect, key)`: the system's `Range` of a parameter, or None.
    """
    for effect, values in effects.items():
        for key, value in values.items():
            rule = effect_range(effect, key)
            if rule is not None and not rule.low <= value <= rule.high:
                raise ParameterError(f'--effect {effect}:{key}={value:g}: {_outside(rule, value)}')


def option_type(name):
    """Return an argparse type for the option `name` of OPTIONS: a finite number in range."""
    import argparse
    import math
    rule = OPTIONS[name]

    def parse(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f'expected a number in {rule.unit}, got '
                                             f'{text!r}') from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f'expected a finite number in {rule.unit}, got '
                                             f'{text!r}')
        if not rule.low <= value <= rule.high:
            raise argparse.ArgumentTypeError(_outside(rule, value))
        return value
    parse.__name__ = name  # argparse names the type in some messages
    return parse
