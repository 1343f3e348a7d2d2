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
sim_actuator_node in the test's process: the simulated board behind its port, the plant it steps.

The node is built in an rclpy context of the test's own (on a domain of its own), its port a path
in tmp_path. Its board steps the plant from a 1 kHz thread; a test that calls `step` itself
closes the node first, so that nothing else steps the plant. The driver reading the board over
its port is test_graph_stiffness.py's; live effect strengths, test_graph_live_effects.py's.
"""
import math
import os
import stat
import time

from polling import wait_for
import pytest

from bellows_ros.errors import ParameterError
from bellows_ros.nodes.diagnostics import DiagnosticStatusWrapper
from bellows_ros.nodes.sim_actuator_node import SimActuatorNode

LEAK = 'effect.air_leak.conductance'


@pytest.fixture
def sim(build_node, tmp_path):
    """Return `build(**parameters)`: the node on port tmp_path/board (conftest's `build_node`)."""
    def build(**parameters):
        parameters.setdefault('port', str(tmp_path / 'board'))
        return build_node(SimActuatorNode, **parameters)
    return build


def plant_values(node):
    """Return the plant's /diagnostics values of `node`, by key."""
    status = DiagnosticStatusWrapper()
    node.diagnose_plant(status)
    return dict(status.values)


@pytest.mark.parametrize('name, value', [('port', ''), ('effects', ['no_such_effect']),
                                         (LEAK, 1.0), ('spring.period', 0.0)])
def test_a_bad_parameter_is_refused_naming_it_before_any_board_is_made(
        sim, tmp_path, name, value):
    with pytest.raises(ParameterError, match=f"^sim_actuator_node: parameter '{name}'"):
        sim(**{name: value})
    assert list(tmp_path.iterdir()) == []


def test_a_port_path_that_is_taken_is_refused_and_left_as_it_is(sim, tmp_path):
    taken = tmp_path / 'board'
    taken.write_text('not a board')
    with pytest.raises(ParameterError, match=f'^port {taken}: a file exists there'):
        sim()
    assert taken.read_text() == 'not a board'


@pytest.mark.realtime
def test_the_board_answers_on_its_port_until_the_node_closes(sim, tmp_path):
    port = tmp_path / 'board'
    node = sim()
    # the port is a link to the board's pseudo-terminal, as /dev/serial/by-id links a board
    assert port.is_symlink() and stat.S_ISCHR(os.stat(port).st_mode)
    assert node.board.port == str(port)
    assert wait_for(lambda: node.plant.t > 0.0)  # the board steps the plant
    values = plant_values(node)
    assert float(values['t_plant']) > 0.0 and values[LEAK] == '0'  # the baseline: no leak
    node.close()
    assert not os.path.lexists(port)  # the driver sees the board gone
    t = node.plant.t
    time.sleep(0.05)
    assert node.plant.t == t  # and the plant steps no more


@pytest.mark.realtime
def test_a_strength_given_at_start_switches_its_effect_on_and_zero_keeps_it_off(sim, tmp_path):
    node = sim(**{LEAK: 2e-10})
    assert node.plant.effects['air_leak']['conductance'] == 2e-10
    assert plant_values(node)[LEAK] == '2e-10'
    node.close()
    # named in `effects` but given strength 0: off
    node = sim(port=str(tmp_path / 'board2'), effects=['air_leak'], **{LEAK: 0.0})
    assert 'air_leak' not in node.plant.effects


@pytest.mark.realtime
def test_the_spring_is_moved_sinusoidally_between_zero_and_the_amplitude(sim):
    amplitude, period = 0.01, 0.5
    node = sim(**{'spring.amplitude': amplitude, 'spring.period': period})
    node.close()  # from here only this test steps the plant
    positions = []
    for _ in range(600):
        t = node.plant.t
        positions.append(node.step(1e-3, 0.0).x_s)
        assert positions[-1] == pytest.approx(
            0.5 * amplitude * (1.0 - math.cos(2.0 * math.pi * t / period)), abs=1e-12)
    assert min(positions) >= 0.0 and max(positions) == pytest.approx(amplitude, rel=1e-3)


@pytest.mark.realtime
def test_with_sim_time_the_plants_time_goes_out_on_clock(sim):
    node = sim(use_sim_time=True, clock_rate=250.0)  # one /clock every 4 plant steps
    node.close()
    sent = []
    node.clock_pub = type('Recorder', (), {'publish': staticmethod(sent.append)})()
    times = []
    for _ in range(8):
        node.step(1e-3, 0.0)
        times.append(node.plant.t)
    assert len(sent) == 2
    stamps = [m.clock.sec + m.clock.nanosec * 1e-9 for m in sent]
    assert all(min(abs(s - t) for t in times) < 1e-9 for s in stamps)
    assert stamps[1] - stamps[0] == pytest.approx(4e-3)
