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
section in docs/doctor.md). The plant, the doctor, the live doctor, the YAML's ranges and the
benches iterate over `EFFECTS`; none of them names an effect.
"""
import importlib
import pkgutil

from bellows_ros.models.actuator_effects.base import ActuatorEffect


def _discover():
    effects = []
    for module in pkgutil.iter_modules(__path__):
        if module.name == 'base':
            continue
        effect = importlib.import_module(f'{__name__}.{module.name}').EFFECT
        if not isinstance(effect, ActuatorEffect) or effect.name != module.name:
            raise TypeError(f'{__name__}.{module.name}.EFFECT must be an ActuatorEffect '
                            f'named {module.name!r}')
        effects.append(effect)
    return tuple(sorted(effects, key=lambda e: (e.rank, e.name)))


EFFECTS = _discover()
NAMES = tuple(effect.name for effect in EFFECTS)
BY_NAME = {effect.name: effect for effect in EFFECTS}
# The parameter of each effect that says how strong it is, 0 = off.
STRENGTHS = {effect.name: effect.strength for effect in EFFECTS}

__all__ = ['base', 'EFFECTS', 'NAMES', 'BY_NAME', 'STRENGTHS']
