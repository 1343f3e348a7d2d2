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
Live effect strengths (models/effect_strengths.py): one number per effect, 0 = off.

The node parameter names, reading strengths from node parameters (nan = the starting strength),
and laying strengths over a plant's chosen effects (a table shaped like the actuator's).
"""
import math

import pytest

from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator_effects import STRENGTHS
from bellows_ros.models.effect_strengths import from_parameters, parameter_name, with_strengths

TABLE = {'air_leak': 'conductance', 'backlash': 'width', 'buckling': 'scale'}


def test_the_parameter_of_a_strength_names_the_effect_and_its_key():
    assert parameter_name('air_leak', 'conductance') == 'effect.air_leak.conductance'
    # every strength of the plant gets its own parameter
    names = [parameter_name(effect, key) for effect, key in STRENGTHS.items()]
    assert len(set(names)) == len(STRENGTHS)


def test_strengths_are_read_from_their_parameters_and_nan_is_the_start():
    start = {'air_leak': 2e-9, 'backlash': 1e-4, 'buckling': 1.0}
    values = {'effect.air_leak.conductance': math.nan, 'effect.backlash.width': 0.0,
              'effect.buckling.width': 5.0,     # not buckling's strength parameter
              'effect.unknown.scale': 3.0, 'p_max': 7e5}
    assert from_parameters(values, TABLE, start) == {'air_leak': 2e-9, 'backlash': 0.0}
    assert from_parameters({}, TABLE, start) == {}


def test_zero_switches_an_effect_off_and_another_value_on_or_stronger():
    chosen = {'air_leak': {'conductance': 1e-9, 'p_supply': 2e5}, 'buckling': {'scale': 1.0}}
    out = with_strengths(chosen, {'air_leak': 3e-9, 'buckling': 0.0, 'backlash': 2e-4}, TABLE,
                         'actuator')
    # the strength changes, the effect's other parameters stay
    assert out == {'air_leak': {'conductance': 3e-9, 'p_supply': 2e5},
                   'backlash': {'width': 2e-4}}
    assert type(with_strengths({}, {'backlash': 1}, TABLE, 'actuator')['backlash']['width']) \
        is float
    # the caller's dictionaries are left as they were
    assert chosen == {'air_leak': {'conductance': 1e-9, 'p_supply': 2e5},
                      'buckling': {'scale': 1.0}}
    assert with_strengths(chosen, {'backlash': 0.0}, TABLE, 'actuator') == chosen  # off: no-op


def test_an_effect_without_a_strength_is_refused_naming_those_with_one():
    with pytest.raises(ParameterError) as error:
        with_strengths({}, {'air_leek': 1e-9}, TABLE, 'actuator')
    assert str(error.value) == ("actuator effect 'air_leek' has no strength "
                                '(known: air_leak, backlash, buckling)')
