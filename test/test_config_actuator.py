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
The actuator's parameter file (bellows_ros/config/actuator.py) -> model and plant objects.

Each effect's parameters carry their own range (`effect_range`), and the file's open section
`actuator.effects.*` is checked by name, kind and range; relations between parameters that the
equations need are refused before any object is built. Every refusal is one line naming the file
and the parameter.
"""
import dataclasses

import pytest

from bellows_ros.config import actuator as config
from bellows_ros.config.ranges import Range
from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator import NO_BUCKLING
from bellows_ros.models.actuator_effects import EFFECTS

DEFAULT = config.load_actuator()
DRIVE = DEFAULT.plant.drive


def user_file(tmp_path, body):
    """Write a user's parameter file with `body` (flow YAML) under `actuator:`."""
    path = tmp_path / 'mine.yaml'
    path.write_text('/**:\n  ros__parameters:\n    actuator: ' + body + '\n')
    return path


def refused(call, *needles):
    """Return the one-line ParameterError of `call()`, which must hold every needle."""
    with pytest.raises(ParameterError) as error:
        call()
    message = str(error.value)
    assert '\n' not in message, message
    for needle in needles:
        assert needle in message, message
    return message


def test_each_effect_parameter_has_its_own_range_and_nothing_else_has_one():
    for effect in EFFECTS:
        for key, parameter in effect.parameters.items():
            assert config.effect_range(effect.name, key) == Range(
                parameter.low, parameter.high, parameter.unit, parameter.hint)
    assert config.effect_range('air_leak', 'conductanc') is None
    assert config.effect_range('no_such_effect', 'conductance') is None
    assert config.effect_range('air_leak', '') is None
    # The heat exchange's ambient is a temperature in K: its range says what a mistake looks like.
    rule = config.effect_range('heat_exchange', 't_ambient')
    assert rule.low <= 293.15 <= rule.high and not rule.low <= 20.0 <= rule.high
    assert '°C' in rule.hint


def test_a_files_effects_reach_the_plant_as_sorted_floats(tmp_path):
    path = user_file(tmp_path, '{effects: {sensor_drift: {rate: 5}, '
                               'air_leak: {conductance: 2.0e-11}}}')
    loaded = config.load_actuator(path)
    assert loaded.plant.effects == (('air_leak', (('conductance', 2e-11),)),
                                    ('sensor_drift', (('rate', 5.0),)))
    assert isinstance(loaded.plant.effects[1][1][0][1], float)  # 5 in the file, a float here
    assert loaded.model == DEFAULT.model  # the effects change the plant only
    assert DEFAULT.plant.effects == ()    # none unless a file names them


@pytest.mark.parametrize('body, needles', [
    ('{effects: {air_leak: {conductanc: 2.0e-11}}}',
     ["unknown parameter 'actuator.effects.air_leak.conductanc'", 'docs/effects.md']),
    ('{effects: {no_such_effect: {scale: 1.0}}}',
     ["unknown parameter 'actuator.effects.no_such_effect.scale'"]),
    ('{effects: {air_leak: [1.0, 2.0]}}', ["unknown parameter 'actuator.effects.air_leak'"]),
    ('{effects: {air_leak: {conductance: leaky}}}',
     ["'actuator.effects.air_leak.conductance' must be a number, got 'leaky'"]),
    ('{effects: {air_leak: {conductance: true}}}',
     ["'actuator.effects.air_leak.conductance' must be a number, got True"]),
    ('{effects: {heat_exchange: {t_ambient: 20.0}}}',
     ["'actuator.effects.heat_exchange.t_ambient' is 20, outside its physical range 200..400 K",
      'was it written in °C?']),
    ('{effects: {backlash: {width: 2.0}}}',
     ["'actuator.effects.backlash.width' is 2, outside its physical range 0..0.01 m"]),
])
def test_the_open_effects_section_is_checked_by_name_kind_and_range(tmp_path, body, needles):
    path = user_file(tmp_path, body)
    message = refused(lambda: config.load_actuator(path), *needles)
    assert message.startswith(f'{path}: ')


def test_the_flat_names_are_the_inverse_of_actuator_from_flat():
    effects = (('air_leak', (('conductance', 3e-11),)), ('backlash', (('width', 2e-4),)))
    plant = dataclasses.replace(DEFAULT.plant, effects=effects)
    whole = config.ActuatorConfig(DEFAULT.model, plant)
    flat = whole.flat()
    assert flat['actuator.effects.backlash.width'] == 2e-4
    assert not any('drive' in name for name in flat)  # hardware.yaml's, not this file's
    assert config.actuator_from_flat(flat, DRIVE) == whole
    # Without buckling the spring does not buckle, and the file says nothing of it.
    plain = {name: value for name, value in flat.items() if '.buckling.' not in name}
    loaded = config.actuator_from_flat(plain, DRIVE)
    assert loaded.model.buckling is NO_BUCKLING
    assert config.params_to_flat(loaded.model, loaded.plant) == plain
    assert config.params_to_flat(loaded.model) == {
        name: value for name, value in plain.items()
        if not name.startswith(('actuator.sensors.', 'actuator.effects.'))}


@pytest.mark.parametrize('name, value, needle', [
    ('gas.x_c_ref', 0.05, "'actuator.gas.x_c_ref' must lie within the air chamber travel"),
    ('stiffness.x_s_high', -0.001, "'actuator.stiffness.x_s_high' must exceed x_s_low"),
    ('stiffness.x_s_low', -0.05, "'actuator.stiffness.x_s_low' must lie within the spring "
                                 'travel'),
    ('sensors.force_noise', -0.01, "'actuator.sensors.force_noise' must be >= 0"),
    ('gas.v_tube', -1e-6, "'actuator.gas.v_tube' must be >= 0"),
    ('spring.wall', -0.001, "'actuator.spring.wall' must be >= 0"),
    ('spring.n', True, "'actuator.spring.n' must be a whole number of segments in 1..1000, got "
                       'True'),
    ('air_chamber.r_small', 0.0, "'actuator.air_chamber.r_big' must exceed r_small > 0"),
    ('gas.p_ref', 'high', "'actuator.gas.p_ref' must be a number, got 'high'"),
])
def test_a_value_the_equations_cannot_use_is_named(name, value, needle):
    # Straight from flat names: the relations are this module's, not the ranges' (ranges.py).
    flat = dict(DEFAULT.flat(), **{f'actuator.{name}': value})
    refused(lambda: config.actuator_from_flat(flat, DRIVE, 'mine.yaml'), 'mine.yaml: parameter '
            + needle)


@pytest.mark.parametrize('change, needle', [
    ({'actuator.bogus.x': 1.0}, "mine.yaml: unknown parameter 'actuator.bogus'"),
    ({'actuator.sensors.bogus': 1.0}, "mine.yaml: actuator.sensors: unknown parameter 'bogus'"),
    ({'actuator.force.f_mts': None}, "mine.yaml: missing parameter 'actuator.force.f_mts'"),
])
def test_an_unknown_or_missing_name_is_refused_naming_the_file(change, needle):
    flat = {**DEFAULT.flat(), **change}
    flat = {name: value for name, value in flat.items() if value is not None}
    refused(lambda: config.actuator_from_flat(flat, DRIVE, 'mine.yaml'), needle)


def test_a_parameter_objects_own_refusal_gets_the_files_name(tmp_path):
    # Buckling checks its value against its bounds but knows no file: the loader adds it, once.
    path = user_file(tmp_path, '{buckling: {onset_width: 0.6}}')
    message = refused(lambda: config.load_actuator(path),
                      "parameter 'actuator.buckling.onset_width': 0.6 is outside its physical "
                      'range [0.02, 0.5]')
    assert message.startswith(f'{path}: ') and message.count(str(path)) == 1


def test_the_loaders_give_the_parts_of_one_file(tmp_path):
    path = user_file(tmp_path, '{gas: {v_tube: 2.0e-05}, sensors: {pressure_noise: 20.0}}')
    assert config.load_actuator_params(path).v_tube == 2.0e-05
    assert config.load_actuator_plant_params(path).sensors.pressure_noise == 20.0
    assert config.load_actuator_params(path).p_ref == DEFAULT.model.p_ref  # the rest: defaults
    assert config.load_actuator_plant_params().drive == DRIVE
