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
The ROS 2 message and service classes the nodes use, by short name: `msg.JointState`, ...

They are the ROS packages' own classes (sensor_msgs, std_msgs, ...), from a sourced Jazzy or from
the `ros-jazzy-*` wheels. `message_class('sensor_msgs/msg/JointState')` gives a class by its ROS
name (the contract in bellows_ros/interfaces.py names topics' types that way).

control_msgs (the arm controller's `~/state`, JointTrajectoryControllerState) has no wheel on
PyPI: where it does not import, `msg.JointTrajectoryControllerState` is None and the controller
says once that it does not publish that topic.
"""
import importlib
import types

USED_TYPES = {
    'Header': 'std_msgs/msg/Header',
    'Float64': 'std_msgs/msg/Float64',
    'Bool': 'std_msgs/msg/Bool',
    'JointState': 'sensor_msgs/msg/JointState',
    'Wrench': 'geometry_msgs/msg/Wrench',
    'WrenchStamped': 'geometry_msgs/msg/WrenchStamped',
    'KeyValue': 'diagnostic_msgs/msg/KeyValue',
    'DiagnosticStatus': 'diagnostic_msgs/msg/DiagnosticStatus',
    'DiagnosticArray': 'diagnostic_msgs/msg/DiagnosticArray',
    'Clock': 'rosgraph_msgs/msg/Clock',
    'Duration': 'builtin_interfaces/msg/Duration',
    'JointTrajectoryPoint': 'trajectory_msgs/msg/JointTrajectoryPoint',
    'JointTrajectory': 'trajectory_msgs/msg/JointTrajectory',
    'JointTrajectoryControllerState': 'control_msgs/msg/JointTrajectoryControllerState',
}
# Packages that may be missing where ROS 2 came from PyPI (no wheel there).
OPTIONAL_PACKAGES = ('control_msgs',)

USED_SERVICES = ('std_srvs/srv/Trigger', 'std_srvs/srv/SetBool')


def message_class(ros_name):
    """Return the class of `ros_name` ('sensor_msgs/msg/JointState'); ImportError if absent."""
    package, kind, name = ros_name.split('/')
    return getattr(importlib.import_module(f'{package}.{kind}'), name)


def _optional(ros_name):
    try:
        return message_class(ros_name)
    except ImportError:
        if ros_name.split('/')[0] in OPTIONAL_PACKAGES:
            return None
        raise


msg = types.SimpleNamespace(**{short: _optional(name) for short, name in USED_TYPES.items()})
srv = types.SimpleNamespace(**{name.rsplit('/', 1)[1]: message_class(name)
                               for name in USED_SERVICES})
