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
Mixed graphs: an rclpy node and a DDS-runtime node on one ROS 2 graph.

Both exchange every topic of the contract (`topics.TOPICS`, each with its message type) in both
directions and check the other's values (mixed_peer.py); the ROS 2 CLI (`ros2 node list`,
`ros2 topic info -v`) sees the DDS-runtime node by name; an rclpy node (model_node) answers
`ros2 param list/get`. The CLI runs with `--no-daemon`, retried while discovery settles.
"""
import json
import os
from pathlib import Path
import random
import select
import shutil
import subprocess
import sys
import time

import pytest
from runtimes import node_env, require_rclpy, stop_all

from bellows_ros import params
from bellows_ros.interfaces import by_name

TOPICS = by_name()

pytestmark = pytest.mark.slow

HERE = Path(__file__).resolve().parent
BIN = Path(sys.executable).parent
CONFIG = HERE.parent / 'config' / 'nodes_sim.yaml'
TIMEOUT_S = 60


@pytest.fixture
def domain():
    require_rclpy()
    if shutil.which('ros2') is None:
        pytest.fail('rclpy imports but the ros2 CLI is not on PATH: source the ROS 2 setup')
    return str(random.randint(60, 99))


@pytest.fixture
def start(domain):
    """Return a starter of node processes in the test's domain, stopped (SIGINT) at the end."""
    processes = []

    def start_process(argv, runtime):
        process = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                   text=True, env=node_env(runtime, ROS_DOMAIN_ID=domain))
        processes.append(process)
        return process
    yield start_process
    stop_all(processes)


def ros2(domain, *args):
    """Output of `ros2 *args` in the domain (stdout; '' on failure)."""
    result = subprocess.run([sys.executable, shutil.which('ros2'), *args], capture_output=True,
                            text=True, timeout=60, env=dict(os.environ, ROS_DOMAIN_ID=domain))
    return result.stdout if result.returncode == 0 else ''


def ros2_until(domain, args, condition, attempts=8):
    """`ros2 *args`, retried (discovery takes a moment) until `condition(output)`; the output."""
    for _ in range(attempts):
        output = ros2(domain, *args)
        if condition(output):
            break
        time.sleep(0.5)
    return output


def read_report(process, deadline):
    """Return the peer's JSON line once it has the other side's values on every topic."""
    ready, _, _ = select.select([process.stdout], [], [], max(0.0, deadline - time.monotonic()))
    assert ready, f'{process.args[-1]} peer: not every topic within {TIMEOUT_S} s'
    line = process.stdout.readline()
    assert line, f'peer exited with {process.wait()}: {process.stderr.read()}'
    return json.loads(line)


def test_rclpy_and_dds_nodes_exchange_every_topic(start, domain):
    peers = {side: start([sys.executable, str(HERE / 'mixed_peer.py'), side], side)
             for side in ('rclpy', 'dds')}
    deadline = time.monotonic() + TIMEOUT_S
    reports = {side: read_report(process, deadline) for side, process in peers.items()}
    for side, report in reports.items():
        assert report['node'] == f'mixed_{side}'
        assert sorted(report['received']) == sorted(TOPICS)
    assert reports['rclpy']['received']['/actuator/stiffness'] == [2.5]  # the DDS side's value
    assert reports['dds']['received']['/actuator/stiffness'] == [1.25]

    nodes = ros2_until(domain, ['node', 'list', '--no-daemon'],
                       lambda out: '/mixed_dds' in out and '/mixed_rclpy' in out)
    assert '/mixed_dds' in nodes.split() and '/mixed_rclpy' in nodes.split(), nodes
    info = ros2_until(domain, ['topic', 'info', '-v', '--no-daemon', '/bellows/wrench'],
                      lambda out: out.count('Node name:') >= 4)
    publishers = info.split('Subscription count')[0]
    assert 'Node name: mixed_dds' in publishers and 'Node name: mixed_rclpy' in publishers, info
    assert 'geometry_msgs/msg/WrenchStamped' in info


def test_rclpy_node_answers_ros2_param(start, domain):
    model = start([str(BIN / 'model_node'), '--ros-args', '--params-file', str(CONFIG)], 'rclpy')
    segments = params.read_file(CONFIG, 'model_node')['segments']
    names = ros2_until(domain, ['param', 'list', '--no-daemon', '/model_node'],
                       lambda out: 'segments' in out)
    assert model.poll() is None, model.stderr.read()
    assert 'segments' in names.split() and 'use_sim_time' in names.split(), names
    value = ros2_until(domain, ['param', 'get', '--no-daemon', '/model_node', 'segments'],
                       lambda out: 'values are' in out)
    assert f'Integer values are: {segments}' in value, value
