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
The bellows graph against real hardware (no simulators).

    ros2 launch bellows_ros hw.launch.py [actuator_port:=/dev/ttyACM0] [can_interface:=socketcan]
        [can_channel:=can0] [actuator:=true] [arm:=true] [params_file:=FILE]

Starts driver_node, model_node (when the arm is on) and stiffness_controller_node (when the
actuator is on). The driver is a managed node: the launch configures it (it opens the devices)
and activates it; a configure that fails (a device absent: the driver's log says which) ends the
launch with an error. Ports default to the parameter file, whose '' means config/hardware.yaml (the
board's /dev/serial/by-id link, socketcan can0). Arguments override the file's node sections
(launch_ros writes them under the node's full name, after `params_file`). Every node is required:
if one exits (a bad parameter: its one-line error is in the output) the launch stops,
and exits 1 when the node failed. The network is left as the user configured it
(ROS_AUTOMATIC_DISCOVERY_RANGE, CYCLONEDDS_URI): a robot's graph is meant to be seen from other
hosts.
"""
import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction, RegisterEventHandler, Shutdown
from launch.event_handlers import OnProcessExit
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import LifecycleNode, Node

from bellows_ros.runtime.managed_launch import bring_to_active, own_session

PACKAGE = 'bellows_ros'


def _flag(context, name):
    """Parse a true/false launch argument."""
    text = LaunchConfiguration(name).perform(context).strip().lower()
    if text not in ('true', 'false', '1', '0', 'yes', 'no'):
        raise ValueError(f"{name}:='{text}': expected true or false")
    return text in ('true', '1', 'yes')


def _nodes(context):
    """Build the node actions from the evaluated launch arguments."""
    def arg(name):
        return LaunchConfiguration(name).perform(context).strip()

    params_file = arg('params_file')
    if not os.path.isfile(params_file):
        raise ValueError(f"params_file:='{params_file}': no such file")
    use_arm, use_actuator = _flag(context, 'arm'), _flag(context, 'actuator')
    if not (use_arm or use_actuator):
        raise ValueError('arm:=false and actuator:=false: nothing to drive')
    driver = {'arm.enabled': use_arm, 'actuator.enabled': use_actuator}
    for argument, parameter in (('actuator_port', 'actuator.port'),
                                ('can_interface', 'arm.interface'),
                                ('can_channel', 'arm.channel')):
        if arg(argument):
            driver[parameter] = arg(argument)

    def node(executable, overrides=None, managed=False):
        # name= and namespace= make launch_ros write the dict under the node's own name (with
        # either missing it writes `/**`, which the file's node section beats).
        kind = LifecycleNode if managed else Node
        return kind(package=PACKAGE, executable=executable, name=executable, namespace='',
                    output='screen', parameters=[params_file, overrides or {}],
                    prefix=own_session(), exec_name=executable)

    # The driver is a managed node: configured (devices opened) and activated below.
    driver = node('driver_node', driver, managed=True)
    nodes = [driver]
    if use_arm:
        nodes.append(node('model_node'))
    if use_actuator:
        nodes.append(node('stiffness_controller_node'))
    return nodes + [RegisterEventHandler(OnProcessExit(target_action=n, on_exit=_on_exit))
                    for n in nodes] + bring_to_active(driver)


def _on_exit(event, context):
    """Stop the launch when a node exits; `ros2 launch` exits 1 (it does on an exception)."""
    if context.is_shutdown:
        return None
    name = event.action.node_name.lstrip('/')
    if event.returncode == 0:
        return [Shutdown(reason=f'{name} exited')]
    raise RuntimeError(f'{name} exited with status {event.returncode}; see its output above')


def generate_launch_description():
    """Declare the arguments; the nodes are built once they are known (`_nodes`)."""
    share = get_package_share_directory(PACKAGE)
    return LaunchDescription([
        DeclareLaunchArgument('actuator_port', default_value='',
                              description="actuator board's serial port ('' = params_file, "
                                          'then hardware.yaml)'),
        DeclareLaunchArgument('can_interface', default_value='',
                              description="python-can interface of the arm bus ('' = params_file, "
                                          'then hardware.yaml: socketcan)'),
        DeclareLaunchArgument('can_channel', default_value='',
                              description="arm bus channel ('' = params_file, then "
                                          'hardware.yaml: can0)'),
        DeclareLaunchArgument('arm', default_value='true',
                              description='drive the arm (and run model_node)'),
        DeclareLaunchArgument('actuator', default_value='true',
                              description='drive the actuator '
                                          '(and run stiffness_controller_node)'),
        DeclareLaunchArgument('params_file',
                              default_value=os.path.join(share, 'config', 'nodes_hw.yaml'),
                              description='ROS 2 parameter file for every node'),
        OpaqueFunction(function=_nodes),
    ])
