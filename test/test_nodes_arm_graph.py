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
arm_graph in the test's process: the three nodes of one process, each with its own parameters.

`main(argv)` is run only where it refuses to start (exit status 2, one line on stderr): a bad
value in one node's section names that node's parameter, so each node is built with its own
section. The running graph, as a process, is test_graph_composed.py's. `run` sets the process's
SIGINT and SIGTERM handlers, and rclpy's EventsExecutor points faulthandler at the stderr it finds
(the capture's): each test puts pytest's back. A graph that starts after all would spin until
stopped: a SIGTERM after `BOUND` s stops it (run's own handler), and the test fails instead of
hanging.
"""
import faulthandler
import os
import signal
import sys
import threading

from node_processes import free_domain
import pytest

from bellows_ros.nodes import arm_graph
from bellows_ros.nodes.arm_controller_node import ArmControllerNode
from bellows_ros.nodes.driver_node import DriverNode
from bellows_ros.nodes.model_node import ModelNode

DRIVER = ['-p', 'driver_node:arm.enabled:=true']  # a driver that may be built (not configured)
BOUND = 60.0  # s: a bound on a refusal, not an expectation of its speed


@pytest.fixture
def graph(monkeypatch, capfd):
    """
    Return `start(*ros_args)`: the exit status of arm_graph's main, and its lines on stderr.

    The lines are the program's own: the nodes' ROS log records ('[INFO] [...] ...') are left out.
    """
    monkeypatch.setenv('ROS_DOMAIN_ID', free_domain())
    handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    fault_handler = faulthandler.is_enabled()

    def start(*ros_args):
        capfd.readouterr()
        stop = threading.Timer(BOUND, os.kill, (os.getpid(), signal.SIGTERM))
        stop.start()
        try:
            status = arm_graph.main(['arm_graph', '--ros-args', *ros_args])
        finally:
            stop.cancel()
        lines = capfd.readouterr().err.strip().splitlines()
        return status, [line for line in lines if not line.startswith('[')]
    yield start
    for number, handler in handlers.items():
        signal.signal(number, handler)
    if fault_handler:
        faulthandler.enable(file=sys.__stderr__)
    else:
        faulthandler.disable()


def test_the_graph_is_the_driver_the_model_and_the_controller_in_that_order():
    # built in this order, closed in the reverse one: the driver, which vents, goes last
    assert arm_graph.NODES == (DriverNode, ModelNode, ArmControllerNode)


@pytest.mark.parametrize('node, setting, name', [
    ('model_node', 'segments:=[5]', 'segments'),
    ('arm_controller_node', 'control_every:=0', 'control_every'),
])
def test_a_bad_value_in_one_nodes_section_is_refused_naming_it(graph, node, setting, name):
    status, lines = graph(*DRIVER, '-p', f'{node}:{setting}')
    assert status == 2 and len(lines) == 1, lines
    # '<program>: error: <node>: parameter ...', the program as run names it
    assert f": error: {node}: parameter '{name}'" in lines[0]


def test_the_driver_is_built_first_and_refuses_a_graph_without_a_device(graph):
    status, lines = graph('-p', 'arm_controller_node:control_every:=0')
    assert status == 2 and len(lines) == 1, lines
    assert 'neither arm.enabled nor actuator.enabled is set' in lines[0]


def test_a_value_given_without_a_node_reaches_every_node(graph):
    # `-p name:=value` is every node's: the controller's parameter is unknown to the driver
    status, lines = graph(*DRIVER, '-p', 'control_every:=5')
    assert status == 2 and len(lines) == 1, lines
    assert "unknown parameter 'control_every' for node 'driver_node'" in lines[0]
