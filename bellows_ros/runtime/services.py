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
ROS 2 services on plain Cyclone DDS, on the wire as rmw_cyclonedds_cpp (Jazzy) puts them.

A service `/n/vent` of type `std_srvs/srv/Trigger` is two DDS topics: requests on
`rq/n/ventRequest` of type `std_srvs::srv::dds_::Trigger_Request_`, replies on
`rr/n/ventReply` of type `std_srvs::srv::dds_::Trigger_Response_`. Each sample starts with the
request header rmw_cyclonedds_cpp writes before the message (`cdds_request_header_t`: the client's
64-bit writer id, then the 64-bit sequence number, plain CDR); a reply carries its request's
header back, which is how the client finds its answers. The service's reader and writer carry
`serviceid=<id>;` in their USER_DATA: a ROS 2 client takes a service as available once it has
matched a request reader and a reply writer with the same id (`rmw_service_server_is_available`),
and the typehash of the request and reply types, as every rmw_cyclonedds_cpp endpoint does.

The service types come from their .srv definitions (`cdr.USED_SERVICES`; the rosbags type
store holds no services): `srv.Trigger.Request` / `.Response` are plain message classes like
`msg.*`; the wire classes add the header. The rclpy runtime uses rclpy's own service classes;
callbacks are written once, `callback(request, response) -> response`, as in rclpy.
"""
import dataclasses
import types

from cyclonedds.idl import IdlMeta, IdlStruct
from cyclonedds.idl import types as idl
from rosbags.typesys import get_types_from_msg
from rosbags.typesys.base import Nodetype

from bellows_ros.runtime.cdr import TYPESTORE, USED_SERVICES
from bellows_ros.runtime.messages import dds_type_name, message_class

# What ROS's IDL gives a message with no fields (rosidl): one uint8, so the struct is not empty.
_EMPTY = [('structure_needs_at_least_one_member', (Nodetype.BASE, ('uint8', 0)))]


def _register():
    """Put each service's request and reply into the type store, parsed from its .srv text."""
    fielddefs = {}
    for ros_name, text in USED_SERVICES.items():
        package = ros_name.split('/')[0]
        for suffix, part in zip(('_Request', '_Response'), text.split('---')):
            # rosbags reads .msg text; a short type name is resolved in the package named here.
            parsed = get_types_from_msg(part, f'{package}/msg/_{suffix}')
            (_, fields), = parsed.values()
            fielddefs[ros_name + suffix] = ([], fields or _EMPTY)
    TYPESTORE.register(fielddefs)


_register()


def _wire_class(ros_name):
    """Build the DDS type of a request or reply: the request header, then the message's fields."""
    plain = message_class(ros_name)
    class_name = ros_name.split('/')[-1]
    namespace = IdlMeta.__prepare__(class_name, (IdlStruct,), typename=dds_type_name(ros_name))
    namespace['__annotations__']['client_guid'] = idl.uint64
    namespace['client_guid'] = 0
    namespace['sequence_number'] = 0
    namespace['__annotations__']['sequence_number'] = idl.int64
    for field in dataclasses.fields(plain):
        namespace['__annotations__'][field.name] = plain.__annotations__[field.name]
        namespace[field.name] = dataclasses.field(default_factory=field.default_factory)
    cls = dataclasses.dataclass(IdlMeta(class_name, (IdlStruct,), namespace))
    cls.__ros_type__ = ros_name
    cls.plain = plain
    return cls


@dataclasses.dataclass(frozen=True)
class ServiceType:
    """A service type: its name, the plain Request/Response classes and their wire classes."""

    name: str
    Request: type
    Response: type
    WireRequest: type
    WireResponse: type


def service_type(ros_name):
    """Return the ServiceType of a service name such as 'std_srvs/srv/Trigger'."""
    return ServiceType(ros_name, message_class(ros_name + '_Request'),
                       message_class(ros_name + '_Response'), _wire_class(ros_name + '_Request'),
                       _wire_class(ros_name + '_Response'))


def fields_of(message):
    """{field: value} of a plain or wire message, without the request header."""
    return {f.name: getattr(message, f.name) for f in dataclasses.fields(message)
            if f.name not in ('client_guid', 'sequence_number')}


srv = types.SimpleNamespace(**{name.rsplit('/', 1)[1]: service_type(name)
                               for name in USED_SERVICES})
