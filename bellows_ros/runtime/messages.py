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
ROS 2 message classes for Cyclone DDS, generated from the rosbags Jazzy type store.

The definitions are not hand-copied: each class is built from `typestore.fielddefs`, recursively,
so `JointState` pulls in `std_msgs/Header` and `builtin_interfaces/Time`. The DDS type names follow
ROS 2's convention (`sensor_msgs/msg/JointState` -> `sensor_msgs::msg::dds_::JointState_`), which
is what `rmw_cyclonedds_cpp` registers, so ROS 2 nodes and these classes match on the wire.

The classes look like rclpy's messages where the nodes touch them: keyword construction with
defaults for every field (`JointState(name=[...], effort=[...])`), attribute access
(`msg.header.stamp.sec`), and the constants of the .msg file (`DiagnosticStatus.OK`).
"""
import dataclasses

from cyclonedds.idl import IdlMeta, IdlStruct
from cyclonedds.idl import types as idl
from rosbags.typesys.base import Nodetype

from bellows_ros.runtime import cdr
from bellows_ros.runtime.cdr import TYPESTORE, USED_TYPES  # noqa: F401 (this module's interface)

# ROS 2 .msg primitive -> IDL type. In ROS 2's IDL mapping `byte` is an octet and `char` a uint8.
_BASE = {
    'bool': bool, 'byte': idl.byte, 'char': idl.uint8,
    'int8': idl.int8, 'uint8': idl.uint8, 'int16': idl.int16, 'uint16': idl.uint16,
    'int32': idl.int32, 'uint32': idl.uint32, 'int64': idl.int64, 'uint64': idl.uint64,
    'float32': idl.float32, 'float64': idl.float64, 'string': str,
}


def dds_type_name(ros_name):
    """'sensor_msgs/msg/JointState' -> 'sensor_msgs::msg::dds_::JointState_' (ROS 2 wire name)."""
    package, kind, name = ros_name.split('/')
    return f'{package}::{kind}::dds_::{name}_'


def type_hash(ros_name):
    """Return the RIHS01 type hash ROS 2 Jazzy advertises for `ros_name` (REP 2011)."""
    return TYPESTORE.hash_rihs01(ros_name)


_classes = {}


def message_class(ros_name):
    """Return the IdlStruct class for a ROS message type, built (once) from the type store."""
    if ros_name not in _classes:
        _classes[ros_name] = _build(ros_name)
    return _classes[ros_name]


def _build(ros_name):
    constants, fields = TYPESTORE.fielddefs[ros_name]
    class_name = ros_name.split('/')[-1]
    namespace = IdlMeta.__prepare__(class_name, (IdlStruct,), typename=dds_type_name(ros_name))
    for field_name, desc in fields:
        annotation, default = _field(desc)
        namespace['__annotations__'][field_name] = annotation
        namespace[field_name] = dataclasses.field(default_factory=default)
    cls = dataclasses.dataclass(IdlMeta(class_name, (IdlStruct,), namespace))
    for name, _type, value in constants:
        setattr(cls, name, value)
    cls.__ros_type__ = ros_name
    _add_fast_cdr(cls, ros_name)
    return cls


# --- fast plain-CDR path
# ----------------------------------------------------------------------------- cyclonedds' generic
# serializer walks a tree of "machines" per field and costs ~40 us per JointState to write and ~60
# us to read: at 1 kHz x 2 topics that was a fifth of a core per node. For the types runtime/cdr.py
# can carry, the same XCDR1 little-endian bytes (what the writers use, `use_cdrv0_representation`)
# come from its struct-based codec, compiled once per type from the same type-store definition.
# Anything else (XCDR2, big endian, types without a plan) goes through cyclonedds.


def _add_fast_cdr(cls, ros_name):
    """Give `cls` the struct-based XCDR1 little-endian path where its type allows it."""
    steps = cdr.plan(ros_name, message_class)
    if steps is None or not cdr.LITTLE_ENDIAN:
        return
    generic_serialize, generic_deserialize = cls.serialize, cls.deserialize

    def serialize(self, buffer=None, endianness=None, use_version_2=None):
        if buffer is not None or endianness is not None or use_version_2 is not False:
            return generic_serialize(self, buffer=buffer, endianness=endianness,
                                     use_version_2=use_version_2)
        return cdr.encode(steps, self)

    def deserialize(klass, data, has_header=True, use_version_2=None):
        if has_header and use_version_2 is None and isinstance(data, (bytes, bytearray)) \
                and data[:4] == cdr.HEADER:
            return cdr.decode(steps, klass, data)
        return generic_deserialize(data, has_header=has_header, use_version_2=use_version_2)

    cls.serialize = serialize
    cls.deserialize = classmethod(deserialize)


def _field(desc):
    """(IDL annotation, default factory) for one rosbags field description."""
    return _annotation(desc), cdr.default_factory(desc, message_class)


def _annotation(desc):
    kind, detail = desc
    if kind == Nodetype.BASE:
        base, bound = detail
        return idl.bounded_str[bound] if base == 'string' and bound else _BASE[base]
    if kind == Nodetype.NAME:
        return message_class(detail)
    if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        inner, count = detail
        annotation = _annotation(inner)
        if kind == Nodetype.ARRAY:
            return idl.array[annotation, count]
        return idl.sequence[annotation, count] if count else idl.sequence[annotation]
    raise TypeError(f'unsupported field kind {kind!r} in the type store')


def to_typestore(msg):
    """Convert a message instance into the type store's class of the same type (for rosbag2)."""
    ros_name = type(msg).__ros_type__
    store_cls = TYPESTORE.types[ros_name]
    _, fields = TYPESTORE.fielddefs[ros_name]
    values = {}
    for field_name, desc in fields:
        values[field_name] = _convert(getattr(msg, field_name), desc, to_store=True)
    return store_cls(**values)


def from_typestore(obj, ros_name):
    """Convert a type-store message object (e.g. read from a bag) into this module's class."""
    _, fields = TYPESTORE.fielddefs[ros_name]
    values = {name: _convert(getattr(obj, name), desc, to_store=False) for name, desc in fields}
    return message_class(ros_name)(**values)


def _convert(value, desc, to_store):
    import numpy as np
    kind, detail = desc
    if kind == Nodetype.BASE:
        return value.item() if hasattr(value, 'item') else value
    if kind == Nodetype.NAME:
        return to_typestore(value) if to_store else from_typestore(value, detail)
    inner, _count = detail
    if inner[0] == Nodetype.BASE and inner[1][0] != 'string':
        # rosbags keeps numeric arrays as NumPy arrays; the DDS classes use lists.
        if to_store:
            return np.asarray(value, dtype=_numpy_dtype(inner[1][0]))
        return [item.item() for item in value]
    return [_convert(item, inner, to_store) for item in value]


def _numpy_dtype(base):
    return {'bool': 'bool', 'byte': 'uint8', 'char': 'uint8', 'float32': 'float32',
            'float64': 'float64'}.get(base, base)


class MessageModule:
    """Namespace holding the classes by short name: `msg.JointState`, `msg.Float64`, ..."""

    def __init__(self):
        for short, ros_name in USED_TYPES.items():
            setattr(self, short, message_class(ros_name))


msg = MessageModule()
