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
The topic contract (docs/interfaces.md "Topics"): topic -> ROS message type.

Conventions fixed here so the driver, the recorder and the bag reader agree:
- `/joint_states` and `/bellows/chambers` carry one message per sample per device group (the arm's
  segments in one message, the actuator's `air_chamber`/`spring` in another);
- `/bellows/wrench`: `header.frame_id` names the sensor's device group. For an arm segment
  (`frame_id` `segment_<i>`) the measured external torque tau_ext is `wrench.torque.z` (z along the
  segment's bending axis, positive in the direction of positive Psi); for the actuator
  (`frame_id` `actuator`) the spring force f is `wrench.force.z` (positive compressing the spring).
"""

TOPICS = {
    '/joint_states': 'sensor_msgs/msg/JointState',
    '/bellows/chambers': 'sensor_msgs/msg/JointState',
    '/bellows/wrench': 'geometry_msgs/msg/WrenchStamped',
    '/bellows/driving_torque': 'sensor_msgs/msg/JointState',
    '/bellows/external_torque': 'sensor_msgs/msg/JointState',
    '/bellows/pressure_command': 'sensor_msgs/msg/JointState',
    '/actuator/stiffness_setpoint': 'std_msgs/msg/Float64',
    '/actuator/stiffness': 'std_msgs/msg/Float64',
    '/actuator/motor_command': 'std_msgs/msg/Float64',
    '/diagnostics': 'diagnostic_msgs/msg/DiagnosticArray',
    '/clock': 'rosgraph_msgs/msg/Clock',
}

# Depth for the 1 kHz sample topics: a reader stalled by its host for up to a second (seen on a
# shared 2-core machine under load) must not lose samples; 1000 samples of 4 segments is ~200 kB.
SAMPLE_DEPTH = 1000

ACTUATOR_FRAME = 'actuator'
