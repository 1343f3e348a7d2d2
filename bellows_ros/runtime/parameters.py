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
A node's parameters as a table: name, default, description, bounds; checked once, at start.

Each node module lists its parameters as a tuple of `Spec` (`PARAMETERS`), and declares them with
`Node.declare_specs(PARAMETERS)`. Every value, given or default, is then checked here, before
the node opens a device or allocates anything: a wrong type (rcl's rule: no conversion), a number
outside its bounds, a string or list element outside its choices, or a node-specific rule
(`check`) is a ParameterError that names the node and the parameter and says what is allowed.
The same table is what rclpy gets as each parameter's ParameterDescriptor (description,
range, read_only), so `ros2 param describe` shows it, and what the docs and the hostile-input
tests walk.

`read_only` is True unless the node applies a change while it runs; a parameter the node reads
once (a port, the segments) must say so, rather than accept a change that does nothing.
"""
import array
from dataclasses import dataclass
import math
from typing import Any, Callable, Optional, Sequence

from bellows_ros.errors import ParameterError


@dataclass(frozen=True)
class Spec:
    """
    One declared parameter.

    low, high: inclusive bounds of a number, or of every element of a number array (None: open);
    choices: the allowed values of a string, or of every element of a string array;
    items: (fewest, most) elements of an array; unique: no element twice;
    check: a rule of its own, `check(value) -> str` naming what is wrong ('' = fine).
    """

    name: str
    default: Any
    description: str
    low: Optional[float] = None
    high: Optional[float] = None
    choices: Sequence[Any] = ()
    items: Optional[tuple] = None
    unique: bool = False
    check: Optional[Callable[[Any], str]] = None
    read_only: bool = True

    def problem(self, value):
        """Say what is wrong with `value` for this parameter ('' when nothing is)."""
        elements = list(value) if isinstance(value, (list, tuple)) else [value]
        if isinstance(value, (list, tuple)):
            fewest, most = self.items or (0, math.inf)
            if not fewest <= len(elements) <= most:
                count = f'{fewest}' if fewest == most else (
                    f'at least {fewest}' if most == math.inf else f'{fewest} to {most}')
                return f'expected {count} elements, got {len(elements)}'
            if self.unique and len(set(elements)) != len(elements):
                return 'an element is given twice'
        for element in elements:
            if isinstance(element, float) and math.isnan(element) and not (
                    isinstance(self.default, float) and math.isnan(self.default)):
                return 'not a number (nan)'
            if isinstance(element, (int, float)) and not isinstance(element, bool):
                if (self.low is not None and element < self.low) or (
                        self.high is not None and element > self.high):
                    return f'expected {self.bounds()}, got {_number(element)}'
            if self.choices and element not in self.choices:
                return (f"expected one of {', '.join(map(repr, self.choices))}, "
                        f'got {element!r}')
        return self.check(value) if self.check else ''

    def type_name(self):
        """Return the parameter's type as docs/interfaces.md names it: 'float', 'int array', ..."""
        value = self.default[0] if isinstance(self.default, (list, tuple)) else self.default
        name = {bool: 'bool', int: 'int', float: 'float', str: 'str'}[type(value)]
        return f'{name} array' if isinstance(self.default, (list, tuple)) else name

    def allowed(self):
        """Return what values are allowed, as docs/interfaces.md says it ('—' = any)."""
        parts = []
        if self.low is not None or self.high is not None:
            parts.append(self.bounds())
        if self.choices:
            parts.append('one of ' + ', '.join(f'`{c}`' if c else "''" for c in self.choices))
        if self.items:
            fewest, most = self.items
            parts.append(f'{fewest}-{most} elements')
        if self.unique:
            parts.append('unique')
        if self.check:
            parts.append('checked')
        return '; '.join(parts) or '—'

    def bounds(self):
        """Return the bounds as text: '1..99', '>= 0', '<= 5'."""
        if self.high is None:
            return f'>= {_number(self.low)}'
        if self.low is None:
            return f'<= {_number(self.high)}'
        return f'{_number(self.low)}..{_number(self.high)}'


def descriptor_message(spec, message_class):
    """
    Return rcl_interfaces/ParameterDescriptor of a Spec: description, range, read_only.

    `message_class(ros_name)` gives the message class of a ROS type name (runtime/messages.py).
    """
    result = message_class('rcl_interfaces/msg/ParameterDescriptor')(
        name=spec.name, description=spec.description, read_only=spec.read_only)
    # rcl's ranges hold no "unset" value: a parameter whose default is nan gets none.
    unset = isinstance(spec.default, float) and math.isnan(spec.default)
    if (spec.low is None and spec.high is None) or unset:
        return result
    element = spec.default[0] if isinstance(spec.default, (list, tuple)) and spec.default \
        else spec.default
    if isinstance(element, int) and not isinstance(element, bool):
        low = -2 ** 63 if spec.low is None else int(math.ceil(spec.low))
        high = 2 ** 63 - 1 if spec.high is None else int(math.floor(spec.high))
        result.integer_range = [message_class('rcl_interfaces/msg/IntegerRange')(
            from_value=low, to_value=high, step=0)]
    elif isinstance(element, float):
        low = -math.inf if spec.low is None else float(spec.low)
        high = math.inf if spec.high is None else float(spec.high)
        result.floating_point_range = [message_class('rcl_interfaces/msg/FloatingPointRange')(
            from_value=low, to_value=high, step=0.0)]
    return result


def value_text(value):
    """Return a parameter value as docs/interfaces.md writes it (YAML-like: true, '', [1, 2])."""
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, str):
        return value or "''"
    if isinstance(value, float) and math.isnan(value):
        return 'nan'
    if isinstance(value, (list, tuple)):
        return '[' + ', '.join(value_text(v) for v in value) + ']'
    return repr(value)


def _number(value):
    return str(value) if isinstance(value, int) else f'{value:g}'


# rcl's parameter types, as rclpy names them in its errors.
def parameter_type(value: Any) -> str:
    """Return rcl's type name for a parameter value ('double', 'integer_array', ...)."""
    if isinstance(value, (list, tuple, array.array)):
        if not len(value):
            return 'array'
        kinds = {parameter_type(v) for v in value}
        return f'{kinds.pop()}_array' if len(kinds) == 1 else 'mixed array'
    for kind, name in ((bool, 'bool'), (int, 'integer'), (float, 'double'), (str, 'string')):
        if isinstance(value, kind):
            return name
    return type(value).__name__


def check_type(node_name: str, name: str, default: Any, value: Any) -> None:
    """
    Raise ParameterError when `value` does not have the type of the declared `default`.

    rcl's rule: no conversion, not even integer to double. Both runtimes apply it to every
    declaration with a value given (file or -p); `validate` applies it to a Spec's value.
    """
    if default is None:
        return
    expected, given = parameter_type(default), parameter_type(value)
    if given == expected or (given == 'array' and expected.endswith('_array')) \
            or (expected == 'array' and given.endswith('_array')):
        return
    hint = ' (write it with a decimal point)' if (expected, given) == ('double', 'integer') else ''
    raise ParameterError(f"{node_name}: parameter '{name}' must be {_article(expected)}, "
                         f'got {_article(given)} {value!r}{hint}')


def _article(kind: str) -> str:
    return ('an ' if kind[0] in 'aeiou' else 'a ') + kind.replace('_', ' ')


def validate(node_name, spec, value):
    """
    Raise ParameterError naming node and parameter when `value` is not allowed by `spec`.

    The one check of a Spec's value, at start (given or default) and for every change while the
    node runs: the type (`check_type`), then bounds, choices, elements and the Spec's own rule.
    """
    check_type(node_name, spec.name, spec.default, value)
    problem = spec.problem(value)
    if problem:
        raise ParameterError(f"{node_name}: parameter '{spec.name}' = {value!r}: {problem} "
                             f'[{spec.description}]')
