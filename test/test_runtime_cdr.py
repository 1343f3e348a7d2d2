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
runtime/cdr.py: the pure-Python codec the rclpy runtime moves its messages with.

Held byte for byte against rclpy's own serializer (rmw_cyclonedds_cpp, in a child process) for
every message type the nodes use, and against the type store; decoding gives back the fields.
"""
import json
from pathlib import Path
import struct
import subprocess
import sys

from hypothesis import given, settings
from hypothesis import strategies as st
import pytest
from runtimes import require_rclpy

from bellows_ros.runtime import cdr

PROBE = Path(__file__).resolve().parent / 'cdr_probe.py'
STAMP = {'sec': -7, 'nanosec': 999_999_999}
CASES = [
    ('builtin_interfaces/msg/Time', STAMP),
    ('std_msgs/msg/Float64', {'data': -1.5e-300}),
    ('std_msgs/msg/Bool', {'data': True}),
    ('sensor_msgs/msg/JointState', {
        'header': {'stamp': STAMP, 'frame_id': 'base_ü'},
        'name': ['segment_1', '', 'a' * 13], 'position': [0.25, -3.0, 1e300],
        'velocity': [], 'effort': [2.5e5]}),
    ('sensor_msgs/msg/JointState', {}),
    ('geometry_msgs/msg/WrenchStamped', {
        'header': {'frame_id': 'actuator'}, 'wrench': {'force': {'z': -12.5},
                                                       'torque': {'x': 1.0}}}),
    ('diagnostic_msgs/msg/DiagnosticArray', {
        'header': {'stamp': STAMP}, 'status': [
            {'level': 1, 'name': 'driver: arm', 'message': 'late', 'hardware_id': 'can0',
             'values': [{'key': 'rate_hz', 'value': '998.2'}, {'key': 'k', 'value': ''}]},
            {'level': 0, 'name': 'driver: actuator', 'values': []}]}),
    ('rosgraph_msgs/msg/Clock', {'clock': {'sec': 3, 'nanosec': 5}}),
    ('lifecycle_msgs/msg/TransitionEvent', {
        'timestamp': 2 ** 63 + 5, 'transition': {'id': 3, 'label': 'activate'},
        'start_state': {'id': 2, 'label': 'inactive'},
        'goal_state': {'id': 13, 'label': 'activating'}}),
    ('trajectory_msgs/msg/JointTrajectory', {
        'header': {'stamp': STAMP}, 'joint_names': ['segment_2', 'segment_1'], 'points': [
            {'positions': [0.5, -0.25], 'time_from_start': {'sec': 1, 'nanosec': 500_000_000}},
            {'positions': [0.0, 0.0], 'velocities': [0.0, 0.0], 'accelerations': [1.0, -1.0],
             'time_from_start': {'sec': 3, 'nanosec': 0}}]}),
    ('control_msgs/msg/JointTrajectoryControllerState', {
        'header': {'stamp': STAMP}, 'joint_names': ['segment_1'],
        'reference': {'positions': [0.7], 'velocities': [0.1], 'accelerations': [0.0],
                      'time_from_start': {'sec': 2, 'nanosec': 7}},
        'feedback': {'positions': [0.69], 'velocities': [0.12]},
        'error': {'positions': [0.01], 'velocities': [-0.02]}, 'output': {'effort': [1.5]},
        'speed_scaling_factor': 1.0}),
]


def test_every_type_the_nodes_use_has_a_plan():
    for ros_name in cdr.USED_TYPES.values():
        assert cdr.plan(ros_name, cdr.plain_class) is not None, ros_name


def test_bytes_are_rclpys_and_decode_back():
    require_rclpy()
    cases = [{'type': ros_name, 'fields': fields} for ros_name, fields in CASES]
    assert {case['type'] for case in cases} >= set(cdr.USED_TYPES.values()) - {
        'std_msgs/msg/Header', 'geometry_msgs/msg/Vector3', 'geometry_msgs/msg/Wrench',
        'diagnostic_msgs/msg/KeyValue', 'diagnostic_msgs/msg/DiagnosticStatus',
        'builtin_interfaces/msg/Duration', 'trajectory_msgs/msg/JointTrajectoryPoint'}  # nested
    result = subprocess.run([sys.executable, str(PROBE)], input='\n'.join(map(json.dumps, cases)),
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    lines = [json.loads(line) for line in result.stdout.splitlines()]
    assert len(lines) == len(cases)
    for case, line in zip(cases, lines):
        assert line['cdr'] == line['rclpy'], case['type']
        assert _subset(case['fields'], line['decoded']), (case, line['decoded'])


def _subset(given, decoded):
    """Every value given is decoded (the rest are defaults)."""
    if isinstance(given, dict):
        return all(_subset(value, decoded[name]) for name, value in given.items())
    if isinstance(given, list):
        return len(given) == len(decoded) and all(map(_subset, given, decoded))
    return given == decoded


@settings(max_examples=200, deadline=None)
@given(st.lists(st.text(max_size=9), max_size=5), st.lists(st.floats(), max_size=5),
       st.integers(-2**31, 2**31 - 1), st.text(max_size=5))
def test_round_trip_any_joint_state(names, values, sec, frame):
    cls = cdr.plain_class('sensor_msgs/msg/JointState')
    steps = cdr.plan(cls.__ros_type__, cdr.plain_class)
    message = cls(name=names, effort=values)
    message.header.stamp.sec, message.header.frame_id = sec, frame
    data = cdr.encode(steps, message)
    assert bytes(cdr.TYPESTORE.serialize_cdr(
        cdr.TYPESTORE.deserialize_cdr(data, cls.__ros_type__), cls.__ros_type__)) == data
    back = cdr.decode(steps, cls, data)
    assert back.name == names and back.header.stamp.sec == sec and back.header.frame_id == frame
    assert [repr(v) for v in back.effort] == [repr(v) for v in values]  # NaN, -0.0 too


def test_another_encapsulation_is_a_value_error():
    cls = cdr.plain_class('std_msgs/msg/Float64')
    steps = cdr.plan(cls.__ros_type__, cdr.plain_class)
    big_endian = b'\x00\x00\x00\x00' + struct.pack('>d', 2.0)
    with pytest.raises(ValueError, match='not little-endian plain CDR'):
        cdr.decode(steps, cls, big_endian)


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=120))
def test_any_bytes_decode_to_a_message_or_a_value_error(tail):
    cls = cdr.plain_class('diagnostic_msgs/msg/DiagnosticArray')
    steps = cdr.plan(cls.__ros_type__, cdr.plain_class)
    try:
        message = cdr.decode(steps, cls, cdr.HEADER + tail)
    except ValueError as error:
        assert str(error).startswith('malformed CDR')
        return
    assert isinstance(message, cls)
