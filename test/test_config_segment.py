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
The segment's parameter file (bellows_ros/config/segment.py) -> model, plant, identification.

`segment.plant.*` goes to the plant, `segment.identify.*` to identification, the rest to paper A's
model; a name none of them has is refused, and so is a value one of them cannot use, in one line
naming the file and the parameter. An `--effect` parameter takes its YAML parameter's range.
"""
import dataclasses

import pytest

from bellows_ros.config import segment as config
from bellows_ros.config.ranges import RANGES
from bellows_ros.errors import ParameterError
from bellows_ros.models.segment_effects import EFFECTS

DEFAULT = config.load_segment()
FLAT = {name[len('segment.'):]: value for name, value in DEFAULT.flat().items()}


def refused(flat, *needles, source='mine.yaml'):
    """Return the one-line ParameterError of `segment_from_flat(flat, source)`."""
    with pytest.raises(ParameterError) as error:
        config.segment_from_flat(flat, source)
    message = str(error.value)
    assert '\n' not in message and message.startswith(f'{source}: '), message
    for needle in needles:
        assert needle in message, message
    return message


def test_an_effect_parameter_has_its_yaml_parameters_range_from_the_effects_lowest():
    for effect in EFFECTS:
        for key, parameter in effect.parameters.items():
            rule = RANGES['segment.' + parameter.name]
            low = rule.low if parameter.low is None else max(rule.low, parameter.low)
            assert config.effect_range(effect.name, key) == rule._replace(low=low), key
    # A friction strength is never negative (0 = off), though the file's c_fp may be.
    assert RANGES['segment.friction.c_fp'].low < 0
    assert config.effect_range('pressure_friction', 'c_fp').low == 0.0
    assert config.effect_range('natural_curvature', 'c_psi0') == RANGES['segment.restoring.c_psi0']
    assert config.effect_range('contact_hysteresis', 'anything') is None  # it has no parameter
    assert config.effect_range('no_such_effect', 'tau') is None
    assert config.effect_range('sensor_lag', 'time_constant') is None


def test_the_flat_names_split_into_three_objects_and_come_back():
    assert config.segment_from_flat(FLAT, 'mine.yaml') == DEFAULT
    changed = dict(FLAT, **{'plant.noise.p': 1500.0, 'identify.input_cutoff': 0.0,
                            'p_max': 7e5})
    loaded = config.segment_from_flat(changed)
    assert loaded.plant.noise_p == 1500.0 and loaded.identify.input_cutoff == 0.0  # 0 = off
    assert loaded.model.p_max == 7e5
    assert loaded.flat()['segment.plant.noise.p'] == 1500.0
    assert config.SegmentIdentifyParams(12.5).flat() == {'segment.identify.input_cutoff': 12.5}


@pytest.mark.parametrize('name', ['bogus', 'plant.bogus', 'identify.bogus', 'geometry.bogus',
                                  'plant.noise_p', 'plant', 'identify'])
def test_a_name_no_object_has_is_refused(name):
    # plant.noise_p is the plant's field name; the file's name is plant.noise.p.
    refused(dict(FLAT, **{name: 1.0}), f"unknown parameter 'segment.{name}'")


@pytest.mark.parametrize('name, value, needle', [
    ('p_max', 101325.0, "'segment.p_max' must exceed p0"),
    ('p0', 1.013, "'segment.p0' must be an ambient pressure"),
    ('geometry.n_lambda', 10.5, "'segment.geometry.n_lambda' must be a whole number"),
    ('ogden.mu', [4000.0], "'segment.ogden.mu' needs two values > 0"),
    ('actuator.theta', [1.0] * 7, "'segment.actuator.theta' needs 8 values (29)"),
    ('dynamics.damping', -0.1, "'segment.dynamics.damping' must be >= 0"),
    ('plant.valve_tau', 0.0, "'segment.plant.valve_tau' must be > 0"),
    ('plant.noise.psi', -1e-3, "'segment.plant.noise.psi' must be >= 0"),
    ('identify.input_cutoff', -1.0, "'segment.identify.input_cutoff' must be >= 0"),
])
def test_a_value_an_object_cannot_use_is_named_with_the_file(name, value, needle):
    refused(dict(FLAT, **{name: value}), 'parameter ' + needle)


def test_a_missing_name_is_refused():
    refused({name: value for name, value in FLAT.items() if name != 'plant.valve_tau'},
            "segment.plant: missing parameter 'valve_tau'")


def test_a_users_file_is_laid_over_the_defaults_and_named_in_errors(tmp_path):
    path = tmp_path / 'mine.yaml'
    path.write_text('/**:\n  ros__parameters:\n    segment: {p_max: 600000.0, '
                    'plant: {valve_tau: 0.08}, identify: {input_cutoff: 10.0}}\n')
    assert config.load_segment_params(path) == dataclasses.replace(DEFAULT.model, p_max=6e5)
    assert config.load_segment_plant_params(path).valve_tau == 0.08
    assert config.load_segment_identify_params(path).input_cutoff == 10.0
    # Inside each range, but not above p0: the relation is refused naming the user's file.
    path.write_text('/**:\n  ros__parameters:\n    segment: {p0: 101325.0, p_max: 100000.0}\n')
    with pytest.raises(ParameterError) as error:
        config.load_segment(path)
    assert str(error.value) == f"{path}: parameter 'segment.p_max' must exceed p0"
