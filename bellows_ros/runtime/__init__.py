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
How a bellows node runs on rclpy.

The node base classes and `run` (runtime/node.py), the message classes (messages.py), the 1 kHz
samples as serialized JointStates (joint_state_cdr.py), parameter tables (parameters.py),
real-time scheduling (realtime.py) and the recorder (record.py).
"""
from bellows_ros.runtime.node import LifecycleNode, Node, run, stamp_ns

__all__ = ['LifecycleNode', 'Node', 'run', 'stamp_ns']
