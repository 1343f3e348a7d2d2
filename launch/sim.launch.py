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
The whole bellows graph on simulated hardware, with the scripted scenario.

    ros2 launch bellows_ros sim.launch.py [duration:=40.0] [scenario:=true] [output_dir:=DIR]
        [actuator_port:=PATH] [can_channel:=GROUP] [arm_effects:='[..]'] [actuator_effects:='[..]']
        [params_file:=FILE] [discovery_range:=LOCALHOST] [namespace:=NS]

Starts sim_arm_node (CAN over udp_multicast on loopback), sim_actuator_node (serial on a pty),
driver_node (a managed node, brought to active), model_node, stiffness_controller_node and
arm_controller_node. With scenario:=true
(the default) scenario_node runs the stiffness step and segment_1's angle trajectory (through
the arm controller) for `duration` s,
prints its summary, writes scenario.png and scenario.csv into `output_dir`, and the launch shuts
down; with scenario:=false the graph runs until Ctrl-C. Every node is required: if one exits, the
launch stops, and exits 1 when that was not a clean end (`ros2 launch` returns 1 on an exception).

Arguments override the parameter file's node sections: launch_ros writes a dict of parameters to
a file under the node's full name (when both name and namespace are given), passed after
`params_file`, so it wins as `-p node:name:=value` would. The default pty path and multicast
group are private to each launch (from its process id), so two launches on one machine do not
collide: with `namespace:=arm_a` and `namespace:=arm_b` two whole graphs run side by side, each
under its namespace (config/nodes_sim.yaml's sections are `/**/<node>`, so they apply in any).
"""
import os
import tempfile

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import (DeclareLaunchArgument, OpaqueFunction, RegisterEventHandler,
                            SetEnvironmentVariable, Shutdown)
from launch.event_handlers import OnProcessExit
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import LifecycleNode, Node
import yaml

from bellows_ros.runtime.managed_launch import bring_to_active, own_session

PACKAGE = 'bellows_ros'


def _effects(text, argument):
    """Parse an effects argument: a YAML list or comma-separated names; '' = the file's."""
    text = text.strip()
    if not text:
        return None
    value = yaml.safe_load(text) if text.startswith('[') else text.split(',')
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise ValueError(f"{argument}:='{text}': expected a list of effect names, "
                         "e.g. '[wall_bulging, air_leak]' or 'none'")
    names = [v.strip() for v in value if v.strip() and v.strip() != 'none']
    # The nodes declare a string array and skip empty names: [''] is "no effect" (rcl has no
    # typed empty array in a parameter file).
    return names or ['']


def _double(text, argument):
    """Parse a number as a double (rcl types parameters strictly: 12 would be an integer)."""
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"{argument}:='{text}': expected a number of seconds") from None


def _nodes(context):
    """Build the node actions from the evaluated launch arguments."""
    def arg(name):
        return LaunchConfiguration(name).perform(context).strip()

    params_file = arg('params_file')
    if not os.path.isfile(params_file):
        raise ValueError(f"params_file:='{params_file}': no such file")
    port = arg('actuator_port') or os.path.join(tempfile.gettempdir(),
                                                f'bellows_sim_actuator_{os.getpid()}')
    channel = arg('can_channel') or f'239.74.163.{os.getpid() % 200 + 20}'
    arm = {'can.channel': channel}
    actuator = {'port': port}
    for overrides, name in ((arm, 'arm_effects'), (actuator, 'actuator_effects')):
        effects = _effects(arg(name), name)
        if effects is not None:
            overrides['effects'] = effects

    namespace = arg('namespace').strip('/')

    def node(executable, overrides=None, managed=False, **kwargs):
        # name= and namespace= make launch_ros write the dict under the node's own name (with
        # either missing it writes `/**`, which the file's node section beats).
        kind = LifecycleNode if managed else Node
        return kind(package=PACKAGE, executable=executable, name=executable, namespace=namespace,
                    output='screen', parameters=[params_file, overrides or {}],
                    prefix=own_session(), exec_name=executable, **kwargs)

    # The driver is a managed node: brought to active below (bring_to_active).
    driver = node('driver_node', {'arm.channel': channel, 'actuator.port': port}, managed=True)

    nodes = [
        node('sim_arm_node', arm),
        node('sim_actuator_node', actuator),
        driver,
        node('model_node'),
        node('stiffness_controller_node'),
        node('arm_controller_node'),
    ]
    if arg('scenario').lower() in ('true', '1', 'yes'):
        output_dir = os.path.abspath(os.path.expanduser(arg('output_dir')))
        nodes.append(node('scenario_node', {'duration': _double(arg('duration'), 'duration'),
                                            'output_dir': output_dir}))
    elif arg('scenario').lower() not in ('false', '0', 'no'):
        raise ValueError(f"scenario:='{arg('scenario')}': expected true or false")
    handlers = [RegisterEventHandler(OnProcessExit(target_action=n, on_exit=_on_exit))
                for n in nodes]
    return nodes + handlers + bring_to_active(driver)


def _on_exit(event, context):
    """Stop the launch when a node exits; a failure (not during shutdown) makes it exit 1."""
    if context.is_shutdown:
        return None
    name = event.action.node_name.lstrip('/')
    if event.returncode == 0 and name == 'scenario_node':
        return [Shutdown(reason='scenario finished')]
    if event.returncode == 0:
        return [Shutdown(reason=f'{name} exited')]
    # Raising is how a launch file makes `ros2 launch` exit non-zero; the launch still shuts
    # down every other node.
    raise RuntimeError(f'{name} exited with status {event.returncode}; see its output above')


def generate_launch_description():
    """Declare the arguments; the nodes are built once they are known (`_nodes`)."""
    share = get_package_share_directory(PACKAGE)
    discovery = os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE') or 'LOCALHOST'
    return LaunchDescription([
        DeclareLaunchArgument('scenario', default_value='true',
                              description='run scenario_node and shut down when it is done'),
        DeclareLaunchArgument('duration', default_value='40.0',
                              description='scenario length, s'),
        DeclareLaunchArgument('output_dir', default_value='scenario_out',
                              description='where the scenario writes scenario.png/.csv'),
        DeclareLaunchArgument('actuator_port', default_value='',
                              description="simulated board's pty link ('' = private temp path)"),
        DeclareLaunchArgument('can_channel', default_value='',
                              description="simulated CAN multicast group ('' = private group)"),
        DeclareLaunchArgument('arm_effects', default_value='',
                              description="sim_arm_node effects, e.g. '[contact_hysteresis]' "
                                          "or 'none' ('' = params_file's)"),
        DeclareLaunchArgument('actuator_effects', default_value='',
                              description='sim_actuator_node effects, e.g. '
                                          "'[wall_bulging, air_leak]' or 'none' "
                                          "('' = params_file's)"),
        DeclareLaunchArgument('params_file',
                              default_value=os.path.join(share, 'config', 'nodes_sim.yaml'),
                              description='ROS 2 parameter file for every node'),
        DeclareLaunchArgument('namespace', default_value='',
                              description='namespace of every node and topic (a second graph '
                                          'beside the first: namespace:=arm_b)'),
        DeclareLaunchArgument('discovery_range', default_value=discovery,
                              description='ROS_AUTOMATIC_DISCOVERY_RANGE for the nodes '
                                          '(default LOCALHOST unless set in the environment)'),
        # A simulation has no business on the network: DDS discovery stays on this host (the
        # simulated CAN bus is on loopback already).
        SetEnvironmentVariable('ROS_AUTOMATIC_DISCOVERY_RANGE',
                               LaunchConfiguration('discovery_range')),
        OpaqueFunction(function=_nodes),
    ])
