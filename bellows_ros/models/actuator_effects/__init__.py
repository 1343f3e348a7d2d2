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
The actuator's physical effects, one module each, and their one registry (`EFFECTS`).

Every module of this package but `base` defines `EFFECT`, an instance of
`base.ActuatorEffect`: adding an effect is adding a module here (with its test and its
section in docs/effects.md). The plant, the doctor, the live doctor, the ranges and the
benches iterate over `EFFECTS`; none of them names an effect.
"""
from bellows_ros.models.actuator_effects.base import ActuatorEffect
from bellows_ros.models.effect_registry import discover

EFFECTS = discover(__name__, __path__, ActuatorEffect)
NAMES = tuple(effect.name for effect in EFFECTS)
BY_NAME = {effect.name: effect for effect in EFFECTS}
# The parameter of each effect that says how strong it is, 0 = off.
STRENGTHS = {effect.name: effect.strength for effect in EFFECTS}

__all__ = ['base', 'EFFECTS', 'NAMES', 'BY_NAME', 'STRENGTHS']
