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
Actuator parameters: config/actuator.yaml (and a user's file over it) -> one object per layer.

The file's `actuator.` section splits into paper B's model, `ActuatorParams` (air_chamber, spring,
gas, force, buckling, stiffness), and the simulated actuator's `ActuatorPlantParams` (sensors,
effects, and the drive train, which is hardware: config/hardware.yaml,
`hardware.actuator_board.drive`, its one home, shared with the driver). Values the equations cannot
use are refused here, naming the parameter, before any object is built.
"""
import dataclasses
from typing import NamedTuple

from bellows_ros.config import ranges
from bellows_ros.config.hardware import load_drive
from bellows_ros.errors import ParameterError
from bellows_ros.io import params as param_files
from bellows_ros.models.actuator import ActuatorParams, Buckling, NO_BUCKLING
from bellows_ros.models.actuator_effects import EFFECTS
from bellows_ros.models.actuator_geometry import Bellows
from bellows_ros.models.actuator_plant import ActuatorPlantParams, Sensors
from bellows_ros.models.limits import MAX_CONVOLUTIONS, MAX_LENGTH

DEFAULT_SOURCE = 'config/actuator.yaml'


class ActuatorConfig(NamedTuple):
    """The two parameter objects of one actuator file."""

    model: ActuatorParams
    plant: ActuatorPlantParams

    def flat(self):
        """All names of a complete actuator file (not the drive: hardware.yaml's), for writing."""
        return params_to_flat(self.model, self.plant)


# Each effect's parameters carry their own range (`models.actuator_effects`), checked with the
# file's other numbers (config/ranges.py's) when the model loads.
EFFECT_RANGES = {f'actuator.effects.{effect.name}.{key}':
                 ranges.Range(p.low, p.high, p.unit, p.hint)
                 for effect in EFFECTS for key, p in effect.parameters.items()}


def effect_range(effect, key):
    """`Range` of the actuator's `--effect effect:key=...` (its YAML parameter's), or None."""
    return EFFECT_RANGES.get(f'actuator.effects.{effect}.{key}')


def load_actuator(params_path=None, hardware_params_path=None):
    """
    `config/actuator.yaml` with the user's file (if any) laid over it -> `ActuatorConfig`.

    The plant's drive train comes from config/hardware.yaml (`hardware_params_path` over it).
    """
    flat = ranges.load('actuator', params_path, more=EFFECT_RANGES)
    return actuator_from_flat(flat, load_drive(hardware_params_path),
                              params_path or DEFAULT_SOURCE)


def load_actuator_params(params_path=None):
    """Return paper B's model, `ActuatorParams`, of `load_actuator(params_path)`."""
    return load_actuator(params_path).model


def load_actuator_plant_params(params_path=None, hardware_params_path=None):
    """Return the simulated actuator's `ActuatorPlantParams` of `load_actuator(...)`."""
    return load_actuator(params_path, hardware_params_path).plant


def actuator_from_flat(flat, drive, source='parameters'):
    """Build `ActuatorConfig` from flat dotted names (`actuator.gas.v_tube`, ...) and a `Drive`."""
    values = param_files.section(flat, 'actuator')
    build = param_files.build
    parts = {}
    for prefix in ('air_chamber', 'spring', 'gas', 'force', 'stiffness', 'sensors', 'effects',
                   'buckling'):
        parts[prefix] = param_files.section(values, prefix)
    known = {name.split('.')[0] for name in values}
    unknown = sorted(known - set(parts))
    if unknown:
        raise ParameterError(f"{source}: unknown parameter 'actuator.{unknown[0]}'")
    effects = {}
    for name, value in parts['effects'].items():
        if f'actuator.effects.{name}' not in EFFECT_RANGES:
            raise ParameterError(f"{source}: unknown parameter 'actuator.effects.{name}' (the "
                                 f"effects' parameters: docs/effects.md)")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ParameterError(f"{source}: parameter 'actuator.effects.{name}' must be a "
                                 f'number, got {value!r}')
        effect, _, key = name.partition('.')
        effects.setdefault(effect, {})[key] = float(value)
    try:
        _check_admissible(parts, source)
        model = ActuatorParams(
            chamber=build(Bellows, parts['air_chamber'], f'{source}: actuator.air_chamber'),
            spring=build(Bellows, parts['spring'], f'{source}: actuator.spring'),
            p_ref=float(_need(parts['gas'], 'p_ref', source, 'gas')),
            x_c_ref=float(_need(parts['gas'], 'x_c_ref', source, 'gas')),
            v_tube=float(_need(parts['gas'], 'v_tube', source, 'gas')),
            f_mts=tuple(float(v) for v in _need(parts['force'], 'f_mts', source, 'force')),
            e_f=tuple(float(v) for v in _need(parts['force'], 'e_f', source, 'force')),
            x_s_low=float(_need(parts['stiffness'], 'x_s_low', source, 'stiffness')),
            x_s_high=float(_need(parts['stiffness'], 'x_s_high', source, 'stiffness')),
            buckling=_buckling(parts['buckling'], source),
        )
        plant = ActuatorPlantParams(
            drive=drive,
            sensors=build(Sensors, parts['sensors'], f'{source}: actuator.sensors'),
            effects=tuple(sorted((k, tuple(sorted(v.items()))) for k, v in effects.items())),
        )
        return ActuatorConfig(model, plant)
    except TypeError as exc:  # a list where a number belongs, or the reverse
        raise ParameterError(f'{source}: {exc}') from None
    except ParameterError as exc:  # from a parameter object's own checks, which know no file
        message = str(exc)
        if message.startswith(f'{source}:'):
            raise
        raise ParameterError(f'{source}: {message}') from None


def _check_admissible(parts, source):
    """
    Refuse values the equations cannot use, naming the parameter (as the segment's check does).

    Without this a zero height divides by zero while the gas amount is computed, a fractional
    segment count is silently truncated, and a travel range beyond the frustum geometry (3) takes
    the square root of a negative number.
    """
    def fail(name, why):
        raise ParameterError(f"{source}: parameter 'actuator.{name}' {why}")

    def number(group, name):
        value = parts[group].get(name)
        if not isinstance(value, (int, float)) or isinstance(value, bool):
            fail(f'{group}.{name}', f'must be a number, got {value!r}')
        return float(value)
    for group in ('air_chamber', 'spring'):
        r_big, r_small = number(group, 'r_big'), number(group, 'r_small')
        h0, x_min, x_max = number(group, 'h0'), number(group, 'x_min'), number(group, 'x_max')
        n = parts[group].get('n')
        if isinstance(n, bool) or not isinstance(n, (int, float)) or n != int(n) \
                or not 1 <= n <= MAX_CONVOLUTIONS:
            fail(f'{group}.n', f'must be a whole number of segments in 1..{MAX_CONVOLUTIONS}, '
                 f'got {n!r}')
        if not MAX_LENGTH >= r_big > r_small > 0:
            fail(f'{group}.r_big', f'must exceed r_small > 0 and stay within {MAX_LENGTH:g} m '
                 f'(got {r_big:g}, {r_small:g}; in mm?)')
        if not 0 < h0 <= MAX_LENGTH:
            fail(f'{group}.h0', f'must lie in (0, {MAX_LENGTH:g}] m, got {h0:g} (in mm?)')
        if number(group, 'wall') < 0:
            fail(f'{group}.wall', 'must be >= 0')
        if not x_min < x_max < n * h0:
            fail(f'{group}.x_max', f'must exceed x_min and stay below n*h0 = {n * h0:g} m')
        for x in (x_min, x_max):  # R(dh)^2 term of (3) is concave in dh: the ends bound it
            dh = x / n
            if (r_big - r_small) ** 2 - (dh * dh - 2.0 * h0 * dh) / 4.0 <= 0:
                fail(f'{group}.x_min' if x == x_min else f'{group}.x_max',
                     f'{x:g} m lies beyond the frustum geometry (3) of this bellows')
    if not number('gas', 'p_ref') > 0:
        fail('gas.p_ref', 'must be > 0 (absolute pressure, Pa)')
    if number('gas', 'v_tube') < 0:
        fail('gas.v_tube', 'must be >= 0')
    x_c_ref = number('gas', 'x_c_ref')
    if not number('air_chamber', 'x_min') <= x_c_ref <= number('air_chamber', 'x_max'):
        fail('gas.x_c_ref', 'must lie within the air chamber travel [x_min, x_max]')
    if not number('stiffness', 'x_s_low') < number('stiffness', 'x_s_high'):
        fail('stiffness.x_s_high', 'must exceed x_s_low')
    # The stiffness window is spring compression: outside the spring's travel F_MTS has no data,
    # and the rest-point search (`rest_compression`) would walk to it in 0.5 mm steps.
    for name in ('x_s_low', 'x_s_high'):
        if not number('spring', 'x_min') <= number('stiffness', name) <= number('spring', 'x_max'):
            fail(f'stiffness.{name}', 'must lie within the spring travel [x_min, x_max]')
    for name, value in parts['sensors'].items():
        if number('sensors', name) < 0:
            fail(f'sensors.{name}', 'must be >= 0')


def _buckling(values, source):
    if not values:
        return NO_BUCKLING
    bounds = {}
    for name, value in param_files.section(values, 'bounds').items():
        if not (isinstance(value, (list, tuple)) and len(value) == 2):
            raise ParameterError(f"{source}: parameter 'actuator.buckling.bounds.{name}' "
                                 'expected [low, high]')
        bounds[name] = (float(value[0]), float(value[1]))
    plain = {k: v for k, v in values.items() if not k.startswith('bounds.')}
    plain['bounds'] = tuple(sorted(bounds.items()))
    return param_files.build(Buckling, plain, f'{source}: actuator.buckling')


def _need(mapping, name, source, group):
    if name not in mapping:
        raise ParameterError(f"{source}: missing parameter 'actuator.{group}.{name}'")
    return mapping[name]


def params_to_flat(params, plant=None):
    """
    Flat dotted names of `params` (ActuatorParams), ready for `params.write_file`.

    With `plant` (ActuatorPlantParams) its sensors and effects too: the inverse of
    `actuator_from_flat` (the drive is config/hardware.yaml's).
    """
    flat = {}
    for name, bellows in (('air_chamber', params.chamber), ('spring', params.spring)):
        for field in dataclasses.fields(Bellows):
            value = getattr(bellows, field.name)
            flat[f'actuator.{name}.{field.name}'] = (list(value) if isinstance(value, tuple)
                                                     else value)
    flat['actuator.gas.p_ref'] = params.p_ref
    flat['actuator.gas.x_c_ref'] = params.x_c_ref
    flat['actuator.gas.v_tube'] = params.v_tube
    flat['actuator.force.f_mts'] = list(params.f_mts)
    flat['actuator.force.e_f'] = list(params.e_f)
    flat['actuator.stiffness.x_s_low'] = params.x_s_low
    flat['actuator.stiffness.x_s_high'] = params.x_s_high
    if params.buckling is not NO_BUCKLING:
        for name in Buckling.NAMES:
            flat[f'actuator.buckling.{name}'] = getattr(params.buckling, name)
        for name, (low, high) in params.buckling.bounds:
            flat[f'actuator.buckling.bounds.{name}'] = [low, high]
    if plant is not None:
        for field in dataclasses.fields(plant.sensors):
            flat[f'actuator.sensors.{field.name}'] = getattr(plant.sensors, field.name)
        for effect, items in plant.effects:
            for key, value in items:
                flat[f'actuator.effects.{effect}.{key}'] = value
    return flat
