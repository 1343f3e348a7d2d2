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

"""Messages for the bags tests write with rosbags (no ROS): joint states and wrenches, stamped."""
import numpy as np
from rosbags.typesys import get_typestore, Stores

STORE = get_typestore(Stores.ROS2_JAZZY)
JOINT_STATE = 'sensor_msgs/msg/JointState'
WRENCH = 'geometry_msgs/msg/WrenchStamped'


def header(ns, frame=''):
    """std_msgs/Header stamped `ns` nanoseconds."""
    stamp = STORE.types['builtin_interfaces/msg/Time'](sec=ns // 10 ** 9, nanosec=ns % 10 ** 9)
    return STORE.types['std_msgs/msg/Header'](stamp=stamp, frame_id=frame)


def joints(ns, names, position=(), effort=()):
    """sensor_msgs/JointState of `names` with `position` and `effort`, stamped `ns`."""
    return STORE.types[JOINT_STATE](header=header(ns), name=list(names),
                                    position=np.array(position, float),
                                    velocity=np.array([], float), effort=np.array(effort, float))


def wrench(ns, force_z):
    """geometry_msgs/WrenchStamped of the actuator frame with force.z = `force_z`."""
    vector = STORE.types['geometry_msgs/msg/Vector3']
    body = STORE.types['geometry_msgs/msg/Wrench'](force=vector(x=0.0, y=0.0, z=force_z),
                                                   torque=vector(x=0.0, y=0.0, z=0.0))
    return STORE.types[WRENCH](header=header(ns, 'actuator'), wrench=body)
