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
ROS 2's parameter services on the DDS runtime, so `ros2 param` reaches its nodes.

rclpy serves them itself (rclpy/parameter_service.py); this is the same interface for a node of
runtime/dds_node.py: `~/list_parameters`, `~/get_parameters`, `~/get_parameter_types`,
`~/describe_parameters`, `~/set_parameters` and `~/set_parameters_atomically` (rcl_interfaces
services, on rmw_cyclonedds_cpp's wire: runtime/services.py). A set goes through the node's
`set_parameters`, so it is checked exactly as on rclpy: declared, same type, the node's
callbacks (runtime/node.py: read-only, range, choices), then stored.
"""
from bellows_ros.runtime.messages import message_class

# ParameterType's constants and the ParameterValue field of each (rcl_interfaces).
_TYPES = ((1, 'bool_value', bool), (2, 'integer_value', int), (3, 'double_value', float),
          (4, 'string_value', str))
_ARRAY_TYPES = ((6, 'bool_array_value', bool), (7, 'integer_array_value', int),
                (8, 'double_array_value', float), (9, 'string_array_value', str))
BYTE_ARRAY = (5, 'byte_array_value')


def type_id(value):
    """rcl_interfaces/ParameterType of a Python value (0 = not set)."""
    if isinstance(value, (list, tuple)):
        for type_id_, _field, kind in _ARRAY_TYPES:
            if value and all(type(element) is kind for element in value):
                return type_id_
        return 8 if not value else 0  # an empty array: rcl reads it as a double array
    if isinstance(value, bytes):
        return BYTE_ARRAY[0]
    for type_id_, _field, kind in _TYPES:
        if type(value) is kind:
            return type_id_
    return 0


def to_message(value):
    """Python value -> rcl_interfaces/ParameterValue."""
    message = message_class('rcl_interfaces/msg/ParameterValue')(type=type_id(value))
    for type_id_, field, _kind in _TYPES + _ARRAY_TYPES + (BYTE_ARRAY + (bytes,),):
        if type_id_ == message.type:
            setattr(message, field, list(value) if isinstance(value, (list, tuple, bytes))
                    else value)
    return message


def from_message(message):
    """rcl_interfaces/ParameterValue -> Python value (None when not set)."""
    for type_id_, field, _kind in _TYPES + _ARRAY_TYPES + (BYTE_ARRAY + (bytes,),):
        if type_id_ == message.type:
            value = getattr(message, field)
            return bytes(value) if type_id_ == BYTE_ARRAY[0] else (
                list(value) if isinstance(value, (list, tuple)) else value)
    return None


class ParameterServices:
    """The six rcl_interfaces parameter services of one DDS-runtime node."""

    def __init__(self, node, srv):
        self.node = node
        for name, srv_type, callback in (
                ('list_parameters', srv.ListParameters, self.list_parameters),
                ('get_parameters', srv.GetParameters, self.get_parameters),
                ('get_parameter_types', srv.GetParameterTypes, self.get_parameter_types),
                ('describe_parameters', srv.DescribeParameters, self.describe_parameters),
                ('set_parameters', srv.SetParameters, self.set_parameters),
                ('set_parameters_atomically', srv.SetParametersAtomically,
                 self.set_parameters_atomically)):
            node.create_service(srv_type, f'~/{name}', callback)

    def list_parameters(self, request, response):
        # rclpy's rule: a name under any prefix (or every name), no deeper than `depth` dots
        # (0 = any depth); the prefixes of the names found are listed too.
        names, prefixes = [], set()
        for name in self.node.parameter_names():
            if request.prefixes and not any(name == p or name.startswith(p + '.')
                                            for p in request.prefixes):
                continue
            if request.depth and name.count('.') >= request.depth:
                continue
            names.append(name)
            if '.' in name:
                prefixes.add(name.rsplit('.', 1)[0])
        response.result.names, response.result.prefixes = names, sorted(prefixes)
        return response

    def get_parameters(self, request, response):
        response.values = [to_message(self.node.get_parameter(name).value)
                           if self.node.has_parameter(name)
                           else message_class('rcl_interfaces/msg/ParameterValue')()
                           for name in request.names]
        return response

    def get_parameter_types(self, request, response):
        response.types = [type_id(self.node.get_parameter(name).value)
                          if self.node.has_parameter(name) else 0 for name in request.names]
        return response

    def describe_parameters(self, request, response):
        response.descriptors = [self.node.describe_parameter(name) for name in request.names
                                if self.node.has_parameter(name)]
        return response

    def set_parameters(self, request, response):
        response.results = [self.node.set_parameter(p.name, from_message(p.value))
                            for p in request.parameters]
        return response

    def set_parameters_atomically(self, request, response):
        response.result = self.node.set_parameters_atomically(
            {p.name: from_message(p.value) for p in request.parameters})
        return response
