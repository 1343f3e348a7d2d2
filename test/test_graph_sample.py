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
Acceptance: the simulated graph over real DDS, driver -> model, counted sample by sample.

Runs twice: the nodes on rclpy (`[rclpy]`) and on the DDS runtime (`[dds]`); the test's own probe
is a DDS-runtime node either way.

Processes: sim_arm_node (udp_multicast CAN), sim_actuator_node (pty), driver_node, model_node; an
independent plain-Cyclone subscriber (no bellows_ros import, its own IDL definitions with ROS 2
type names) must see /joint_states and /bellows/driving_torque. Then the driver is stopped and its
final count of published arm samples must equal the model node's count of evaluated samples.
The probe counts the sample topics by joint names: the arm's topics carry no actuator message
(the arm's 1 kHz subscribers never decode one), the actuator's carry the actuator's only.
"""
from collections import Counter
import math
import os
import random
import signal
import subprocess
import sys
import textwrap
import time

from node_processes import launch, logs, node_env, override, SIM_CONFIG
from plain_cyclone import JOINT_STATE_SUBSCRIBER
import probe
import pytest

from bellows_ros import interfaces, params
from bellows_ros.runtime import realtime
from bellows_ros.runtime.messages import msg


PLAIN_SUBSCRIBER = JOINT_STATE_SUBSCRIBER + textwrap.dedent("""\
    qos = Qos(Policy.Reliability.Reliable(0), Policy.History.KeepLast(50))
    readers = {t: DataReader(participant, Topic(participant, 'rt' + t, JointState), qos=qos)
               for t in sys.argv[2:]}
    seen = {t: None for t in readers}
    end = time.time() + 20
    while time.time() < end and any(v is None for v in seen.values()):
        for topic, reader in readers.items():
            for sample in reader.take(50):
                if getattr(sample, 'name', None) and sample.name[0] == 'segment_1':
                    seen[topic] = sample
        time.sleep(0.005)
    for topic, sample in seen.items():
        print(topic, sample.name[0], sample.header.stamp.sec, sample.header.stamp.nanosec,
              sample.position[0] if sample.position else sample.effort[0])
""")


# Which node owns the writer of each topic, as `ros2 topic info -v` works it out: the writers a
# reader matched (GUIDs, from DDS discovery), their owners from `ros_discovery_info`.
PLAIN_GRAPH_READER = JOINT_STATE_SUBSCRIBER + textwrap.dedent("""\
    from cyclonedds.idl.types import array, bounded_str, uint8

    @dataclass
    class Gid(IdlStruct, typename='rmw_dds_common::msg::dds_::Gid_'):
        data: array[uint8, 16]

    @dataclass
    class NodeEntitiesInfo(IdlStruct, typename='rmw_dds_common::msg::dds_::NodeEntitiesInfo_'):
        node_namespace: bounded_str[256]
        node_name: bounded_str[256]
        reader_gid_seq: sequence[Gid]
        writer_gid_seq: sequence[Gid]

    @dataclass
    class ParticipantEntitiesInfo(IdlStruct,
                                  typename='rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_'):
        gid: Gid
        node_entities_info_seq: sequence[NodeEntitiesInfo]

    # Every participant writes this one unkeyed topic: a deep history, or one node's sample
    # replaces another's before it is taken.
    qos = Qos(Policy.Reliability.Reliable(0), Policy.Durability.TransientLocal,
              Policy.History.KeepLast(100))
    info = DataReader(participant, Topic(participant, 'ros_discovery_info',
                                         ParticipantEntitiesInfo), qos=qos)
    readers = {t: DataReader(participant, Topic(participant, 'rt' + t, JointState))
               for t in sys.argv[2:]}
    owner, found = {}, {}
    end = time.time() + 20
    while time.time() < end and set(found) != set(readers):
        for sample in info.take(50):
            for node in getattr(sample, 'node_entities_info_seq', []):
                for gid in node.writer_gid_seq:
                    owner[bytes(gid.data)] = node.node_namespace.rstrip('/') + '/' + node.node_name
        for topic, reader in readers.items():
            for handle in reader.get_matched_publications():
                key = reader.get_matched_publication_data(handle).key.bytes
                if key in owner:
                    found[topic] = owner[key]
        time.sleep(0.02)
    for topic, node in sorted(found.items()):
        print(topic, node)
""")


def stop(process, timeout=10):
    if process.poll() is None:
        process.send_signal(2)
    try:
        process.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
    return process.returncode


pytestmark = pytest.mark.slow  # four node processes, ~25 s per runtime


@pytest.fixture
def graph(runtime, tmp_path, monkeypatch):
    domain = str(random.randint(100, 180))
    group = f'239.74.164.{random.randint(2, 250)}'
    port = str(tmp_path / 'actuator')
    env = node_env(ROS_DOMAIN_ID=domain)
    monkeypatch.setenv('ROS_DOMAIN_ID', domain)
    probe.init()
    watcher = probe.Node('acceptance_probe')
    final = {}

    def on_diagnostics(array):
        for status in array.status:
            final[status.name] = {kv.key: kv.value for kv in status.values}
    watcher.create_subscription(msg.DiagnosticArray, '/diagnostics', on_diagnostics, 50)
    # Every message on the four sample topics, by the names it carries (subscribed before the
    # driver starts: it waits for a subscriber on each).
    seen = {topic.resolved(): Counter() for topic in (
        interfaces.JOINT_STATES, interfaces.CHAMBERS, interfaces.ACTUATOR_JOINT_STATES,
        interfaces.ACTUATOR_CHAMBERS)}
    for name, counter in seen.items():
        watcher.create_subscription(msg.JointState, name,
                                    lambda m, counter=counter: counter.update([tuple(m.name)]),
                                    interfaces.SAMPLE_DEPTH)
    # One scheduling class for the whole path: config/nodes_sim.yaml runs the simulated arm and
    # the driver SCHED_FIFO above a model node at normal priority, which on a loaded machine then
    # falls behind and drops samples, and this test counts every sample through the model.
    normal = {name: override(name, 'realtime_priority', 0)
              for name in ('sim_arm_node', 'driver_node')}
    processes = {
        'sim_arm_node': launch('sim_arm_node', override('sim_arm_node', 'can.channel', group)
                               + override('sim_arm_node', 'n_segments', 2)
                               + normal['sim_arm_node'], env, tmp_path),
        'sim_actuator_node': launch('sim_actuator_node', override('sim_actuator_node', 'port',
                                                                  port),
                                    env, tmp_path),
        'model_node': launch('model_node', override('model_node', 'segments', '[1, 2]'), env,
                             tmp_path),
    }
    try:
        # The driver publishes from its first sample on: the model must be subscribed by then
        # (and the driver waits until it has matched it), or the count below would include
        # samples published before anyone listened.
        end = time.monotonic() + 60.0
        while 'model_node: driving torque' not in final and time.monotonic() < end:
            probe.spin_once(watcher, timeout_sec=0.05)
        assert 'model_node: driving torque' in final, logs(tmp_path)
        driver = [override('driver_node', name, value) for name, value in (
            ('arm.channel', group), ('arm.n_segments', 2), ('actuator.port', port),
            ('wait_for_subscribers', 20.0))]
        processes['driver_node'] = launch('driver_node', sum(driver, []) + normal['driver_node'],
                                          env, tmp_path)
        yield processes, domain, tmp_path, probe, final, seen
    finally:
        for process in processes.values():
            stop(process)
        probe.shutdown()


def test_graph_publishes_and_every_sample_is_evaluated(graph):
    processes, domain, tmp_path, node, final, seen = graph
    plain = subprocess.run([sys.executable, '-c', PLAIN_SUBSCRIBER, domain, '/joint_states',
                            '/bellows/driving_torque'], capture_output=True, text=True, timeout=60,
                           env={k: v for k, v in os.environ.items() if k != 'PYTHONPATH'},
                           cwd=tmp_path)
    assert plain.returncode == 0, plain.stderr + logs(tmp_path)
    lines = dict(line.split(' ', 1) for line in plain.stdout.strip().splitlines())
    assert set(lines) == {'/joint_states', '/bellows/driving_torque'}, logs(tmp_path)
    for line in lines.values():
        name, sec, _nanosec, value = line.split()
        assert name == 'segment_1' and abs(int(sec) - time.time()) < 600 \
            and math.isfinite(float(value)), line
    # The same reader can tell which node publishes what (ROS 2's graph, `ros_discovery_info`).
    owners = subprocess.run([sys.executable, '-c', PLAIN_GRAPH_READER, domain, '/joint_states',
                             '/bellows/driving_torque'],
                            capture_output=True, text=True, timeout=60,
                            env={k: v for k, v in os.environ.items() if k != 'PYTHONPATH'},
                            cwd=tmp_path)
    assert owners.returncode == 0, owners.stderr
    assert dict(line.split() for line in owners.stdout.strip().splitlines()) == {
        '/joint_states': '/driver_node', '/bellows/driving_torque': '/model_node'}, owners.stdout

    # Count: let the graph run, stop the driver, then compare its final count with the model's.
    end = time.monotonic() + 4.0
    while time.monotonic() < end:
        probe.spin_once(node, timeout_sec=0.05)
    assert stop(processes['driver_node']) == 0, logs(tmp_path)
    end = time.monotonic() + 3.0
    while time.monotonic() < end:
        probe.spin_once(node, timeout_sec=0.05)
    driver, model = final['driver_node: arm'], final['model_node: driving torque']
    published = int(driver['published'])
    assert published > 500, (driver, logs(tmp_path))
    assert int(model['evaluated']) == published, f'driver {driver}\nmodel {model}'
    assert model['rejected'] == '0' and model['unmatched_dropped'] == '0'
    assert int(final['driver_node: actuator']['published']) > 500
    # Each group on its own topics: no actuator message reaches an arm subscriber (#22 point 4).
    arm = {'/joint_states': {('segment_1', 'segment_2')},
           '/bellows/chambers': {('segment_1/chain_1', 'segment_1/chain_2', 'segment_2/chain_1',
                                  'segment_2/chain_2')},
           '/actuator/joint_states': {interfaces.ACTUATOR_JOINTS},
           '/actuator/chambers': {(interfaces.ACTUATOR_CHAMBER,)}}
    for topic, names in arm.items():
        assert set(seen[topic]) == names, (topic, seen[topic])
        assert sum(seen[topic].values()) > 500, (topic, seen[topic])

    # The CPU latency limit the config asks for was in force while the nodes ran (each reports
    # the limit in force on /diagnostics), where the nodes could request it.
    if os.access(realtime.CPU_LATENCY_DEVICE, os.W_OK):
        limit = params.read_file(SIM_CONFIG, 'model_node')['cpu_latency_limit']
        reported = {name.split(':')[0]: values['cpu_latency_limit_us']
                    for name, values in final.items() if 'cpu_latency_limit_us' in values}
        assert set(reported) == {'sim_arm_node', 'sim_actuator_node', 'driver_node', 'model_node'}
        assert set(reported.values()) == {f'{limit * 1e6:.0f}'}, reported


def test_a_driver_stopped_for_half_a_second_stamps_its_backlog_on_the_arms_clock(graph):
    """
    The samples a driver reads late from its socket keep the times the arm took them.

    SIGSTOP stands for a driver the machine does not schedule; the arm's frames wait in the
    socket meanwhile. Stamped when read, the backlog went out as fresh samples: a hole in the
    stamps, then a burst stamped at the same instant, each sample's age hidden from the arm
    controller's `max_sample_age` (docs/bench_log.md, 2026-11-26).
    """
    processes, domain, tmp_path, probe, final, seen = graph
    stamps = []
    watcher.create_subscription(
        msg.JointState, interfaces.JOINT_STATES.resolved(),
        lambda m: stamps.append(m.header.stamp.sec * 10**9 + m.header.stamp.nanosec),
        interfaces.SAMPLE_DEPTH)

    def spin(seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            probe.spin_once(watcher, timeout_sec=0.05)
    end = time.monotonic() + 30.0
    while len(stamps) < 1000 and time.monotonic() < end:
        spin(0.1)
    assert len(stamps) >= 1000, logs(tmp_path)
    driver = processes['driver_node']
    before = len(stamps)
    driver.send_signal(signal.SIGSTOP)
    time.sleep(0.5)
    driver.send_signal(signal.SIGCONT)
    spin(3.0)
    after = stamps[before - 100:]
    assert len(after) > 1500, len(after)
    gaps = [b - a for a, b in zip(after, after[1:])]
    # The stop is not a hole in the arm's time base (the simulated arm sent every sample) ...
    assert max(gaps) < 50 * 10**6, f'largest stamp gap {max(gaps) / 1e6:.1f} ms'
    # ... and the backlog is not bunched at the moment it was read: stamps keep the sample period
    # (DeviceClock; a gap shortens only where a less-delayed arrival corrects its offset).
    bunched = sum(gap < 0.1 * interfaces.SAMPLE_PERIOD * 1e9 for gap in gaps)
    assert bunched <= len(gaps) // 100, f'{bunched} of {len(gaps)} stamps bunched'
