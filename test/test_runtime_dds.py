"""The DDS runtime between processes: delivery, ROS 2 wire conventions, sim time, exit status."""
import os
import subprocess
import sys
import textwrap
import time

import pytest

from bellows_ros.runtime import dds_node
from bellows_ros.runtime.messages import msg

from plain_cyclone import JOINT_STATE_SUBSCRIBER

DOMAIN = '191'

TALKER = textwrap.dedent('''
    import sys
    from bellows_ros.runtime import rt

    class Talker(rt.Node):
        def __init__(self):
            super().__init__('talker')
            rate = self.declare_parameter('rate', 100.0).value
            self.offset = self.declare_parameter('offset', 0.0).value
            self.publisher = self.create_publisher(rt.msg.JointState, 'joint_states', 10)
            self.count = 0
            self.create_timer(1.0 / rate, self.tick)

        def tick(self):
            self.count += 1
            state = rt.msg.JointState(name=['segment_1'], position=[self.offset + self.count])
            state.header.stamp = self.get_clock().now().to_msg()
            self.publisher.publish(state)

    sys.exit(rt.main(Talker))
''')

# A subscriber that knows nothing of bellows_ros: plain cyclonedds and its own IDL definitions
# with the ROS 2 type names. It prints the last position it received and the type name and USER_DATA
# of the matched writer (from discovery). (Reading the builtin DCPSPublication topic crashes
# cyclonedds-python 11.0.1, so the matched-publication data is used instead.)
INDEPENDENT = JOINT_STATE_SUBSCRIBER + textwrap.dedent('''\
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
''')


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


def test_two_processes_talk_with_ros_args(tmp_path, env):
    talker = start(tmp_path, TALKER, ['--ros-args', '-p', 'rate:=200', '-p', 'offset:=1000',
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
    from rosbags.typesys import Stores, get_typestore
    expected = get_typestore(Stores.ROS2_JAZZY).hash_rihs01('sensor_msgs/msg/JointState')
    assert userdata == f'typehash={expected};'


def test_use_sim_time_follows_clock(tmp_path, env):
    talker = start(tmp_path, TALKER, ['--ros-args', '-p', 'use_sim_time:=true',
                                      '-p', 'rate:=100'], env)
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
    (['--ros-args', '-p', 'rate:=fast'], "parameter 'rate': expected a double"),
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
