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
arm_graph: driver, model and arm controller composed in one process, on one executor.

Beside a simulated arm, the composed process must do what the three processes do: the driver
reaches `active` (by autostart, from the shared parameter file's sections), the model publishes
driving torques, the arm controller commands the chambers along its built-in trajectory, each
node answers `ros2 param` under its own name, and Ctrl-C ends all three with the vent.
"""
import random
import signal
import subprocess
import time

from node_processes import (BIN, free_domain, launch, logs, node_env, override,
                            require_ros2_cli, ros2_cli, SIM_CONFIG, stop_all)
import probe
import pytest

from bellows_ros import interfaces
from bellows_ros.runtime.messages import msg

# two node processes, ~20 s
pytestmark = [pytest.mark.slow, pytest.mark.realtime]


def test_the_composed_arm_graph_runs_the_three_nodes(tmp_path, monkeypatch):
    domain = free_domain()
    group = f'239.74.171.{random.randint(2, 250)}'
    monkeypatch.setenv('ROS_DOMAIN_ID', domain)
    env = node_env(ROS_DOMAIN_ID=domain)
    sim = launch('sim_arm_node', override('sim_arm_node', 'can.channel', group)
                 + override('sim_arm_node', 'realtime_priority', 0), env, tmp_path)
    log = open(tmp_path / 'arm_graph.log', 'w')
    graph = subprocess.Popen(
        [str(BIN / 'arm_graph'), '--ros-args', '--params-file', str(SIM_CONFIG),
         *override('driver_node', 'autostart', 'true'),
         *override('driver_node', 'arm.channel', group),
         *override('driver_node', 'actuator.enabled', 'false'),
         *override('arm_controller_node', 'trajectory', 'reversals'),
         *override('arm_controller_node', 'realtime_priority', 0)],
        env=env, stdout=log, stderr=subprocess.STDOUT)
    torques, pressures = [], []
    probe.init()
    try:
        watcher = probe.Node('composed_probe')
        watcher.create_subscription(msg.JointState, interfaces.DRIVING_TORQUE.resolved(),
                                    lambda m: torques.append(m), 1000)
        watcher.create_subscription(msg.JointState, interfaces.JOINT_STATES.resolved(),
                                    lambda m: pressures.append(probe.highest_pressure(m)), 1000)
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not (
                torques and pressures and max(pressures) > 1.5e5):
            probe.spin_once(watcher, timeout_sec=0.05)
        assert torques, logs(tmp_path)
        assert max(pressures) > 1.5e5, logs(tmp_path)  # the controller commands the chambers
        require_ros2_cli()
        for node, name in (('driver_node', 'startup_timeout'), ('model_node', 'latency_budget'),
                           ('arm_controller_node', 'pid.kp')):
            answer = ros2_cli(['param', 'get', f'/{node}', name], env)
            assert 'value is' in answer.stdout, (node, answer.stdout + answer.stderr)
        graph.send_signal(signal.SIGINT)
        assert graph.wait(timeout=30) == 0, logs(tmp_path)
    finally:
        probe.shutdown()
        stop_all([graph, sim])
    text = (tmp_path / 'arm_graph.log').read_text()
    assert 'shutdown: every device at rest' in text, text[-2000:]
