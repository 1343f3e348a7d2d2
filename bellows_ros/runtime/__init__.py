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
The runtime the nodes run on: rclpy, or plain Cyclone DDS with ROS 2's wire conventions.

Nodes are written once against the runtime contract (runtime/contract.py), subclassing `Node`
(runtime/node.py), and started with `run(NodeClass, args)`, which picks the implementation once
(`rclpy_runtime` where rclpy imports, else `dds_node`; `$BELLOWS_RUNTIME=rclpy|dds` chooses
explicitly) and composes the node class with it: `NodeClass.on(runtime)`, on rclpy an
`rclpy.node.Node`.
"""
from bellows_ros.runtime.node import Node, run, select_runtime, stamp_ns

__all__ = ['Node', 'run', 'select_runtime', 'stamp_ns']
