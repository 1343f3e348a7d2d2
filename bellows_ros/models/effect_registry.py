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
The one way a package of effects becomes a registry: every module but `base` defines `EFFECT`.

`models.actuator_effects` and `models.segment_effects` are such packages. Adding an effect is
adding a module; nothing else lists it.
"""
import importlib
import pkgutil


def discover(package, path, kind):
    """
    Return the `EFFECT` of every module of `package` (its `__name__`, `__path__`), in rank order.

    Each must be an instance of `kind` named as its module, with a rank of its own.
    """
    effects = []
    for module in pkgutil.iter_modules(path):
        if module.name == 'base':
            continue
        effect = importlib.import_module(f'{package}.{module.name}').EFFECT
        if not isinstance(effect, kind) or effect.name != module.name:
            raise TypeError(f'{package}.{module.name}.EFFECT must be a {kind.__name__} named '
                            f'{module.name!r}')
        effects.append(effect)
    ranks = [effect.rank for effect in effects]
    if len(set(ranks)) != len(ranks):
        raise TypeError(f'{package}: two effects share a rank ({sorted(ranks)})')
    return tuple(sorted(effects, key=lambda effect: effect.rank))
