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

"""Message classes built from the rosbags Jazzy type store: names, defaults, CDR round trips."""
import json
import os
from pathlib import Path

from rosbags.typesys import get_typestore, Stores
from node_processes import require_rclpy

from bellows_ros.runtime.cdr import EXTRA_DEFINITIONS, TYPESTORE
from bellows_ros.runtime.messages import (dds_type_name, from_typestore, message_class, msg,
                                          to_typestore, type_hash, USED_TYPES)

STORE = get_typestore(Stores.ROS2_JAZZY)


def test_dds_type_names_follow_ros2_convention():
    assert dds_type_name('sensor_msgs/msg/JointState') == 'sensor_msgs::msg::dds_::JointState_'
    assert msg.JointState.__idl__.idl_transformed_typename == 'sensor_msgs::msg::dds_::JointState_'
    assert msg.Clock.__idl__.idl_transformed_typename == 'rosgraph_msgs::msg::dds_::Clock_'


def test_fields_come_from_the_type_store():
    for ros_name in USED_TYPES.values():
        cls = message_class(ros_name)
        _, fields = TYPESTORE.fielddefs[ros_name]
        assert list(cls.__dataclass_fields__) == [name for name, _ in fields], ros_name
        # rosbags' own definitions, but for the types it lacks
        assert (ros_name in STORE.fielddefs) != (ros_name in EXTRA_DEFINITIONS), ros_name


def installed_description(ros_name):
    """Return the type description JSON a ROS 2 package installs for `ros_name`, or None."""
    package, _, name = ros_name.split('/')
    for prefix in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep):
        path = Path(prefix) / 'share' / package / 'msg' / f'{name}.json'
        if prefix and path.is_file():
            return json.loads(path.read_text())
    return None


def test_added_definitions_have_the_hash_ros_advertises():
    """A type registered from .msg text is the installed package's, to the RIHS01 hash."""
    for ros_name in EXTRA_DEFINITIONS:
        description = installed_description(ros_name)
        if description is None:
            require_rclpy()  # no ROS 2 here: skipped (or failed where ROS 2 was installed)
        hashes = {h['type_name']: h['hash_string'] for h in description['type_hashes']}
        assert type_hash(ros_name) == hashes[ros_name]


def test_defaults_and_constants_like_rclpy():
    state = msg.JointState()
    assert state.name == [] and state.effort == [] and state.header.stamp.sec == 0
    assert msg.DiagnosticStatus.ERROR == 2 and msg.DiagnosticStatus.STALE == 3
    # Defaults are per instance, not shared.
    other = msg.JointState()
    state.name.append('x')
    assert other.name == []


def test_cdr_is_byte_identical_to_the_type_store():
    state = msg.JointState(name=['segment_1', 'air_chamber'], position=[0.25, -0.003],
                           velocity=[1.5, 0.0], effort=[2.5e5, 1.1e5])
    state.header.stamp.sec, state.header.stamp.nanosec = 12, 345_678_901
    state.header.frame_id = 'base'
    data = state.serialize()
    assert bytes(STORE.serialize_cdr(to_typestore(state), 'sensor_msgs/msg/JointState')) == data
    back = msg.JointState.deserialize(data)
    assert back == state
    assert from_typestore(STORE.deserialize_cdr(data, 'sensor_msgs/msg/JointState'),
                          'sensor_msgs/msg/JointState') == state


def test_nested_sequences_round_trip():
    array = msg.DiagnosticArray(status=[
        msg.DiagnosticStatus(level=msg.DiagnosticStatus.WARN, name='driver: arm', message='late',
                             values=[msg.KeyValue(key='rate_hz', value='998.2')]),
        msg.DiagnosticStatus(level=msg.DiagnosticStatus.OK, name='driver: actuator')])
    data = array.serialize()
    assert bytes(STORE.serialize_cdr(to_typestore(array),
                                     'diagnostic_msgs/msg/DiagnosticArray')) == data
    assert msg.DiagnosticArray.deserialize(data) == array
    wrench = msg.WrenchStamped()
    wrench.wrench.torque.z = -6.7
    assert msg.WrenchStamped.deserialize(wrench.serialize()).wrench.torque.z == -6.7


def test_type_hash_is_rihs01():
    value = type_hash('sensor_msgs/msg/JointState')
    assert value.startswith('RIHS01_') and len(value) == 7 + 64
    assert value == STORE.hash_rihs01('sensor_msgs/msg/JointState')
