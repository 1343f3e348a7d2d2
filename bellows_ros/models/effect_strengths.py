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
Live effect strengths of a simulated plant: one number per effect, 0 = off.

Each plant names, per effect that has one, the parameter that is its strength
(`actuator_plant.STRENGTHS`, `segment_plant.STRENGTHS`: {effect: parameter}). The simulated
devices' nodes offer them as live node parameters named `parameter_name(effect, key)`, nan
standing for the value the plant started with.
"""
import math

from bellows_ros.errors import ParameterError


def parameter_name(effect, key):
    """Return the node parameter of an effect's strength: `effect.<effect>.<key>`."""
    return f'effect.{effect}.{key}'


def from_parameters(values, table, start):
    """
    Return {effect: strength} of the strength parameters among `values` ({name: value}).

    `table` is the plant's {effect: strength parameter}; a nan value stands for `start[effect]`,
    the strength the plant started with. Parameters not in `values` are left out.
    """
    strengths = {}
    for effect, key in table.items():
        value = values.get(parameter_name(effect, key))
        if value is not None:
            strengths[effect] = start[effect] if math.isnan(value) else value
    return strengths


def with_strengths(chosen, strengths, table, system):
    """
    Return effects `chosen` ({name: {parameter: value}}) with new strengths {effect: value}.

    0 switches an effect off; another value switches it on (its other parameters as the plant
    fills them in from its YAML) or changes its strength. An effect not in `table` (the plant's
    {effect: strength parameter}) is a ParameterError naming the `system`'s effects that have one.
    """
    chosen = {name: dict(values) for name, values in chosen.items()}
    for name, value in strengths.items():
        if name not in table:
            raise ParameterError(f"{system} effect '{name}' has no strength (known: "
                                 f"{', '.join(table)})")
        if value == 0.0:
            chosen.pop(name, None)
        else:
            chosen[name] = {**chosen.get(name, {}), table[name]: float(value)}
    return chosen
