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
The segment's physical effects, one module each, and their one registry (`EFFECTS`).

Every module of this package but `base` defines `EFFECT`, an instance of
`base.SegmentEffect`: adding an effect is adding a module here, with its test and its section in
docs/effects.md. The plant, the doctor, the ranges, the report and the benches iterate over
`EFFECTS`; none of them names an effect.
"""
from bellows_ros.models.effect_registry import discover
from bellows_ros.models.segment_effects.base import SegmentEffect

EFFECTS = discover(__name__, __path__, SegmentEffect)
NAMES = tuple(effect.name for effect in EFFECTS)
BY_NAME = {effect.name: effect for effect in EFFECTS}
# The parameter of each effect that says how strong it is, 0 = off (those that have one).
STRENGTHS = {effect.name: effect.strength for effect in EFFECTS if effect.strength}


def driving_torque(names):
    """Return the model output that is the driving torque with effects `names` on."""
    return next((BY_NAME[name].torque for name in names if BY_NAME[name].torque), 'tau_prev')


__all__ = ['base', 'EFFECTS', 'NAMES', 'BY_NAME', 'STRENGTHS', 'driving_torque']
