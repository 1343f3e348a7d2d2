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
Live parameters with ROS 2's own `ros2 param`, and the same services from any rclpy client.

The controllers and the model node run as node processes (rclpy, on the EventsExecutor in
bounded slices, so their parameter services answer). Table-driven: a live parameter is set and
reads back; a value outside its Spec is refused with the reason; a read-only one is refused as
read-only; a refused one changes nothing (it is not announced on /parameter_events); a change
reaches the running node (its /diagnostics show the new feedforward).

`ros2 param` takes each verb once (set, get, a refusal, describe); the rest of the tables go
through rclpy's AsyncParameterClient from this process, with the values parsed as the command
line parses them (`rclpy.parameter.get_parameter_value`): one call of the command line costs 3-10
s here, a service call milliseconds.
"""
import time

from node_processes import free_domain, launch, logs, node_env, ros2_cli, stop_all
from polling import wait_for
import probe
import pytest
from rclpy.parameter import get_parameter_value, parameter_value_to_python as python_value
from rclpy.parameter_client import AsyncParameterClient

from bellows_ros.runtime.messages import message_class, msg

# three nodes and four ros2 CLI calls
pytestmark = [pytest.mark.slow, pytest.mark.realtime]

NODES = ('arm_controller_node', 'stiffness_controller_node', 'model_node')
ParameterMsg = message_class('rcl_interfaces/msg/Parameter')

# (node, parameter, a value it takes, what `ros2 param get` then prints)
LIVE = [
    ('arm_controller_node', 'pid.kp', '35.0', 'Double value is: 35.0'),
    ('arm_controller_node', 'feedforward', 'previous', 'String value is: previous'),
    ('arm_controller_node', 'co_contraction', '50000.0', 'Double value is: 50000.0'),
    ('stiffness_controller_node', 'pd.kp', '500.0', 'Double value is: 500.0'),
    ('stiffness_controller_node', 'control_every', '2', 'Integer value is: 2'),
    ('model_node', 'latency_budget', '0.003', 'Double value is: 0.003'),
]
# (node, parameter, a value it refuses, what the refusal says: the Spec's words, or rclpy's own
# where rclpy checks the descriptor (range, type, read-only) before the node's callback)
REFUSED = [
    ('arm_controller_node', 'pid.kp', '-1.0', 'out of range Min: 0.0, Max: 10000.0'),
    ('arm_controller_node', 'feedforward', 'magic',
     "parameter 'feedforward' = 'magic': expected one of 'paper_a', 'previous', 'none'"),
    ('arm_controller_node', 'co_contraction', '650000.0',
     'must lie in [p0, p_max] = [101325, 750000] Pa'),  # p0 + co_contraction above p_max
    ('arm_controller_node', 'pid.kp', '35', "Wrong parameter type, expected 'Type.DOUBLE'"),
    ('stiffness_controller_node', 'pd.duty_max', '2.0', 'out of range Min: 0.01, Max: 1.0'),
    ('model_node', 'latency_budget', '0.0', 'out of range Min: 0.0001, Max: 1.0'),
    ('arm_controller_node', 'segments', '[2]', 'Trying to set a read-only parameter: segments'),
    ('model_node', 'segments', '[1]', 'Trying to set a read-only parameter: segments'),
    ('stiffness_controller_node', 'actuator_params', 'x.yaml',
     'Trying to set a read-only parameter: actuator_params'),
]


def ros2_param(env, *args):
    result = ros2_cli(['param', *args], env)
    return result.stdout + result.stderr


class Clients:
    """A plain rclpy node in this process: the nodes' parameter clients, its topics seen."""

    def __init__(self):
        self.node = probe.Node('live_parameter_probe')
        self.clients = {name: AsyncParameterClient(self.node, name) for name in NODES}
        self.seen, self.changed = {}, []  # the arm controller's diagnostics; changes announced
        self.node.create_subscription(
            msg.DiagnosticArray, '/diagnostics',
            lambda a: self.seen.update({kv.key: kv.value for s in a.status
                                        if s.name.startswith('arm_controller_node')
                                        for kv in s.values}), 50)
        # Every change taken is announced on /parameter_events; a refused one is not.
        self.node.create_subscription(
            message_class('rcl_interfaces/msg/ParameterEvent'), '/parameter_events',
            lambda e: self.changed.extend((e.node.lstrip('/'), p.name,
                                           str(python_value(p.value)))
                                          for p in e.changed_parameters), 1000)

    def ready(self):
        """Whether every node's parameter services are discovered."""
        probe.spin_once(self.node, 0.1)
        return all(client.services_are_ready() for client in self.clients.values())

    def set_parameter(self, node, name, value):
        """Set `name` to `value` (text, parsed as `ros2 param set` parses it); the result."""
        parameter = ParameterMsg(name=name, value=get_parameter_value(value))
        answer = probe.result_of(self.node, self.clients[node].set_parameters([parameter]))
        return answer.results[0]

    def get_parameter(self, node, name):
        value, = probe.result_of(self.node, self.clients[node].get_parameters([name])).values
        return python_value(value)


@pytest.fixture
def graph(tmp_path, monkeypatch):
    domain = free_domain()
    monkeypatch.setenv('ROS_DOMAIN_ID', domain)
    env = node_env(ROS_DOMAIN_ID=domain)
    processes = [launch(name, [], env, tmp_path) for name in NODES]
    probe.init()
    try:
        clients = Clients()
        # a loaded 2-core host starts a node in seconds
        assert wait_for(clients.ready, timeout=90), (clients.node.get_node_names(),
                                                     logs(tmp_path))
        yield env, tmp_path, clients
    finally:
        probe.shutdown()
        stop_all(processes)


def test_live_parameters_set_refuse_and_take_effect(graph):
    env, log_dir, clients = graph
    # Each verb once through the command line, with the words it prints.
    node, name, value, shown = LIVE[0]
    answer = ros2_param(env, 'set', f'/{node}', name, value)
    assert 'Set parameter successful' in answer, (node, name, answer, logs(log_dir))
    assert ros2_param(env, 'get', f'/{node}', name).strip() == shown
    node, name, value, reason = REFUSED[0]
    answer = ros2_param(env, 'set', f'/{node}', name, value)
    assert 'Setting parameter failed' in answer and reason in answer, (node, name, answer)
    described = ros2_param(env, 'describe', '/arm_controller_node', 'pid.kp', 'segments')
    assert 'Min value: 0.0' in described and 'Max value: 10000.0' in described, described
    assert described.count('Read only: true') == 1, described  # segments only

    # The rest of the tables through the same services.
    for node, name, value, _ in LIVE[1:]:
        result = clients.set_parameter(node, name, value)
        assert result.successful, (node, name, result.reason, logs(log_dir))
        assert clients.get_parameter(node, name) == python_value(get_parameter_value(value))
    # A refused value changes nothing: /parameter_events (checked below) announce exactly the
    # LIVE changes, and a read-back shows the value taken before.
    for node, name, value, reason in REFUSED[1:]:
        result = clients.set_parameter(node, name, value)
        assert not result.successful and reason in result.reason, (node, name, result.reason)
    assert clients.get_parameter('arm_controller_node', 'pid.kp') == 35.0

    # The change reached the running controller: its /diagnostics name the new feedforward.
    deadline = time.monotonic() + 15
    while (clients.seen.get('feedforward') != 'previous'
           or len(clients.changed) < len(LIVE)) and time.monotonic() < deadline:
        probe.spin_once(clients.node, timeout_sec=0.1)
    assert clients.seen.get('feedforward') == 'previous', clients.seen
    taken = sorted((node, name, value) for node, name, value, _ in LIVE)
    assert sorted(clients.changed) == taken, clients.changed
