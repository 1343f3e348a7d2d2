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


def parse_effect(text):
    """'air_leak:conductance=2e-9,p_ambient=101325' -> ('air_leak', {'conductance': 2e-9, ...})."""
    name, _, rest = text.partition(':')
    name = name.strip()
    if not name:
        raise ParameterError(f'--effect {text!r}: missing effect name')
    options = {}
    for item in filter(None, (part.strip() for part in rest.split(','))):
        key, sep, value = item.partition('=')
        if not sep or not key.strip():
            raise ParameterError(f'--effect {text!r}: expected k=v, got {item!r}')
        try:
            options[key.strip()] = float(value)
        except ValueError:
            raise ParameterError(
                f'--effect {text!r}: {key.strip()} must be a number, got {value!r}') from None
    return name, options
