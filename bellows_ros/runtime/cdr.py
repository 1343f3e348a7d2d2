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
ROS 2 messages on the wire, in pure Python: their definitions, plain classes and CDR bytes.

The definitions come from the rosbags Jazzy type store (not hand-copied). A *plan* is one type's
fields compiled once into (name, kind, detail) steps; `encode` and `decode` walk it with `struct`
and produce and read the bytes every ROS 2 Jazzy rmw puts on the wire for these types: plain CDR
(XCDR1), little endian, behind the 4-byte encapsulation header. No DDS library is imported here,
so both runtimes use it: the DDS runtime inside its cyclonedds classes (runtime/messages.py), the
rclpy runtime to move the nodes' messages as serialized bytes (runtime/rclpy_runtime.py), where
rclpy's own C <-> Python message conversion cost the model node more than its model.

Supported: primitives, unbounded strings, nested messages, unbounded sequences of those. Anything
else (bounded types, fixed arrays, big endian) has no plan: `plan` returns None.
"""
from array import array
import dataclasses
import struct
import sys

from rosbags.typesys import get_types_from_msg, get_typestore, Stores
from rosbags.typesys.base import Nodetype

# The message types the nodes publish or subscribe to (ROS names), and the short names they go by.
USED_TYPES = {
    'Time': 'builtin_interfaces/msg/Time',
    'Header': 'std_msgs/msg/Header',
    'Float64': 'std_msgs/msg/Float64',
    'Bool': 'std_msgs/msg/Bool',
    'JointState': 'sensor_msgs/msg/JointState',
    'Vector3': 'geometry_msgs/msg/Vector3',
    'Wrench': 'geometry_msgs/msg/Wrench',
    'WrenchStamped': 'geometry_msgs/msg/WrenchStamped',
    'KeyValue': 'diagnostic_msgs/msg/KeyValue',
    'DiagnosticStatus': 'diagnostic_msgs/msg/DiagnosticStatus',
    'DiagnosticArray': 'diagnostic_msgs/msg/DiagnosticArray',
    'Clock': 'rosgraph_msgs/msg/Clock',
    'TransitionEvent': 'lifecycle_msgs/msg/TransitionEvent',
    'Duration': 'builtin_interfaces/msg/Duration',
    'JointTrajectoryPoint': 'trajectory_msgs/msg/JointTrajectoryPoint',
    'JointTrajectory': 'trajectory_msgs/msg/JointTrajectory',
    'JointTrajectoryControllerState': 'control_msgs/msg/JointTrajectoryControllerState',
}

# The services the nodes offer, as their .srv files define them (request --- response); the
# DDS runtime builds them (runtime/services.py), rclpy has its own classes.
USED_SERVICES = {
    'std_srvs/srv/Trigger': '---\nbool success\nstring message',
    'std_srvs/srv/SetBool': 'bool data\n---\nbool success\nstring message',
    # A managed node's services (rcl_lifecycle's; runtime/lifecycle.py serves them).
    'lifecycle_msgs/srv/ChangeState': 'lifecycle_msgs/Transition transition\n---\nbool success',
    'lifecycle_msgs/srv/GetState': '---\nlifecycle_msgs/State current_state',
    'lifecycle_msgs/srv/GetAvailableStates': '---\nlifecycle_msgs/State[] available_states',
    'lifecycle_msgs/srv/GetAvailableTransitions':
        '---\nlifecycle_msgs/TransitionDescription[] available_transitions',
    # Every node's parameter services (the DDS runtime serves them: runtime/parameter_services.py).
    'rcl_interfaces/srv/ListParameters':
        'string[] prefixes\nuint64 depth\n---\nrcl_interfaces/ListParametersResult result',
    'rcl_interfaces/srv/GetParameters':
        'string[] names\n---\nrcl_interfaces/ParameterValue[] values',
    'rcl_interfaces/srv/GetParameterTypes': 'string[] names\n---\nuint8[] types',
    'rcl_interfaces/srv/DescribeParameters':
        'string[] names\n---\nrcl_interfaces/ParameterDescriptor[] descriptors',
    'rcl_interfaces/srv/SetParameters':
        'rcl_interfaces/Parameter[] parameters\n---\nrcl_interfaces/SetParametersResult[] results',
    'rcl_interfaces/srv/SetParametersAtomically':
        'rcl_interfaces/Parameter[] parameters\n---\nrcl_interfaces/SetParametersResult result',
}

# Types the rosbags Jazzy store lacks (it holds only ROS 2's core packages): their .msg text as
# Jazzy's package installs it, comments left out (they are not part of the type, nor of its hash:
# test_runtime_messages.py holds the RIHS01 hash to the one the ROS 2 package advertises).
EXTRA_DEFINITIONS = {
    # control_msgs 5.x (ros2_control for Jazzy): joint_trajectory_controller's ~/controller_state.
    'control_msgs/msg/JointTrajectoryControllerState': """
std_msgs/Header header
string[] joint_names
trajectory_msgs/JointTrajectoryPoint reference
trajectory_msgs/JointTrajectoryPoint feedback
trajectory_msgs/JointTrajectoryPoint error
trajectory_msgs/JointTrajectoryPoint output
string[] multi_dof_joint_names
trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_reference
trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_feedback
trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_error
trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_output
float64 speed_scaling_factor
""",
}

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
for _name, _text in EXTRA_DEFINITIONS.items():
    TYPESTORE.register(get_types_from_msg(_text, _name))

LITTLE_ENDIAN = sys.byteorder == 'little'
HEADER = b'\x00\x01\x00\x00'  # encapsulation: plain CDR, little endian, no options
_U32 = struct.Struct('<I')
_STRUCT = {'bool': '?', 'byte': 'B', 'char': 'B', 'int8': 'b', 'uint8': 'B', 'int16': 'h',
           'uint16': 'H', 'int32': 'i', 'uint32': 'I', 'int64': 'q', 'uint64': 'Q',
           'float32': 'f', 'float64': 'd'}
_ZERO = {'bool': False, 'string': '', 'float32': 0.0, 'float64': 0.0}


def plan(ros_name, class_of):
    """
    Compile a type into steps for `encode`/`decode`, or None where this codec cannot carry it.

    `class_of(ros_name)` gives the class a nested message is read into (the caller's classes:
    cyclonedds structs for the DDS runtime, `plain_class` for rclpy).
    """
    steps = []
    for name, (kind, detail) in TYPESTORE.fielddefs[ros_name][1]:
        if kind == Nodetype.BASE:
            base, bound = detail
            if bound:
                return None
            steps.append((name, 'str', None) if base == 'string' else
                         (name, 'prim', _primitive(base)))
        elif kind == Nodetype.NAME:
            inner = plan(detail, class_of)
            if inner is None:
                return None
            steps.append((name, 'struct', (class_of(detail), inner)))
        elif kind == Nodetype.SEQUENCE and not detail[1]:
            (inner_kind, inner_detail), _bound = detail
            if inner_kind == Nodetype.BASE and not inner_detail[1]:
                base = inner_detail[0]
                steps.append((name, 'strseq', None) if base == 'string' else
                             (name, 'seq', _primitive(base)))
            elif inner_kind == Nodetype.NAME:
                inner = plan(inner_detail, class_of)
                if inner is None:
                    return None
                steps.append((name, 'structseq', (class_of(inner_detail), inner)))
            else:
                return None
        else:
            return None
    return steps


def _primitive(base):
    """(struct code, compiled little-endian Struct, size, CDR alignment) of a primitive type."""
    code = _STRUCT[base]
    packer = struct.Struct('<' + code)
    return code, packer, packer.size, min(packer.size, 8)


def encode(steps, obj):
    """Return the CDR bytes of message `obj` (any object with the fields' attributes)."""
    out = bytearray(HEADER)
    _write(steps, obj, out)
    return bytes(out)


def decode(steps, cls, data):
    """
    Read a message of class `cls` from CDR bytes.

    ValueError for another encapsulation and for bytes that are not a message of this type
    (cut short, a length past the end, a string that is not UTF-8).
    """
    if data[:2] != HEADER[:2]:
        raise ValueError(f'not little-endian plain CDR (encapsulation {bytes(data[:4]).hex()})')
    try:
        return _read(steps, cls, bytes(data), 4)[0]
    except (struct.error, UnicodeDecodeError) as error:
        raise ValueError(f'malformed CDR ({len(data)} bytes): {error}') from None


def _write(steps, obj, out):
    """
    Append `obj`'s CDR to `out`.

    `out` is a bytearray whose first 4 bytes are the encapsulation header; alignment counts from
    after it, as in XCDR1.
    """
    # Strings are written inline in both places below, as _read reads them: a helper call per
    # string measured 1-3 us more per JointState, on a path that runs 4000 times a second.
    for name, kind, detail in steps:
        value = getattr(obj, name)
        if kind == 'prim':
            out += bytes(-(len(out) - 4) % detail[3])
            out += detail[1].pack(value)
        elif kind == 'str':
            data = value.encode()
            out += bytes(-(len(out) - 4) % 4)
            out += _U32.pack(len(data) + 1) + data + b'\0'
        elif kind == 'struct':
            _write(detail[1], value, out)
        elif kind == 'seq':
            out += bytes(-(len(out) - 4) % 4)
            out += _U32.pack(len(value))
            if len(value):
                out += bytes(-(len(out) - 4) % detail[3])
                if isinstance(value, array) and value.typecode == detail[0] \
                        and LITTLE_ENDIAN:
                    out += value.tobytes()
                else:
                    out += struct.pack(f'<{len(value)}{detail[0]}', *value)
        elif kind == 'strseq':
            out += bytes(-(len(out) - 4) % 4)
            out += _U32.pack(len(value))
            for item in value:
                data = item.encode()
                out += bytes(-(len(out) - 4) % 4)
                out += _U32.pack(len(data) + 1) + data + b'\0'
        else:  # sequence of messages
            out += bytes(-(len(out) - 4) % 4)
            out += _U32.pack(len(value))
            for item in value:
                _write(detail[1], item, out)


def _read(steps, cls, data, pos):
    """Read an instance of `cls` from CDR `data` at `pos`; return it and the position after it."""
    values = {}
    for name, kind, detail in steps:
        if kind == 'prim':
            pos += -(pos - 4) % detail[3]
            values[name] = detail[1].unpack_from(data, pos)[0]
            pos += detail[2]
        elif kind == 'str':
            pos += -(pos - 4) % 4
            length = _U32.unpack_from(data, pos)[0]
            values[name] = data[pos + 4:pos + 3 + length].decode()
            pos += 4 + length
        elif kind == 'struct':
            values[name], pos = _read(detail[1], detail[0], data, pos)
        elif kind == 'seq':
            pos += -(pos - 4) % 4
            count = _U32.unpack_from(data, pos)[0]
            pos += 4
            if count:
                pos += -(pos - 4) % detail[3]
                values[name] = list(struct.unpack_from(f'<{count}{detail[0]}', data, pos))
                pos += count * detail[2]
            else:
                values[name] = []
        elif kind == 'strseq':
            pos += -(pos - 4) % 4
            count = _U32.unpack_from(data, pos)[0]
            pos += 4
            items = []
            for _ in range(count):
                pos += -(pos - 4) % 4
                length = _U32.unpack_from(data, pos)[0]
                items.append(data[pos + 4:pos + 3 + length].decode())
                pos += 4 + length
            values[name] = items
        else:  # sequence of messages
            pos += -(pos - 4) % 4
            count = _U32.unpack_from(data, pos)[0]
            pos += 4
            items = []
            for _ in range(count):
                item, pos = _read(detail[1], detail[0], data, pos)
                items.append(item)
            values[name] = items
    return cls(**values), pos


_plain = {}


def plain_class(ros_name):
    """
    Return a plain Python class for a ROS message type (built once): fields, defaults, constants.

    Like rclpy's classes where the nodes touch them: keyword construction with a default for
    every field, attribute access, the .msg file's constants (as numbers); `__ros_type__` names
    the type. Instances compare equal field by field.
    """
    if ros_name not in _plain:
        constants, fields = TYPESTORE.fielddefs[ros_name]
        specs = [(name, object,
                  dataclasses.field(default_factory=default_factory(desc, plain_class)))
                 for name, desc in fields]
        cls = dataclasses.make_dataclass(ros_name.split('/')[-1], specs, slots=True)
        for name, _type, value in constants:
            setattr(cls, name, value)
        cls.__ros_type__ = ros_name
        _plain[ros_name] = cls
    return _plain[ros_name]


def default_factory(desc, class_of):
    """
    Return the default factory of a field (a rosbags field description), as rclpy's defaults.

    Zero, False or '' for a primitive; `class_of(ros_name)` for a nested message; a list of
    defaults for a fixed array; an empty list for a sequence.
    """
    kind, detail = desc
    if kind == Nodetype.BASE:
        zero = _ZERO.get(detail[0], 0)
        return lambda: zero
    if kind == Nodetype.NAME:
        return class_of(detail)
    if kind == Nodetype.ARRAY:
        inner = default_factory(detail[0], class_of)
        return lambda: [inner() for _ in range(detail[1])]
    return list
