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
The interface contract: every topic with its type, QoS and naming rules, in one place.

Nodes, the recorder, the bag reader, the scenario and the tests take topic names, message types,
queue depths and joint names from here; docs/interfaces.md is the reference that a test holds to
this module. Names are relative, so a node's namespace (`ros2 launch ... namespace:=arm_a`,
`--ros-args -r __ns:=/arm_a`) moves the whole graph, and `-r` remaps any of them; a private name
(`~/state`) lies under its node's name, as ros2_controllers' controllers name theirs. Three are
absolute on purpose, as ROS defines them: `/diagnostics` (one aggregator reads every node's
status) and `/clock` (one time source); and `/bellows/estop`, one stop for every driver.

Message conventions:
- each device group has one sample topic, one message per sample: the arm's on `joint_states`,
  the actuator's on `actuator/joint_states`; so a 1 kHz node of one group never receives
  (decodes, then drops) the other's samples, and no node re-joins a sample from several
  messages. A sample message names the group's joints and then its chambers (`arm_sample_names`,
  `actuator_sample_names`): a joint's `position` and `velocity` are its state and its `effort`
  the force or torque measured on it (NaN where none is); a chamber's `effort` is its absolute
  pressure (Pa) and its `position` and `velocity` are NaN. Subscribers find values by name
  (`SampleIndex`): another publisher may share a topic, and may name fewer or more entries.
  Recordings from before (the chambers on `bellows/chambers` and `actuator/chambers`, the
  actuator's force on `bellows/wrench`, and before that the actuator on `joint_states`) are
  still read (`bellows_ros.io.bag`);
- `bellows/wrench`: an arm's force/torque sensor, `header.frame_id` `segment_<i>`: the measured
  external torque tau_ext is `wrench.torque.z` (z along the segment's bending axis, positive in
  the direction of positive Psi).
"""
from dataclasses import dataclass

# Depth for the 1 kHz sample topics, writers and readers: a reader stalled by its host for up to
# five seconds loses no sample. `bellows record` runs at normal priority and a loaded shared 2-core
# machine starved it for over a second: with 1000 the records had holes of 0.08-0.31 s that the
# doctor refuses (test_runtime_record: a recorder stopped 2.5 s). 5000 samples of 4 segments is
# about 1 MB per topic, held only while a reader lags.
SAMPLE_DEPTH = 5000
# s: the devices' sample period (their 1 kHz clock); a sample's stamp is on that time base, so a
# stamp gap of n periods means n - 1 samples its reader never got.
SAMPLE_PERIOD = 1e-3
# Depth for commands, set-points and status: only the newest few matter.
COMMAND_DEPTH = 10
# s: the longest gap between pressure commands after which a driver may vent the arm (its
# `hardware.arm_bus.command_timeout` is at least this, checked when the driver's hardware file is
# read). A controller sends a command at least every quarter of it, whatever file the driver
# was given: this is the promise between them, not a copy of the driver's configuration.
COMMAND_WATCHDOG = 0.1


@dataclass(frozen=True)
class Topic:
    """A topic of the contract: name (relative unless it starts with '/'), ROS type, QoS depth."""

    name: str
    ros_type: str
    depth: int
    content: str
    latched: bool = False  # reliable, transient local, depth 1: a late joiner gets the last one
    node: str = ''  # for a private name ('~/...'): the node it belongs to

    @property
    def message(self):
        """The message's short name, as the runtimes' `msg` namespace holds it ('JointState')."""
        return self.ros_type.rsplit('/', 1)[1]

    def resolved(self, namespace='/'):
        """Return the full name in `namespace` ('/joint_states' in the root namespace)."""
        if self.name.startswith('/'):
            return self.name
        if self.name.startswith('~'):
            return namespace.rstrip('/') + '/' + self.node + self.name[1:]
        return namespace.rstrip('/') + '/' + self.name


JOINT_STATES = Topic('joint_states', 'sensor_msgs/msg/JointState', SAMPLE_DEPTH,
                     'arm: segment angles and rates; chain pressures, Pa abs, in effort')
ACTUATOR_JOINT_STATES = Topic('actuator/joint_states', 'sensor_msgs/msg/JointState',
                              SAMPLE_DEPTH, 'actuator: compressions x_c, x_s; spring force f, N, '
                              'and chamber pressure, Pa abs, in effort')
WRENCH = Topic('bellows/wrench', 'geometry_msgs/msg/WrenchStamped', SAMPLE_DEPTH,
               "an arm force/torque sensor: a segment's external torque")
DRIVING_TORQUE = Topic('bellows/driving_torque', 'sensor_msgs/msg/JointState', SAMPLE_DEPTH,
                       'driving torque per segment, N·m, A(2)')
EXTERNAL_TORQUE = Topic('bellows/external_torque', 'sensor_msgs/msg/JointState', SAMPLE_DEPTH,
                        'estimated external torque per segment, N·m, A(2)')
PRESSURE_COMMAND = Topic('bellows/pressure_command', 'sensor_msgs/msg/JointState', COMMAND_DEPTH,
                         'chamber pressure set-points, Pa abs, in effort')
STIFFNESS_SETPOINT = Topic('actuator/stiffness_setpoint', 'std_msgs/msg/Float64', COMMAND_DEPTH,
                           'actuator stiffness set-point, N/m')
STIFFNESS = Topic('actuator/stiffness', 'std_msgs/msg/Float64', COMMAND_DEPTH,
                  'present actuator stiffness from the measured state, N/m')
MOTOR_COMMAND = Topic('actuator/motor_command', 'std_msgs/msg/Float64', COMMAND_DEPTH,
                      'lead-screw motor duty, -1..1')
PSI_SETPOINT = Topic('arm/psi_setpoint', 'sensor_msgs/msg/JointState', COMMAND_DEPTH,
                     'segment angle set-points, rad, in position')
# The arm controller's own interface, named as ros2_controllers' joint_trajectory_controller names
# its: a trajectory in, the tracking state out, under the node's name.
ARM_CONTROLLER_NODE = 'arm_controller_node'
JOINT_TRAJECTORY = Topic('~/joint_trajectory', 'trajectory_msgs/msg/JointTrajectory',
                         COMMAND_DEPTH, 'segment angle trajectories, rad, by joint name',
                         node=ARM_CONTROLLER_NODE)
TRAJECTORY_STATE = Topic('~/state', 'control_msgs/msg/JointTrajectoryControllerState',
                         COMMAND_DEPTH, 'reference, measured angle and tracking error per segment',
                         node=ARM_CONTROLLER_NODE)
DIAGNOSTICS = Topic('/diagnostics', 'diagnostic_msgs/msg/DiagnosticArray', COMMAND_DEPTH,
                    'every node: rates, loop timing, link health, counters')
CLOCK = Topic('/clock', 'rosgraph_msgs/msg/Clock', COMMAND_DEPTH,
              'simulated time, when use_sim_time is on')
# Absolute on purpose: one emergency stop reaches every driver, in whatever namespace. Latched, so
# a driver that starts (or restarts) while it is held is stopped from its first moment.
ESTOP = Topic('/bellows/estop', 'std_msgs/msg/Bool', 1,
              'True: every driver vents and refuses commands until released', latched=True)
# The driver's side of the stop: a controller that kept computing while its commands were refused
# (a latched vent) has a set-point and an integral from before the segment fell.
VENTED = Topic('bellows/vented', 'std_msgs/msg/Bool', 1,
               'arm: True while the driver holds its chambers vented (not active, a latched vent, '
               'the emergency stop, the command watchdog), False once a command has taken; sent '
               'on each change', latched=True)

TOPICS = (JOINT_STATES, ACTUATOR_JOINT_STATES, WRENCH,
          DRIVING_TORQUE, EXTERNAL_TORQUE, PRESSURE_COMMAND, STIFFNESS_SETPOINT, STIFFNESS,
          MOTOR_COMMAND, PSI_SETPOINT, JOINT_TRAJECTORY, TRAJECTORY_STATE, DIAGNOSTICS, CLOCK,
          ESTOP, VENTED)


def by_name(namespace='/'):
    """{full topic name: ROS type} of the contract in `namespace` (the recorder, the bag)."""
    return {topic.resolved(namespace): topic.ros_type for topic in TOPICS}


# Joint, chamber and frame names.
ACTUATOR_JOINTS = ('air_chamber', 'spring')
ACTUATOR_CHAMBER = 'actuator'


def segment_joint(segment):
    """Joint name of arm segment `segment` (1-based): 'segment_1'."""
    return f'segment_{segment}'


def chain_chamber(segment, chain):
    """Chamber name of chain `chain` (1, 2) of segment `segment` (1-based): 'segment_1/chain_2'."""
    return f'{segment_joint(segment)}/chain_{chain}'


def segment_sample_names(segment):
    """Names of segment `segment`'s entries in an arm sample: its joint, its chambers 1 and 2."""
    return (segment_joint(segment), chain_chamber(segment, 1), chain_chamber(segment, 2))


def arm_sample_names(segments):
    """Names of an arm sample message: the segments' joints, then their chambers (chain 1, 2)."""
    return tuple([segment_joint(i) for i in segments] +
                 [chain_chamber(i, chain) for i in segments for chain in (1, 2)])


def actuator_sample_names():
    """Names of an actuator sample message: its joints, then its chamber."""
    return ACTUATOR_JOINTS + (ACTUATOR_CHAMBER,)


class SampleIndex:
    """
    Find entries of sample messages by name, the lookup kept per list of names.

    `SampleIndex(wanted)(msg.name)` -> the index of each wanted name in `msg.name`, or None when
    the message lacks one. A publisher sends the same names in every message, so the lookup is
    built once per list of names (bounded: a flood of different lists cannot grow it).
    """

    MAX_LAYOUTS = 16

    def __init__(self, wanted):
        self.wanted = tuple(wanted)
        self._layouts = {}

    def __call__(self, names):
        key = tuple(names)
        try:
            return self._layouts[key]
        except KeyError:
            pass
        where = {name: i for i, name in enumerate(key)}
        layout = None
        if all(name in where for name in self.wanted):
            layout = tuple(where[name] for name in self.wanted)
        if len(self._layouts) >= self.MAX_LAYOUTS:
            self._layouts.clear()
        self._layouts[key] = layout
        return layout
