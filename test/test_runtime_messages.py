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
The message classes the nodes use (runtime/messages.py) and the type store the bags are read with.

The nodes publish the ROS packages' own classes; the recorder writes their CDR bytes as they came
and bellows_ros.io.bag reads them back with rosbags' Jazzy type store (plus the definitions rosbags
lacks, bag.EXTRA_DEFINITIONS). So the classes must import, the store must hold the same fields
and decode rclpy's bytes to the same values, and a definition the store adds must be the
installed package's, to the RIHS01 hash a publisher of that type advertises.
"""
import importlib.util
import json
import os
from pathlib import Path

import pytest
from rclpy.serialization import deserialize_message, serialize_message

from bellows_ros.io.bag import EXTRA_DEFINITIONS, TYPESTORE
from bellows_ros.runtime import messages
from bellows_ros.runtime.messages import message_class, msg, srv, USED_SERVICES, USED_TYPES


def installed(package):
    return importlib.util.find_spec(package) is not None


def test_every_used_type_imports_but_the_optional_packages():
    for short, ros_name in USED_TYPES.items():
        package = ros_name.split('/')[0]
        if package in messages.OPTIONAL_PACKAGES and not installed(package):
            assert getattr(msg, short) is None, short
            with pytest.raises(ImportError):
                message_class(ros_name)
            continue
        cls = message_class(ros_name)
        assert getattr(msg, short) is cls, short
        # the ROS package's own generated class, not a look-alike
        assert cls.__module__.startswith(f'{package}.msg'), (ros_name, cls.__module__)
    assert messages.OPTIONAL_PACKAGES == ('control_msgs',)  # everything else must import
    for ros_name in USED_SERVICES:
        assert getattr(srv, ros_name.rsplit('/', 1)[1]) is message_class(ros_name)


def importable_types():
    return [name for name in USED_TYPES.values() if installed(name.split('/')[0])]


def test_the_type_store_has_the_fields_of_every_class():
    """bellows_ros.io.bag decodes with the same fields, in the same order, as the nodes publish."""
    for ros_name in USED_TYPES.values():
        assert ros_name in TYPESTORE.fielddefs, ros_name  # also the optional ones: bags hold them
    for ros_name in importable_types():
        _, fields = TYPESTORE.fielddefs[ros_name]
        assert [name for name, _ in fields] == list(
            message_class(ros_name).get_fields_and_field_types()), ros_name


def installed_description(ros_name):
    """Return the type description JSON a ROS 2 package installs for `ros_name`, or None."""
    package, _, name = ros_name.split('/')
    prefixes = os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep)
    for prefix in [p for p in prefixes if p]:
        path = Path(prefix) / 'share' / package / 'msg' / f'{name}.json'
        if path.is_file():
            return json.loads(path.read_text())
    return None


def advertised_hash(ros_name):
    description = installed_description(ros_name)
    if description is None:
        return None
    return {h['type_name']: h['hash_string'] for h in description['type_hashes']}[ros_name]


def test_the_type_store_has_the_hash_of_every_installed_type():
    """A bag's metadata names each topic's type hash: the one its publishers advertise."""
    checked = [name for name in importable_types() if advertised_hash(name) is not None]
    assert 'sensor_msgs/msg/JointState' in checked, 'no installed type descriptions found'
    for ros_name in checked:
        assert TYPESTORE.hash_rihs01(ros_name) == advertised_hash(ros_name), ros_name


def test_added_definitions_have_the_hash_ros_advertises():
    """A type registered from .msg text is the installed package's, to the RIHS01 hash."""
    assert set(EXTRA_DEFINITIONS) == {'control_msgs/msg/JointTrajectoryControllerState'}
    for ros_name in EXTRA_DEFINITIONS:
        value = TYPESTORE.hash_rihs01(ros_name)
        assert value.startswith('RIHS01_') and len(value) == 7 + 64
        expected = advertised_hash(ros_name)
        if expected is None:
            pytest.skip(f'{ros_name.split("/")[0]} is not installed here (no PyPI wheel): its '
                        'advertised hash cannot be compared')
        assert value == expected, ros_name


def test_defaults_and_constants():
    state = msg.JointState()
    assert state.name == [] and list(state.effort) == [] and state.header.stamp.sec == 0
    # a `byte` constant is bytes in rclpy's classes (nodes/diagnostics.py converts)
    assert msg.DiagnosticStatus.ERROR == b'\x02' and msg.DiagnosticStatus.STALE == b'\x03'
    other = msg.JointState()
    state.name.append('x')
    assert other.name == []  # defaults are per instance, not shared


def test_rclpy_bytes_decode_with_the_type_store():
    """What the recorder writes (rclpy's CDR, as it came) is what bellows_ros.io.bag reads."""
    state = msg.JointState(name=['segment_1', 'air_chamber'], position=[0.25, -0.003],
                           velocity=[1.5, 0.0], effort=[2.5e5, 1.1e5])
    state.header.stamp.sec, state.header.stamp.nanosec = 12, 345_678_901
    state.header.frame_id = 'base'
    data = serialize_message(state)
    back = TYPESTORE.deserialize_cdr(data, 'sensor_msgs/msg/JointState')
    assert (back.header.stamp.sec, back.header.stamp.nanosec) == (12, 345_678_901)
    assert back.header.frame_id == 'base' and back.name == ['segment_1', 'air_chamber']
    assert list(back.position) == [0.25, -0.003] and list(back.effort) == [2.5e5, 1.1e5]
    # and back: the store's bytes are rclpy's message (alignment padding may differ in value)
    again = bytes(TYPESTORE.serialize_cdr(back, 'sensor_msgs/msg/JointState'))
    assert len(again) == len(data) and deserialize_message(again, msg.JointState) == state


def test_nested_sequences_decode_with_the_type_store():
    array = msg.DiagnosticArray(status=[
        msg.DiagnosticStatus(level=msg.DiagnosticStatus.WARN, name='driver: arm', message='late',
                             values=[msg.KeyValue(key='rate_hz', value='998.2')]),
        msg.DiagnosticStatus(level=msg.DiagnosticStatus.OK, name='driver: actuator')])
    data = serialize_message(array)
    back = TYPESTORE.deserialize_cdr(data, 'diagnostic_msgs/msg/DiagnosticArray')
    assert [(s.level, s.name) for s in back.status] == [
        (1, 'driver: arm'), (0, 'driver: actuator')]
    assert back.status[0].values[0].key == 'rate_hz' and back.status[0].values[0].value == '998.2'
    wrench = msg.WrenchStamped()
    wrench.wrench.torque.z = -6.7
    back = TYPESTORE.deserialize_cdr(serialize_message(wrench), 'geometry_msgs/msg/WrenchStamped')
    assert back.wrench.torque.z == -6.7
