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

"""The DDS runtime between processes: delivery, ROS 2 wire conventions, sim time, exit status."""
import os
import subprocess
import sys
import textwrap
import time

from plain_cyclone import JOINT_STATE_SUBSCRIBER
import pytest

from bellows_ros.runtime import dds_node
from bellows_ros.runtime.messages import msg

DOMAIN = '191'

TALKER = textwrap.dedent("""
    import sys
    from bellows_ros.runtime import Node, run

    class Talker(Node):
        def __init__(self, **kwargs):
            super().__init__('talker', **kwargs)
            rate = self.declare_parameter('rate', 100.0).value
            self.offset = self.declare_parameter('offset', 0.0).value
            self.publisher = self.create_publisher(self.msg.JointState, 'joint_states', 10)
            self.count = 0
            self.create_timer(1.0 / rate, self.tick)

        def tick(self):
            self.count += 1
            state = self.msg.JointState(name=['segment_1'], position=[self.offset + self.count])
            state.header.stamp = self.get_clock().now().to_msg()
            self.publisher.publish(state)

    sys.exit(run(Talker))
""")

# A subscriber that knows nothing of bellows_ros: plain cyclonedds and its own IDL definitions
# with the ROS 2 type names. It prints the last position it received and the type name and
# USER_DATA of the matched writer (from discovery). (Reading the builtin DCPSPublication topic
# crashes cyclonedds-python 11.0.1, so the matched-publication data is used instead.)
INDEPENDENT = JOINT_STATE_SUBSCRIBER + textwrap.dedent("""\
    topic = Topic(participant, 'rt/' + sys.argv[2].lstrip('/'), JointState)
    reader = DataReader(participant, topic, qos=Qos(Policy.Reliability.Reliable(0),
                                                     Policy.History.KeepLast(10)))
    end = time.time() + 10
    seen, userdata = None, None
    while time.time() < end and (seen is None or userdata is None):
        for sample in reader.take(10):
            seen = sample
        for handle in reader.get_matched_publications():
            endpoint = reader.get_matched_publication_data(handle)
            userdata = endpoint.qos[Policy.Userdata].data.decode()
            typename = endpoint.type_name
        time.sleep(0.01)
    print(seen.name[0], seen.position[0], typename, userdata)
""")


@pytest.fixture
def env(monkeypatch):
    monkeypatch.setenv('ROS_DOMAIN_ID', DOMAIN)
    environment = dict(os.environ, ROS_DOMAIN_ID=DOMAIN, BELLOWS_RUNTIME='dds')
    yield environment
    dds_node.shutdown()


def start(tmp_path, script, args, env):
    path = tmp_path / 'script.py'
    path.write_text(script)
    return subprocess.Popen([sys.executable, str(path), *args], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def stop(process):
    if process.poll() is None:
        process.send_signal(2)
    try:
        return process.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        process.kill()
        return process.communicate()


def receive(node, items, count, timeout=10.0):
    end = time.monotonic() + timeout
    while len(items) < count and time.monotonic() < end:
        dds_node.spin_once(node, timeout_sec=0.05)
    return items


@pytest.mark.slow  # node processes
def test_two_processes_talk_with_ros_args(tmp_path, env):
    talker = start(tmp_path, TALKER, ['--ros-args', '-p', 'rate:=200.0', '-p', 'offset:=1000.0',
                                      '-r', 'joint_states:=/remapped'], env)
    try:
        dds_node.init([])
        node = dds_node.Node('listener')
        received = []
        node.create_subscription(msg.JointState, '/remapped', received.append, 10)
        receive(node, received, 20)
    finally:
        _, err = stop(talker)
    assert len(received) >= 20, err
    positions = [m.position[0] for m in received]
    assert all(p > 1000 for p in positions)
    assert positions == sorted(positions)  # reliable, in order
    assert talker.returncode == 0, err


@pytest.mark.slow  # node processes
def test_independent_cyclone_subscriber_sees_the_runtime(tmp_path, env):
    talker = start(tmp_path, TALKER, ['--ros-args', '-p', 'offset:=0.5'], env)
    (tmp_path / 'sub').mkdir()
    try:
        plain_env = {k: v for k, v in env.items() if k != 'PYTHONPATH'}
        listener = subprocess.run([sys.executable, '-c', INDEPENDENT, DOMAIN, '/joint_states'],
                                  env=plain_env, cwd=tmp_path / 'sub', capture_output=True,
                                  text=True, timeout=30)
    finally:
        stop(talker)
    assert listener.returncode == 0, listener.stderr
    name, position, typename, userdata = listener.stdout.split()
    assert name == 'segment_1' and float(position) > 0.5
    assert typename == 'sensor_msgs::msg::dds_::JointState_'
    from rosbags.typesys import get_typestore, Stores
    expected = get_typestore(Stores.ROS2_JAZZY).hash_rihs01('sensor_msgs/msg/JointState')
    assert userdata == f'typehash={expected};'


@pytest.mark.slow  # node processes
def test_use_sim_time_follows_clock(tmp_path, env):
    talker = start(tmp_path, TALKER, ['--ros-args', '-p', 'use_sim_time:=true',
                                      '-p', 'rate:=100.0'], env)
    try:
        dds_node.init([])
        node = dds_node.Node('clock_source')
        clock = node.create_publisher(msg.Clock, '/clock', 10)
        received = []
        node.create_subscription(msg.JointState, '/joint_states', received.append, 10)
        end = time.monotonic() + 10
        while time.monotonic() < end and not any(m.header.stamp.sec == 1234 for m in received):
            clock.publish(msg.Clock(clock=msg.Time(sec=1234, nanosec=500_000_000)))
            dds_node.spin_once(node, timeout_sec=0.02)
    finally:
        stop(talker)
    stamps = {(m.header.stamp.sec, m.header.stamp.nanosec) for m in received}
    assert (1234, 500_000_000) in stamps
    # Before the first /clock message, sim time is zero; never wall time.
    assert all(sec in (0, 1234) for sec, _ in stamps)


@pytest.mark.parametrize('args, message', [
    (['--ros-args', '-p', 'rat:=5'], "unknown parameter 'rat' for node 'talker'"),
    (['--ros-args', '-p', 'rate:=fast'], "parameter 'rate' must be a double, got a string 'fast'"),
    (['--ros-args', '--params-file', 'missing.yaml'], 'missing.yaml: cannot read parameter file'),
])
def test_user_mistakes_exit_2_with_one_line(tmp_path, env, args, message):
    process = start(tmp_path, TALKER, args, env)
    out, err = process.communicate(timeout=20)
    assert process.returncode == 2
    assert message in err and len(err.strip().splitlines()) == 1, err


def test_bad_yaml_names_the_line(tmp_path, env):
    bad = tmp_path / 'bad.yaml'
    bad.write_text('talker:\n  ros__parameters:\n    rate: [1, 2\n')
    process = start(tmp_path, TALKER, ['--ros-args', '--params-file', str(bad)], env)
    _, err = process.communicate(timeout=20)
    assert process.returncode == 2 and f'{bad}:' in err and len(err.strip().splitlines()) == 1


def test_publisher_waits_until_readers_acknowledged(env):
    dds_node.init([])
    node = dds_node.Node('acked')
    try:
        publisher = node.create_publisher(msg.JointState, '/acked', 100)
        assert publisher.wait_for_all_acked(dds_node.Duration(seconds=0.0))  # no reader yet
        received = []
        node.create_subscription(msg.JointState, '/acked', received.append, 100)
        for i in range(50):
            publisher.publish(msg.JointState(name=['segment_1'], position=[float(i)]))
        assert publisher.wait_for_all_acked(dds_node.Duration(seconds=2.0))
        positions = [m.position[0] for m in receive(node, received, 50)]
        assert positions == [float(i) for i in range(50)]
    finally:
        node.destroy_node()   # its reader would otherwise acknowledge for the next test's


@pytest.mark.slow  # node processes
def test_waiting_for_a_dead_reader_times_out(env):
    """A reader killed without goodbye stays matched until its lease ends: never acknowledges."""
    dds_node.init([])
    node = dds_node.Node('dead_reader')
    publisher = node.create_publisher(msg.JointState, '/dead_reader', 100)
    reader = subprocess.Popen([sys.executable, '-c', JOINT_STATE_SUBSCRIBER + textwrap.dedent("""\
        reader = DataReader(participant, Topic(participant, 'rt/dead_reader', JointState),
                            qos=Qos(Policy.Reliability.Reliable(0), Policy.History.KeepLast(10)))
        time.sleep(60)
        """), DOMAIN], env={k: v for k, v in env.items() if k != 'PYTHONPATH'})
    try:
        end = time.monotonic() + 20.0
        while publisher.get_subscription_count() == 0 and time.monotonic() < end:
            time.sleep(0.02)
        assert publisher.get_subscription_count() == 1
        reader.kill()
        reader.wait()
        publisher.publish(msg.JointState(name=['segment_1'], position=[1.0]))
        start = time.monotonic()
        assert publisher.wait_for_all_acked(dds_node.Duration(seconds=0.3)) is False
        assert time.monotonic() - start < 5.0   # bounded (a generous bound, not a timing claim)
    finally:
        reader.kill()
        node.destroy_node()


def test_a_backlog_of_two_topics_is_served_in_step(env):
    """
    After a stall the two halves of each sample (two topics) must not drift apart.

    The model node pairs them and drops a half after `max_pending` unmatched ones.
    """
    dds_node.init([])
    node = dds_node.Node('backlog')
    order = []
    for topic in ('/half_a', '/half_b'):
        node.create_subscription(msg.JointState, topic,
                                 lambda m, t=topic: order.append((t, m.position[0])), 500)
    publishers = [node.create_publisher(msg.JointState, t, 500) for t in ('/half_a', '/half_b')]
    for i in range(300):                       # nobody spins meanwhile: a 300-sample backlog
        for publisher in publishers:
            publisher.publish(msg.JointState(name=['segment_1'], position=[float(i)]))
    end = time.monotonic() + 10.0
    while len(order) < 600 and time.monotonic() < end:
        dds_node.spin_once(node, timeout_sec=0.05)
    assert len(order) == 600
    seen = {'/half_a': 0, '/half_b': 0}
    worst = 0
    for topic, _ in order:
        seen[topic] += 1
        worst = max(worst, abs(seen['/half_a'] - seen['/half_b']))
    assert worst <= 10, worst                  # was 256 with one topic's backlog taken first


def test_destroying_a_node_deletes_its_dds_entities_at_once(env):
    """Children go before their parent, now, not whenever the garbage collector gets to them."""
    from cyclonedds.core import Entity
    dds_node.init([])
    node = dds_node.Node('short_lived')
    publisher = node.create_publisher(msg.Float64, '/short', 10)
    subscription = node.create_subscription(msg.Float64, '/short', lambda m: None, 10)
    entities = [publisher._writer, subscription.reader, subscription.condition]
    assert all(entity._ref in Entity._entities for entity in entities)
    node.destroy_node()
    assert not any(entity._ref in Entity._entities for entity in entities)
    node.destroy_node()  # a second time: nothing left to do
    participant = dds_node._context.participant
    dds_node.shutdown()
    assert participant._ref not in Entity._entities


CYCLES = textwrap.dedent("""
    from bellows_ros.runtime import dds_node
    for i in range(120):
        dds_node.init([])
        node = dds_node.Node(f'cycle_{i}')
        publisher = node.create_publisher(dds_node.msg.Float64, '/cycle', 10)
        node.create_subscription(dds_node.msg.Float64, '/cycle', lambda m: None, 10)
        for _ in range(3):
            publisher.publish(dds_node.msg.Float64(data=1.0))
            dds_node.spin_once(node, 0.01)
        node.destroy_node()
        dds_node.shutdown()
    print('done')
""")


@pytest.mark.slow  # a child process joins and leaves the domain 120 times
def test_joining_and_leaving_the_domain_many_times_does_not_crash(tmp_path, env):
    """
    A test process joins and leaves the domain once per test.

    With the entities left to the garbage collector this crashed (SIGSEGV in a later write, or
    heap corruption at exit) in about half of the runs of 60 cycles.
    """
    run = subprocess.run([sys.executable, '-c', CYCLES], env=dict(env, PYTHONFAULTHANDLER='1'),
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0 and run.stdout.split() == ['done'], run.stderr[-2000:]
