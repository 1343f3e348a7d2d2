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

"""The controllers' mathematics, without ROS: the nodes in `bellows_ros.nodes` run them."""
__all__ = [
    'angle_tracking',       # angle tracking of one segment: PID plus the model as feedforward
    'pressure_allocation',  # chain pressures for a driving torque
    'angle_trajectory',     # built-in angle trajectories
    'joint_trajectory',     # joint trajectories as ros2_controllers' JTC runs them
    'stiffness',            # stiffness set-point -> chamber compression target
    'pd',                   # PD position control of the lead screw (paper B)
    'effort',               # control effort: valve motion and air used
    'closed_loop',          # the arm controller around the simulated segment, in process
]
