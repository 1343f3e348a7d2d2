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
sim_arm_node in the test's process: the simulated arm on a CAN bus, its segment plants.

The node is built in an rclpy context of the test's own (on a domain of its own), on python-can's
in-process `virtual` bus (a channel per test). Its simulated arm steps the plants from a 1 kHz
thread; a test that calls `step` itself closes the node first, so that nothing else steps them.
A driver on the node's bus is the graph tests' (test_graph_sample.py, ...); live strengths set
with `ros2 param set`, test_graph_live_effects.py's.
"""
import os

from polling import wait_for
import pytest

from bellows_ros.config.hardware import vent_pressure
from bellows_ros.errors import BellowsError, ParameterError
from bellows_ros.nodes.diagnostics import DiagnosticStatusWrapper
from bellows_ros.nodes.sim_arm_node import SimArmNode

FRICTION = 'effect.pressure_friction.c_fp'


@pytest.fixture
def sim(build_node, request):
    """Return `build(**parameters)`: the node on a `virtual` channel of its own."""
    def build(**parameters):
        parameters.setdefault('can.interface', 'virtual')
        parameters.setdefault('can.channel', f'sim-arm-{os.getpid()}-{request.node.name}')
        return build_node(SimArmNode, **parameters)
    return build


def angles(node, steps, setpoints):
    """Step every segment `steps` times at `setpoints` (Pa abs); return the last angles, rad."""
    for _ in range(steps):
        measured = node.step(1e-3, setpoints)
    return [psi for _, _, psi in measured]


@pytest.mark.parametrize('name, value', [('n_segments', 5), ('n_segments', 0),
                                         ('effects', ['contact_hysteresis'] * 2),
                                         (FRICTION, -1.0), ('load_torque', 1e3)])
def test_a_bad_parameter_is_refused_naming_it(sim, name, value):
    with pytest.raises(ParameterError, match=f"^sim_arm_node: parameter '{name}'"):
        sim(**{name: value})


def test_a_bus_that_cannot_be_opened_is_one_error_naming_it(sim):
    # udp_multicast needs a multicast group: refused before any socket exists
    with pytest.raises(BellowsError, match=r'^sim_arm_node: cannot open CAN bus '
                       r'udp_multicast:localhost \(.*multicast'):
        sim(**{'can.interface': 'udp_multicast', 'can.channel': 'localhost'})


@pytest.mark.realtime
def test_the_arm_holds_its_valves_vented_until_a_host_speaks(sim):
    node = sim(n_segments=2)
    assert node.link == f'virtual:{node.get_parameter("can.channel").value}'
    assert wait_for(lambda: node.sim.read() is not None)  # it samples
    # no host heartbeat yet: the safe state, every chamber at ambient
    assert node.sim.vented and node.sim.setpoints == (vent_pressure(),) * 4
    status = DiagnosticStatusWrapper()
    node.diagnose_plant(status)
    values = dict(status.values)
    assert {'segment_1.psi', 'segment_2.psi'} <= set(values) and 'segment_3.psi' not in values
    node.close()
    assert wait_for(lambda: node.sim.read() is None)  # the arm is silent


@pytest.mark.realtime
def test_each_segment_is_a_plant_of_its_own_and_takes_the_strengths_given(sim):
    node = sim(n_segments=3, **{FRICTION: 0.01})
    assert [p.strengths()['pressure_friction'] for p in node.plants] == [0.01] * 3
    assert node.start_strengths['pressure_friction'] == 0.0  # what nan would have kept
    node.close()
    # the same plant and valves, but each segment's sensor noise has a seed of its own
    measured = node.step(1e-3, (2e5,) * 6)
    assert len(measured) == 3 and len({p1 for p1, _, _ in measured}) == 3


@pytest.mark.realtime
def test_a_load_torque_set_live_bends_every_segment_its_way_from_the_next_step(sim):
    node = sim(n_segments=2)
    node.close()  # from here only this test steps the plants
    vented = (vent_pressure(),) * 4
    free = angles(node, 300, vented)
    node.on_parameters({'load_torque': 0.5})
    assert node.load_torque == 0.5
    assert all(p > f + 0.02 for p, f in zip(angles(node, 300, vented), free))
    node.on_parameters({'load_torque': -0.5})
    assert all(p < f - 0.02 for p, f in zip(angles(node, 600, vented), free))


@pytest.mark.realtime
def test_with_sim_time_the_plants_time_goes_out_on_clock(sim):
    node = sim(n_segments=1, use_sim_time=True, clock_rate=500.0)  # every 2nd step
    node.close()
    sent = []
    node.clock_pub = type('Recorder', (), {'publish': staticmethod(sent.append)})()
    angles(node, 6, (vent_pressure(),) * 2)
    assert len(sent) == 3
    stamps = [m.clock.sec + m.clock.nanosec * 1e-9 for m in sent]
    assert stamps[-1] <= node.plants[0].t and stamps[2] - stamps[0] == pytest.approx(4e-3)
