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
The opening of a subscriber script that knows nothing of bellows_ros.

Plain cyclonedds with its own IDL definitions under the ROS 2 type names, for tests that check the
graph speaks the ROS 2 wire format to an independent reader. A test appends its own reading loop
(`JOINT_STATE_SUBSCRIBER + textwrap.dedent(...)`) and runs the text with `python -c` or as a file.
"""
import textwrap

JOINT_STATE_SUBSCRIBER = textwrap.dedent("""
    import sys, time
    from dataclasses import dataclass
    from cyclonedds.core import Qos, Policy
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.idl import IdlStruct
    from cyclonedds.idl.types import int32, uint32, float64, sequence
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    @dataclass
    class Time(IdlStruct, typename='builtin_interfaces::msg::dds_::Time_'):
        sec: int32
        nanosec: uint32

    @dataclass
    class Header(IdlStruct, typename='std_msgs::msg::dds_::Header_'):
        stamp: Time
        frame_id: str

    @dataclass
    class JointState(IdlStruct, typename='sensor_msgs::msg::dds_::JointState_'):
        header: Header
        name: sequence[str]
        position: sequence[float64]
        velocity: sequence[float64]
        effort: sequence[float64]

    participant = DomainParticipant(int(sys.argv[1]))
""")
