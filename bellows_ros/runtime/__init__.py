"""
The runtime the nodes run on: rclpy, or plain Cyclone DDS with ROS 2's wire conventions.

Nodes are written once against `Node` (runtime/node.py, the narrow interface) and started with
`run(NodeClass, args)`, which picks the implementation once: `rclpy_runtime` where rclpy imports,
else `dds_node`; `$BELLOWS_RUNTIME=rclpy|dds` chooses explicitly.
"""
from bellows_ros.runtime.node import Node, run, select_runtime, stamp_ns

__all__ = ['Node', 'run', 'select_runtime', 'stamp_ns']
