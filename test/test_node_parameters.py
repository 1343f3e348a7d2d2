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
Every node parameter is checked at start against its table (runtime/parameters.py).

Walks the `PARAMETERS` table of every node (and runtime/realtime.py's), makes bad values from
each Spec (below, above, a wrong choice, too few or too many elements, an element twice, nan),
and checks that each is refused with a ParameterError naming the node and the parameter; then
starts every node with one bad value: one line on stderr, exit status 2, nothing written.
"""
import importlib
import math
from pathlib import Path
import pkgutil
import subprocess
import sys

from hypothesis import given, settings, strategies as st
from node_processes import free_domain, node_env
import pytest

from bellows_ros import nodes
from bellows_ros.errors import ParameterError
from bellows_ros.runtime import realtime
from bellows_ros.runtime.parameters import validate

BIN = Path(sys.executable).parent


def tables():
    """(owner, PARAMETERS) of every node module that has a table, and of realtime."""
    found = [('realtime', realtime.PARAMETERS)]
    for module in pkgutil.iter_modules(nodes.__path__):
        loaded = importlib.import_module(f'bellows_ros.nodes.{module.name}')
        if hasattr(loaded, 'PARAMETERS'):
            found.append((module.name, loaded.PARAMETERS))
    return found


def bad_values(spec):
    """Values of the parameter's type that its Spec must refuse."""
    array = isinstance(spec.default, list)
    element = spec.default[0] if array and spec.default else spec.default
    values = []
    if isinstance(element, (int, float)) and not isinstance(element, bool):
        kind = type(element)
        if spec.low is not None:
            values.append(kind(spec.low - 1) if kind is int else spec.low - abs(spec.low) - 1.0)
        if spec.high is not None:
            values.append(kind(spec.high + 1) if kind is int else spec.high * 2 + 1.0)
        if kind is float and not math.isnan(element):
            values.append(math.nan)
    if spec.choices:
        values.append('no_such_choice')
    values = [[value] for value in values] if array else values
    if array and spec.items:
        fewest, most = spec.items
        if fewest > 0:
            values.append([])
        values.append([element] * (most + 1))
    if array and spec.unique and spec.default:
        values.append([element, element])
    return values


CASES = [(owner, spec, value) for owner, table in tables() for spec in table
         for value in bad_values(spec)]


def test_every_node_with_parameters_has_a_table():
    owners = {owner for owner, _ in tables()}
    for module in pkgutil.iter_modules(nodes.__path__):
        if module.name.endswith('_node'):
            assert module.name in owners


@pytest.mark.parametrize('owner, spec, value', CASES,
                         ids=[f'{o}:{s.name}={v!r}' for o, s, v in CASES])
def test_a_bad_value_is_refused_naming_the_parameter(owner, spec, value):
    with pytest.raises(ParameterError, match=f"{owner}: parameter '{spec.name}'"):
        validate(owner, spec, value)


@pytest.mark.parametrize('owner, spec', [(o, s) for o, t in tables() for s in t],
                         ids=[f'{o}:{s.name}' for o, t in tables() for s in t])
def test_every_default_is_allowed_and_described(owner, spec):
    validate(owner, spec, spec.default)
    assert spec.description.strip()


def values_like(default):
    """Any value of the parameter's type (a value of another type never gets this far)."""
    element = default[0] if isinstance(default, list) else default
    one = (st.booleans() if isinstance(element, bool) else
           st.integers(-2 ** 63, 2 ** 63 - 1) if isinstance(element, int) else
           st.floats(allow_nan=True) if isinstance(element, float) else st.text(max_size=8))
    return st.lists(one, max_size=8) if isinstance(default, list) else one


@settings(max_examples=300, deadline=None)
@given(st.sampled_from([spec for _, table in tables() for spec in table]).flatmap(
    lambda spec: st.tuples(st.just(spec), values_like(spec.default))))
def test_any_value_is_allowed_or_refused_with_a_parameter_error(case):
    """No value of the type makes the check itself fail: it allows, or names what is wrong."""
    spec, value = case
    try:
        validate('node', spec, value)
    except ParameterError as error:
        assert f"parameter '{spec.name}'" in str(error)


# One bad value per node, as a user gives it (-p name:=value), through the node's start-up.
STARTS = [
    ('model_node', 'segments:=[5]', 'segments'),
    ('model_node', 'latency_budget:=0.0', 'latency_budget'),
    ('arm_controller_node', 'control_every:=0', 'control_every'),
    ('arm_controller_node', 'feedforward:=paper_b', 'feedforward'),
    ('stiffness_controller_node', 'control_every:=0', 'control_every'),
    ('sim_arm_node', 'n_segments:=5', 'n_segments'),
    ('sim_actuator_node', 'seed:=-1', 'seed'),
    ('scenario_node', 'duration:=-1.0', 'duration'),
    ('model_node', 'realtime_priority:=100', 'realtime_priority'),
    ('driver_node', 'arm.n_segments:=5', 'arm.n_segments'),
    ('driver_node', 'actuator.port:=/tmp', 'actuator.port'),
    ('driver_node', 'startup_timeout:=0.0', 'startup_timeout'),
]


@pytest.mark.slow
@pytest.mark.parametrize('node, setting, name', STARTS, ids=[f'{n}:{s}' for n, s, _ in STARTS])
def test_a_node_given_a_bad_value_says_so_in_one_line_and_exits_2(
        node, setting, name, tmp_path):
    env = node_env(ROS_DOMAIN_ID=free_domain())
    result = subprocess.run([str(BIN / node), '--ros-args', '-p', setting], capture_output=True,
                            text=True, timeout=60, env=env, cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert f"parameter '{name}'" in lines[0]
    assert list(tmp_path.iterdir()) == []  # nothing written
