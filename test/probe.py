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
The tests' own ROS 2 participant: an rclpy node in the pytest process, on the test's domain.

    probe.init()                    # rclpy on $ROS_DOMAIN_ID (the test sets it)
    node = probe.Node('estop_probe')    # an rclpy.node.Node
    node.create_subscription(probe.msg.Bool, '/bellows/vented', seen.append, probe.LATCHED)
    probe.spin_once(node, timeout_sec=0.05)
    probe.shutdown()                # every probe node destroyed, rclpy shut down

Plain rclpy, nothing of bellows_ros's node base: what any ROS 2 user's node sees of the graph
(`probe.msg` are the ROS packages' own message classes). A test that builds a bellows node in
its own process (`probe.init(['--ros-args', ...])` for its parameters) spins it with
`probe.adopt(node)` and `probe.spin_once(node)`.
"""
from array import array
import math

import rclpy
from rclpy.executors import SingleThreadedExecutor
import rclpy.node
from rclpy.serialization import serialize_message
from rclpy.task import Future

from bellows_ros import interfaces
from bellows_ros.runtime.joint_state_cdr import JointStateReader
from bellows_ros.runtime.messages import msg  # noqa: F401 (the ROS packages' classes)
from bellows_ros.runtime.node import LATCHED  # noqa: F401 (the probes' QoS for latched topics)

_executors = {}
_NEVER = Future()  # spin_until_future_complete of it: spin for the timeout


def init(args=()):
    """
    rclpy.init on the domain of $ROS_DOMAIN_ID (once per test; `shutdown` ends it).

    `args` ('--ros-args', ...) apply to every node of this process, as a node process's do.
    """
    rclpy.init(args=['probe', *args])


def adopt(node):
    """Spin `node` (a node built in this process) with `spin_once`/`spin_for`; return it."""
    _executors[node] = SingleThreadedExecutor()
    _executors[node].add_node(node)
    return node


def Node(name):  # noqa: N802 (stands for the class, as rclpy.create_node does)
    """Return a new rclpy node `name` in the probe's context."""
    return adopt(rclpy.node.Node(name))


def spin_once(node, timeout_sec=0.05):
    """Serve every callback of `node` that gets ready within `timeout_sec` (>= 1 ms)."""
    _executors[node].spin_until_future_complete(_NEVER, timeout_sec=max(timeout_sec, 0.001))


def result_of(node, future, timeout_sec=30.0):
    """Spin `node` until `future` (e.g. a service call's) is done; its result."""
    _executors[node].spin_until_future_complete(future, timeout_sec=timeout_sec)
    assert future.done(), f'no answer within {timeout_sec} s'
    return future.result()


def spin_for(node, seconds):
    """Spin `node` for `seconds`."""
    spin_once(node, seconds)


def shutdown():
    """Destroy every probe node and shut rclpy down."""
    for node, node_executor in list(_executors.items()):
        node_executor.shutdown(timeout_sec=1.0)
        node.destroy_node()
    _executors.clear()
    rclpy.try_shutdown()


def arm_sample(stamp, psi, psi_dot, pressures, segments=(1,)):
    """
    Return one arm sample message as the driver publishes it (interfaces.py).

    stamp: ns; psi, psi_dot: rad, rad/s per segment; pressures: Pa abs, (chain 1, chain 2) per
    segment, flat.
    """
    nan = [math.nan] * len(pressures)
    sample = msg.JointState(name=list(interfaces.arm_sample_names(segments)),
                            position=array('d', [*psi, *nan]),
                            velocity=array('d', [*psi_dot, *nan]),
                            effort=array('d', [math.nan] * len(segments) + list(pressures)))
    sample.header.stamp.sec, sample.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
    return sample


def as_received(message):
    """Return `message` (a JointState) as a sample subscription hands it over: read."""
    return JointStateReader()(serialize_message(message))


def chamber_pressures(sample):
    """Return the chamber pressures (Pa abs) an arm sample message carries, by chamber name."""
    return {name: p for name, p in zip(sample.name, sample.effort) if '/chain_' in name}


def highest_pressure(sample):
    """Return the highest chamber pressure (Pa abs) of an arm sample message."""
    return max(chamber_pressures(sample).values())
