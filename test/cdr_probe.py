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
Child process of test_runtime_cdr.py: runtime/cdr.py against rclpy's own serializer.

Reads JSON cases from stdin ({type: ROS name, fields: nested values}), and for each prints one
JSON line: the bytes rclpy (rmw_cyclonedds_cpp) serializes the message to, the bytes cdr encodes
its plain class to, and the fields cdr decodes rclpy's bytes into. A process of its own: pytest
never loads rclpy (one Cyclone DDS library per process).
"""
import importlib
import json
import sys

from rclpy.serialization import serialize_message

from bellows_ros.runtime import cdr


def build(module_class, ros_name, fields):
    """Build a message of `module_class(ros_name)` from nested `fields` (dicts for messages)."""
    cls = module_class(ros_name)
    message = cls()
    definitions = dict(cdr.TYPESTORE.fielddefs[ros_name][1])
    for name, value in fields.items():
        kind, detail = definitions[name]
        if isinstance(value, dict):
            value = build(module_class, detail, value)
        elif isinstance(value, list) and value and isinstance(value[0], dict):
            value = [build(module_class, detail[0][1], item) for item in value]
        elif kind.name == 'BASE' and detail[0] == 'byte' and module_class is rclpy_class:
            value = bytes([value])
        setattr(message, name, value)
    return message


def rclpy_class(ros_name):
    package, kind, name = ros_name.split('/')
    return getattr(importlib.import_module(f'{package}.{kind}'), name)


def plain(message):
    """Return a decoded plain message as nested dicts and lists, for JSON."""
    if hasattr(message, '__ros_type__'):
        return {name: plain(getattr(message, name)) for name in message.__dataclass_fields__}
    if isinstance(message, list):
        return [plain(item) for item in message]
    return message


for line in sys.stdin:
    case = json.loads(line)
    ros_name = case['type']
    steps = cdr.plan(ros_name, cdr.plain_class)
    theirs = bytes(serialize_message(build(rclpy_class, ros_name, case['fields'])))
    ours = cdr.encode(steps, build(cdr.plain_class, ros_name, case['fields']))
    decoded = plain(cdr.decode(steps, cdr.plain_class(ros_name), theirs))
    print(json.dumps({'rclpy': theirs.hex(), 'cdr': ours.hex(), 'decoded': decoded}), flush=True)
