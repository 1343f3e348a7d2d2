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
Live effect strengths (nodes/live_effects.py) of a node in this process, on real plants.

A small bellows node takes the `LiveEffectStrengths` mixin as the simulated devices do, over two
plants of the same system (actuator or segment), its `effect.<effect>.<key>` parameters without
bounds of their own, so that what the plant refuses is the plant's to say. A change goes through
`set_parameters` as `ros2 param set` sends it: nan stands for the start strength, 0 switches an
effect off, every plant takes the new strengths, a strength the plant cannot use is refused with
the plant's reason and reaches no plant, a change of another parameter hands them nothing.
"""
import functools
import math

import pytest
from rclpy.parameter import Parameter

from bellows_ros.config.actuator import load_actuator
from bellows_ros.config.segment import load_segment
from bellows_ros.models import actuator_plant, segment_plant
from bellows_ros.models.effect_strengths import parameter_name
from bellows_ros.nodes.live_effects import LiveEffectStrengths
from bellows_ros.runtime.node import Node
from bellows_ros.runtime.parameters import Spec

LEAK = parameter_name('air_leak', 'conductance')
BACKLASH = parameter_name('backlash', 'width')
LAG = parameter_name('sensor_lag', 'tau')
START_LEAK = 2e-11   # m³/(s·Pa): the leak the actuator plants start with


class Recording:
    """A plant that keeps every set of strengths it was handed."""

    def __init__(self, plant):
        self.plant, self.handed = plant, []

    def effects_for(self, strengths):
        return self.plant.effects_for(strengths)

    def set_strengths(self, strengths):
        self.handed.append(dict(strengths))
        self.plant.set_strengths(strengths)

    def strengths(self):
        return self.plant.strengths()


def actuator_plants():
    params, plant = load_actuator()
    chosen = actuator_plant.effect_parameters(plant, {'air_leak': {'conductance': START_LEAK}})
    plants = [actuator_plant.ActuatorPlant(params, plant, effects=chosen, seed=seed)
              for seed in (1, 2)]
    return actuator_plant.STRENGTHS, actuator_plant.strengths_of(chosen), plants


def segment_plants():
    params, plant, _ = load_segment()
    plants = [segment_plant.SegmentPlant(params, plant, seed=seed) for seed in (1, 2)]
    return segment_plant.STRENGTHS, plants[0].strengths(), plants


class Live(LiveEffectStrengths, Node):
    """A simulated device node in small: its strengths and one other live parameter."""

    def __init__(self, table, start, plants, **kwargs):
        super().__init__('live', **kwargs)
        self.strength_table, self.start_strengths = table, start
        self.plants = [Recording(plant) for plant in plants]
        self.declare_specs((
            Spec('load_torque', 0.0, 'another live parameter, N·m', read_only=False),
            *(Spec(parameter_name(effect, key), math.nan, f'strength of {effect}',
                   read_only=False) for effect, key in table.items())))
        self.watch_parameters()

    def effect_plants(self):
        return self.plants


@pytest.fixture
def live(build_node):
    """Build a Live node over given plants (conftest's `build_node`)."""
    return lambda table_start_plants: build_node(functools.partial(Live, *table_start_plants))


def change(node, name, value):
    return node.set_parameters([Parameter(name, value=value)])[0]


def test_given_strengths_are_the_strength_parameters_nan_the_start_value(live):
    node = live(actuator_plants())
    assert node.given_strengths({LEAK: math.nan, BACKLASH: 1e-4, 'load_torque': 0.5}) == \
        {'air_leak': START_LEAK, 'backlash': 1e-4}
    assert node.given_strengths({'load_torque': 0.5}) == {}


@pytest.mark.parametrize('plants, name, effect, value', [
    (actuator_plants, BACKLASH, 'backlash', 1e-4),
    (segment_plants, LAG, 'sensor_lag', 0.02),
])
def test_every_plant_takes_a_new_strength_and_0_switches_it_off(
        live, plants, name, effect, value):
    node = live(plants())
    assert change(node, name, value).successful
    assert [plant.strengths()[effect] for plant in node.plants] == [value, value]
    assert change(node, name, 0.0).successful
    assert [plant.strengths()[effect] for plant in node.plants] == [0.0, 0.0]
    assert [plant.handed for plant in node.plants] == [[{effect: value}, {effect: 0.0}]] * 2


def test_nan_gives_an_effect_back_its_start_strength(live):
    node = live(actuator_plants())
    assert change(node, LEAK, 5e-11).successful
    assert node.plants[1].strengths()['air_leak'] == 5e-11
    assert change(node, LEAK, math.nan).successful
    assert [plant.strengths()['air_leak'] for plant in node.plants] == [START_LEAK] * 2


@pytest.mark.parametrize('plants, name, words', [
    (actuator_plants, LEAK, "effect 'air_leak': parameter 'conductance' must be finite and >= 0"),
    (segment_plants, LAG, "segment effect 'sensor_lag': parameter 'tau' must be >= 0"),
])
def test_a_strength_the_plant_cannot_use_is_refused_in_its_words(live, plants, name, words):
    node = live(plants())
    before = [plant.strengths() for plant in node.plants]
    result = change(node, name, -1.0)
    assert not result.successful and words in result.reason, result.reason
    assert node.parameter_problem({name: -1.0}) == result.reason
    assert node.parameter_problem({name: 0.0}) == ''
    assert [plant.strengths() for plant in node.plants] == before
    assert all(plant.handed == [] for plant in node.plants)
    assert math.isnan(node.get_parameter(name).value)


def test_another_parameter_hands_the_plants_nothing(live):
    node = live(actuator_plants())
    assert change(node, 'load_torque', 0.5).successful
    assert all(plant.handed == [] for plant in node.plants)


def test_the_log_says_which_effects_are_on_from_the_next_step(live, capfd):
    node = live(actuator_plants())
    change(node, BACKLASH, 1e-4)
    change(node, LEAK, 0.0)
    change(node, BACKLASH, 0.0)
    said = 'effect strengths from the next step: '
    lines = [line[line.index(said) + len(said):] for line in capfd.readouterr().err.splitlines()
             if said in line]   # rcutils' console line, whatever its format before the message
    assert lines == ['air_leak 2e-11, backlash 0.0001', 'backlash 0.0001', 'none']
