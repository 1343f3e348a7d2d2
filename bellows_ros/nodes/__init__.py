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
The ROS 2 nodes (rclpy), one job each; each module's `main` is a console script (setup.py).

The topic contract they share is `bellows_ros.interfaces`; docs/nodes.md describes every node.
"""
__all__ = [
    'device_topics',              # each kind of device as driver_node publishes it
    'driver_node',                # the devices on the topics (a lifecycle node)
    'model_node',                 # paper A's driving torque for every sample
    'arm_controller_node',        # angle tracking with the model as feedforward
    'stiffness_controller_node',  # stiffness set-point -> motor duty
    'sim_arm_node',               # the simulated arm on CAN
    'sim_actuator_node',          # the simulated actuator board on a pseudo-terminal
    'scenario_node',              # a scripted scenario on the running graph
    'arm_graph',                  # driver, model and arm controller in one process
]
