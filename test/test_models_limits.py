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
The upper bounds that size a computation (models/limits.py), and that loading enforces them.

Wide enough for any pneumatic bellows (the default device and the papers' lie well inside), tight
enough that a unit mistake is refused with the parameter's name: a length in mm, an ambient
pressure in bar, kPa or hPa, a strain profile or a convolution count of absurd size.
"""
import pytest

from bellows_ros.config.actuator import load_actuator_params
from bellows_ros.config.segment import load_segment_params
from bellows_ros.errors import ParameterError
from bellows_ros.models.limits import (AMBIENT_RANGE, MAX_CONVOLUTIONS, MAX_LENGTH,
                                       MAX_PROFILE_SAMPLES, TIME_CONSTANT)

SEGMENT = load_segment_params()
ACTUATOR = load_actuator_params()
ATMOSPHERE = 101325.0  # Pa


def test_the_default_devices_lie_inside_every_bound():
    lengths = [SEGMENT.geometry_l0, SEGMENT.geometry_s0, SEGMENT.geometry_sa_max]
    for bellows in (ACTUATOR.chamber, ACTUATOR.spring):
        lengths += [bellows.r_big, bellows.r_small, bellows.h0, bellows.n * bellows.h0]
        assert 1 <= bellows.n <= MAX_CONVOLUTIONS
    assert all(0 < length <= MAX_LENGTH for length in lengths)
    assert 1 <= SEGMENT.geometry_n_lambda <= MAX_PROFILE_SAMPLES
    assert AMBIENT_RANGE[0] <= SEGMENT.p0 <= AMBIENT_RANGE[1]


def test_every_ambient_pressure_on_earth_is_one_and_no_other_unit_of_it():
    # sea level; 5000 m up (about 54 kPa); the Dead Sea shore, 430 m below sea level
    for pressure in (ATMOSPHERE, 5.4e4, 1.067e5):
        assert AMBIENT_RANGE[0] <= pressure <= AMBIENT_RANGE[1]
    # one atmosphere in bar, kPa, hPa and psi
    for mistake in (ATMOSPHERE / 1e5, ATMOSPHERE / 1e3, ATMOSPHERE / 1e2, 14.696):
        assert not AMBIENT_RANGE[0] <= mistake <= AMBIENT_RANGE[1]


def test_lengths_written_in_millimetres_are_past_the_longest():
    for length in (SEGMENT.geometry_l0, ACTUATOR.chamber.h0, ACTUATOR.spring.r_big):
        assert length <= MAX_LENGTH < 1000 * length


def test_time_constants_span_piezo_valves_to_insulated_chambers():
    assert TIME_CONSTANT[0] <= 1e-4 and 3600.0 <= TIME_CONSTANT[1]


def segment_yaml(path, key, value):
    path.write_text(f'/**:\n  ros__parameters:\n    segment:\n      {key}: {value}\n')
    return load_segment_params(path)


def actuator_yaml(path, key, value):
    path.write_text(f'/**:\n  ros__parameters:\n    actuator:\n      {key}: {value}\n')
    return load_actuator_params(path)


@pytest.mark.parametrize('load, key, value, name', [
    (segment_yaml, 'p0', 1.01325, 'segment.p0'),                       # bar
    (segment_yaml, 'p0', 101.325, 'segment.p0'),                       # kPa
    (segment_yaml, 'p0', 1013.25, 'segment.p0'),                       # hPa
    (segment_yaml, 'geometry:\n        l0', 50.0, 'segment.geometry.l0'),           # mm
    (segment_yaml, 'geometry:\n        n_lambda', 10 ** 9, 'segment.geometry.n_lambda'),
    (segment_yaml, 'plant:\n        valve_tau', 1e-6, 'segment.plant.valve_tau'),
    (actuator_yaml, 'air_chamber:\n        h0', 14.92, 'actuator.air_chamber.h0'),   # mm
    (actuator_yaml, 'spring:\n        r_big', 18.47, 'actuator.spring.r_big'),       # mm
    (actuator_yaml, 'air_chamber:\n        n', 10 ** 6, 'actuator.air_chamber.n'),
], ids=['p0-bar', 'p0-kPa', 'p0-hPa', 'l0-mm', 'n_lambda', 'valve_tau', 'h0-mm', 'r_big-mm',
        'convolutions'])
def test_a_value_past_its_bound_is_refused_at_load_naming_it(tmp_path, load, key, value, name):
    with pytest.raises(ParameterError, match=f"'{name}' is .* outside its physical range") \
            as error:
        load(tmp_path / 'user.yaml', key, value)
    assert '\n' not in str(error.value)


def test_the_bounds_themselves_are_accepted(tmp_path):
    assert segment_yaml(tmp_path / 'a.yaml', 'geometry:\n        n_lambda',
                        MAX_PROFILE_SAMPLES).geometry_n_lambda == MAX_PROFILE_SAMPLES
    assert segment_yaml(tmp_path / 'b.yaml', 'p0', AMBIENT_RANGE[0]).p0 == AMBIENT_RANGE[0]
