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
bench/graph_floor.py's parts that run no graph: the figures, the nodes' arguments, the floors.

`run` builds the whole graph's and the floor's figures from what `_run_graph` measured (here a
made-up measurement); the per-run arguments of each node and floor node; the threads' CPU and
run-queue wait; and the device-free floor nodes, built in this process beside the nodes they
stand for: the same topics, message types and QoS, and their traffic per input sample. The
graphs over real DDS are test_graph_bench.py's. No time is asserted.
"""
import math
import os
from pathlib import Path
import re
import subprocess
import sys
import threading

import pytest
import rclpy

from bellows_ros import interfaces
from bellows_ros.bench import graph_floor
from bellows_ros.io import params
from bellows_ros.runtime.messages import msg


def documented_whole_graph_names():
    """Return the figures graph_floor's docstring names, `<node>` for each node of the graph."""
    names = set()
    for pattern in re.findall(r'`(graph\.(?:whole|floor)\.[a-z_.<>]+)`', graph_floor.__doc__):
        if '<node>' in pattern:
            names.update(pattern.replace('<node>', node) for node in graph_floor.NODES)
        else:
            names.add(pattern)
    return names


def test_the_whole_graph_is_launch_sims_graph():
    # scripts/launch_sim.sh's nodes, each with a floor node of the same name.
    launch = (Path(__file__).resolve().parent.parent / 'scripts' / 'launch_sim.sh').read_text()
    started = re.findall(r'start (\w+_node)', launch) + re.findall(r'/(scenario_node)"', launch)
    assert set(graph_floor.NODES) == set(started)
    assert set(graph_floor.FLOORS) == set(graph_floor.NODES)
    assert len(documented_whole_graph_names()) == 2 * len(graph_floor.NODES) + 4


def measured(kind):
    """Return a made-up `_run_graph` measurement of a graph: the whole costs twice the floor."""
    scale = 2.0 if kind == 'whole' else 1.0
    return {'cpu': {name: scale * 0.05 * (k + 1) for k, name in enumerate(graph_floor.NODES)},
            'scheduling': dict.fromkeys(graph_floor.NODES, 'SCHED_OTHER'),
            'waited': dict.fromkeys(graph_floor.NODES, 0.01),
            'threads': {name: {name[:15]: 0.1} for name in graph_floor.NODES},
            'window': 3.01, 'bench_cpu': 0.2, 'steal': 0.0,
            'loadavg': ('0.50 0.40 0.30', '0.60 0.40 0.30'),
            'torque_rate': 990.0 / scale, 'torque_messages': int(2980 / scale),
            'model_rate': 985.0 if kind == 'whole' else float('nan')}


def test_the_whole_graphs_figures_are_against_the_floors(monkeypatch):
    calls = []

    def run_graph(kind, window, settle):
        calls.append((kind, window, settle))
        return measured(kind)
    monkeypatch.setattr(graph_floor, '_run_graph', run_graph)
    results = {r.name: r for r in graph_floor.run(quick=True)}
    assert calls == [('floor', 3.0, 1.0), ('whole', 3.0, 1.0)]  # the floor first, --quick's
    assert set(results) == documented_whole_graph_names()
    floor, whole = measured('floor'), measured('whole')
    for name in graph_floor.NODES:
        node, base = results[f'graph.whole.cpu.{name}'], results[f'graph.floor.cpu.{name}']
        assert (node.value, node.unit) == (whole['cpu'][name], 'core')
        assert node.reference == f'graph.floor.cpu.{name}' and node.ratio == pytest.approx(2.0)
        assert base.reference is None and base.ratio is None
        assert node.extra == {'scheduling': 'SCHED_OTHER', 'runqueue_wait': 0.01,
                              'threads': {name[:15]: 0.1}}
    total = results['graph.whole.cpu.total']
    assert total.value == pytest.approx(sum(whole['cpu'].values()))
    assert total.target == graph_floor.TOTAL_TARGET and total.samples == len(graph_floor.NODES)
    assert total.reference == 'graph.floor.cpu.total' and total.ratio == pytest.approx(2.0)
    assert total.extra['loadavg_before'] == '0.50 0.40 0.30' and total.extra['window'] == 3.01
    assert results['graph.floor.cpu.total'].value == pytest.approx(sum(floor['cpu'].values()))
    rate, floor_rate = results['graph.whole.torque_rate'], results['graph.floor.torque_rate']
    assert (rate.value, rate.unit, rate.samples, rate.target) == (495.0, 'Hz', 1490, 1000.0)
    assert rate.ratio == pytest.approx(0.5) and rate.extra['model_rate_hz'] == 985.0
    assert 'model_rate_hz' not in floor_rate.extra  # the floor has no model to report a rate
    monkeypatch.setattr(graph_floor, '_run_graph', lambda *args: calls.append(args)
                        or measured(args[0]))
    graph_floor.run()
    assert calls[-2:] == [('floor', 20.0, graph_floor.SETTLE), ('whole', 20.0, graph_floor.SETTLE)]


def test_a_ratio_against_a_floor_of_nothing_is_nan():
    result = graph_floor.Result('graph.whole.cpu.x', 0.3, 'core')
    graph_floor._against(result, 0.0, 'graph.floor.cpu.x')
    assert result.reference == 'graph.floor.cpu.x' and math.isnan(result.ratio)
    graph_floor._against(result, 0.2, 'graph.floor.cpu.x')
    assert result.ratio == pytest.approx(1.5)


def test_the_whole_graph_gets_launch_sims_per_run_values():
    args = {name: graph_floor._overrides(name, '/run/pty', '239.74.172.9', '/run/out')
            for name in graph_floor.NODES}
    assert 'sim_arm_node:can.channel:=239.74.172.9' in args['sim_arm_node']
    assert 'driver_node:arm.channel:=239.74.172.9' in args['driver_node']
    assert 'sim_actuator_node:port:=/run/pty' in args['sim_actuator_node']
    assert 'driver_node:actuator.port:=/run/pty' in args['driver_node']
    assert 'model_node:segments:=[1, 2, 3, 4]' in args['model_node']
    assert 'scenario_node:duration:=3600.0' in args['scenario_node']  # runs through the window
    assert 'scenario_node:output_dir:=/run/out' in args['scenario_node']
    for name, given in args.items():  # `-p node:name:=value`, each for its own node
        assert given[::2] == ['-p'] * (len(given) // 2)
        assert all(value.startswith(f'{name}:') for value in given[1::2]), name


def test_each_floor_node_gets_its_nodes_scheduling_and_traffic():
    for name in graph_floor.NODES:
        config = params.read_file(graph_floor.CONFIG, name)
        given = dict(value.split(':=') for value in
                     graph_floor._floor_arguments(name, '/run/pty', '239.74.172.9')[1::2])
        assert given['realtime_priority'] == str(config.get('realtime_priority', 0)), name
        assert float(given['cpu_latency_limit']) == float(config.get('cpu_latency_limit', -1.0))
        for key in ('control_every', 'publish_every'):
            assert given.get(key) == (str(config[key]) if key in config else None), name
        assert ('can_channel' in given) == (name in ('sim_arm_node', 'driver_node')), name
        assert ('port' in given) == (name in ('sim_actuator_node', 'driver_node')), name
    arm = graph_floor._floor_arguments('arm_controller_node', '', '')
    controlled = params.read_file(graph_floor.CONFIG, 'arm_controller_node')['segments']
    assert f'segments:={list(controlled)}' in arm


def test_busiest_threads_and_runqueue_wait_over_the_window():
    # {tid: (kernel thread name, cpu s, run-queue wait s)} before and after a 2 s window.
    before = {'1': ('python3', 1.0, 0.0), '2': ('worker', 0.5, 0.0)}
    after = {'1': ('python3', 2.0, 0.1), '2': ('worker', 0.5, 0.2), '3': ('worker', 0.4, 0.05)}
    # Threads of one name are summed; one that started in the window counts from nothing.
    assert graph_floor._busiest(before, after, 2.0) == {'python3': 0.5, 'worker': 0.2}
    assert graph_floor._waited(before, after, 2.0) == pytest.approx(0.35 / 2.0)
    # The busiest THREADS_SHOWN, busiest first; idle ones are left out.
    many = {str(k): (f't{k}', 0.1 * k, 0.0) for k in range(10)}
    shown = graph_floor._busiest({}, many, 1.0)
    assert list(shown) == [f't{k}' for k in range(9, 9 - graph_floor.THREADS_SHOWN, -1)]


def test_threads_are_read_off_proc_and_a_gone_process_has_none():
    seen = graph_floor._thread_seconds(os.getpid())
    name, seconds, waited = seen[str(threading.get_native_id())]  # this very thread
    assert isinstance(name, str) and seconds >= 0.0 and (math.isnan(waited) or waited >= 0.0)
    gone = subprocess.Popen([sys.executable, '-c', 'pass'])
    gone.wait()
    assert graph_floor._thread_seconds(gone.pid) == {}
    assert graph_floor._scheduling(gone.pid) == 'unknown'


def topics(node):
    """Return ({publisher}, {subscription}) of `node`: (topic, type, QoS) each."""
    def key(endpoint):
        qos = endpoint.qos_profile
        return (endpoint.topic_name, endpoint.msg_type.__name__, qos.reliability, qos.durability,
                qos.history, qos.depth)
    return {key(p) for p in node.publishers}, {key(s) for s in node.subscriptions}


@pytest.fixture
def contexts(monkeypatch):
    """Return a function that makes an rclpy context with `args`; all shut down after."""
    from node_processes import free_domain
    monkeypatch.setenv('ROS_DOMAIN_ID', free_domain())
    made = []

    def make(*args):
        context = rclpy.Context()
        rclpy.init(args=['test', '--ros-args', *args] if args else ['test'], context=context)
        made.append(context)
        return context
    yield make
    for context in made:
        context.try_shutdown()


DEVICE_FREE = ('model_node', 'stiffness_controller_node', 'arm_controller_node', 'scenario_node')


@pytest.mark.parametrize('name', DEVICE_FREE)
def test_a_floor_node_has_its_nodes_name_topics_types_and_qos(contexts, tmp_path, name):
    from bellows_ros.nodes.arm_controller_node import ArmControllerNode
    from bellows_ros.nodes.model_node import ModelNode
    from bellows_ros.nodes.scenario_node import ScenarioNode
    from bellows_ros.nodes.stiffness_controller_node import StiffnessControllerNode
    real = {'model_node': ModelNode, 'stiffness_controller_node': StiffnessControllerNode,
            'arm_controller_node': ArmControllerNode, 'scenario_node': ScenarioNode}[name]
    node = real(context=contexts('-p', f'scenario_node:output_dir:={tmp_path}'))
    floor = graph_floor.FLOORS[name](context=contexts())
    try:
        assert floor.get_name() == node.get_name() == name
        assert topics(floor) == topics(node)
    finally:
        floor.close()
        floor.destroy_node()
        node.destroy_node()


def counted(node):
    """Count what `node` publishes, by topic, without sending it."""
    sent = {}
    for publisher in node.publishers:
        publisher.publish = lambda message, topic=publisher.topic_name: sent.update(
            {topic: sent.get(topic, 0) + 1})
    return sent


def feed(node, topic, samples):
    callback = next(s.callback for s in node.subscriptions if s.topic_name == topic)
    for _ in range(samples):
        callback(b'')  # raw: the floor never looks into a sample


def test_the_controllers_floors_publish_per_their_sample_counts(contexts):
    context = contexts('-p', 'control_every:=5', '-p', 'publish_every:=2')
    stiffness = graph_floor.FLOORS['stiffness_controller_node'](context=context)
    arm = graph_floor.FLOORS['arm_controller_node'](context=context)
    try:
        sent = counted(stiffness)
        feed(stiffness, '/actuator/joint_states', 20)
        # A motor command every 5th sample; the stiffness every 2nd command.
        assert sent == {'/actuator/motor_command': 4, '/actuator/stiffness': 2}
        sent = counted(arm)
        feed(arm, '/joint_states', 41)
        # A pressure command on the 1st, 6th, ... 41st sample; ~/state each 20 ms of samples
        # where control_msgs is installed.
        expected = {'/bellows/pressure_command': 9}
        if msg.JointTrajectoryControllerState is not None:
            expected[interfaces.TRAJECTORY_STATE.resolved()] = 2
        assert sent == expected
    finally:
        for node in (stiffness, arm):
            node.close()
            node.destroy_node()
