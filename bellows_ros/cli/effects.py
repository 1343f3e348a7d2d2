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

"""Parsing of `--effect NAME[:k=v,...]` arguments."""
from bellows_ros.errors import ParameterError
from bellows_ros.io.data import NUMBER


def parse_effect(text):
    """
    'air_leak:conductance=2e-9,p_ambient=101325' -> ('air_leak', {'conductance': 2e-9, ...}).

    A value is a plain decimal number (as a CSV cell is read: no `1_0`, `0x10`, `nan` or `inf`);
    a parameter given twice is refused (which one was meant cannot be known).
    """
    name, _, rest = text.partition(':')
    name = name.strip()
    if not name:
        raise ParameterError(f'--effect {text!r}: missing effect name')
    options = {}
    for item in filter(None, (part.strip() for part in rest.split(','))):
        key, sep, value = item.partition('=')
        key = key.strip()
        if not sep or not key:
            raise ParameterError(f'--effect {text!r}: expected k=v, got {item!r}')
        if key in options:
            raise ParameterError(f'--effect {text!r}: {key} is given twice')
        if not NUMBER.fullmatch(value.strip()):
            raise ParameterError(
                f'--effect {text!r}: {key} must be a finite decimal number, got {value!r}')
        options[key] = float(value)
    return name, options


def parse_effects(texts, system):
    """
    {effect: {key: value}} of the `--effect` arguments `texts` of `system`, checked before work.

    The same effect given twice is refused, as the nodes refuse it in their `effects` list; each
    value must lie in the range of the parameter it sets (`config.actuator.effect_range`,
    `config.segment.effect_range`: the nodes' ranges too).
    """
    from importlib import import_module

    from bellows_ros.config.ranges import check_effects
    effect_range = import_module(f'bellows_ros.config.{system}').effect_range
    effects = {}
    for text in texts:
        name, options = parse_effect(text)
        if name in effects:
            raise ParameterError(f'--effect {name}: given twice; give each effect once, with '
                                 'all its parameters (NAME:k=v,k=v)')
        effects[name] = options
    check_effects(effects, effect_range)
    return effects
