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
The bellows part of every node, on rclpy, and `run`, which starts one.

A bellows node subclasses `Node` (an `rclpy.node.Node`) or, for a managed node, `LifecycleNode`
(an `rclpy.lifecycle.LifecycleNode`)::

    class Talker(Node):
        def __init__(self, **kwargs):
            super().__init__('talker', **kwargs)
            self.declare_specs(PARAMETERS)
            self.pub = self.publisher(interfaces.DRIVING_TORQUE)

    def main(args=None):
        return run(Talker, args)

What the base adds to rclpy's node: `declare_specs` (a node's parameter table, checked by
`parameters.validate`, the one check, at start and for every change while running),
`check_parameters` (a parameter given in a file or with -p that the node does not declare is an
error, not silently ignored), `publisher`/`subscription` (a topic of bellows_ros/interfaces.py),
`msg` and `srv` (runtime/messages.py) and the `parameters` dict kept current.

`run` spins the node on rclpy's EventsExecutor (rclpy >= 7.1.5; it costs about a third of the
SingleThreadedExecutor's CPU per message), in bounded slices: on the PyPI wheels an unbounded
`spin()` busy-loops a core and starves Fast DDS's receive threads, so the node stops answering
discovery, services and signals. Where rclpy lacks it (a sourced Jazzy with rclpy 7.1.3) the
node says so once and spins on the SingleThreadedExecutor.
"""
import array
import gc
import os
import signal
import sys
from typing import Any, Callable, Optional, Sequence

import rclpy
import rclpy.exceptions
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
import rclpy.lifecycle
import rclpy.node
from rclpy.qos import DurabilityPolicy, qos_profile_sensor_data, QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from rclpy.task import Future

from bellows_ros.errors import BellowsError, ParameterError
from bellows_ros.runtime import messages
from bellows_ros.runtime.joint_state_cdr import JointStateReader
from bellows_ros.runtime.parameters import descriptor_message, validate

try:
    from rclpy.experimental.events_executor import EventsExecutor
except ImportError:  # rclpy before 7.1.5 (a sourced Jazzy of early 2025)
    EventsExecutor = None

# DDS discovery and traffic on this host only: ROS 2 Jazzy's own switch, which rmw_fastrtps_cpp
# and the other Jazzy RMWs honour (Fast DDS then talks over shared memory and UDP on
# loopback). For the simulated launches, the tests and the benches; a robot's launch leaves the
# network as the user configured it.
LOOPBACK_ENVIRONMENT = {'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST', 'ROS_STATIC_PEERS': ''}
# Reliable, transient local, depth 1: a late joiner gets the last message (a latched state).
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
# s: the longest the executor runs without returning to Python, where signals are acted on and
# the end of a node (`done`) is seen.
SPIN_SLICE = 0.1

# A user's mistake in a node name, namespace, topic name or parameter, as rclpy reports it.
USER_ERRORS = (rclpy.exceptions.ParameterException, rclpy.exceptions.InvalidNodeNameException,
               rclpy.exceptions.InvalidNamespaceException,
               rclpy.exceptions.InvalidTopicNameException)


# The parameters every rclpy node declares itself (Jazzy).
RCLPY_OWN = ('use_sim_time', 'start_type_description_service')


def stamp_ns(stamp: Any) -> int:
    """builtin_interfaces/Time -> integer nanoseconds."""
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def _plain(value: Any) -> Any:
    """Return a parameter value as declared: rclpy hands arrays over as array.array."""
    return list(value) if isinstance(value, array.array) else value


class _BellowsNode:
    """What every bellows node adds to rclpy's node class (see the module docstring)."""

    msg = messages.msg
    srv = messages.srv

    def __init__(self, node_name: str, **kwargs: Any) -> None:
        """Create the node `node_name`; `kwargs` go to rclpy's Node (`namespace`, ...)."""
        self._specs = {}
        # The value of every parameter declared with a Spec, kept current while the node runs.
        self.parameters = {}
        # Every parameter given (files, -p) is declared from its override first, so that the
        # node can tell which it was given (public API: rclpy keeps the overrides private).
        try:
            super().__init__(node_name, automatically_declare_parameters_from_overrides=True,
                             **kwargs)
        except ValueError as exc:  # an override rcl could give no type: an empty array
            if 'PARAMETER_NOT_SET' not in str(exc):
                raise
            raise ParameterError(f'{node_name}: a parameter is given as an empty array ([]), '
                                 'which has no type; give at least one element') from None
        self._given = {name: _plain(value.value) for name, value
                       in self.get_parameters_by_prefix('').items() if name not in RCLPY_OWN}

    # parameters
    def declare_specs(self, specs: Sequence[Any]) -> dict:
        """
        Declare every parameter of `specs` (runtime/parameters.py) and check its value.

        The value given (file or -p), else the default, is checked against its Spec
        (`parameters.validate`) before it is declared; rclpy gets the Spec as the parameter's
        descriptor (`ros2 param describe`). Returns {name: value}.
        """
        values = {}
        for spec in specs:
            given = self._given.get(spec.name, spec.default)
            validate(self.get_name(), spec, given)
            if spec.name in self._given:  # declared from its override: again, with its Spec
                self.undeclare_parameter(spec.name)
            descriptor = descriptor_message(spec, messages.message_class)
            values[spec.name] = _plain(self.declare_parameter(
                spec.name, spec.default, descriptor).value)
        self._specs.update({spec.name: spec for spec in specs})
        self.parameters.update(values)
        return values

    # A change while running (`ros2 param set`, rqt_reconfigure): rclpy has checked that the
    # parameter is declared and keeps its type; here its Spec decides (read-only, bounds,
    # choices, rule), and the node is told once the change is taken.
    def _check_change(self, changes: Sequence[Any]) -> Any:
        result = messages.message_class('rcl_interfaces/msg/SetParametersResult')(
            successful=True)
        for change in changes:
            spec = self._specs.get(change.name)
            if spec is None or spec.read_only:
                result.successful = False
                result.reason = (f"parameter '{change.name}' is read-only: the node reads it at "
                                 'start (restart the node to change it)')
                return result
            try:
                validate(self.get_name(), spec, _plain(change.value))
            except ParameterError as error:
                result.successful, result.reason = False, str(error)
                return result
        if hasattr(self, 'parameter_problem'):
            # A rule across parameters or with the node's own data (the node says what is wrong).
            result.reason = self.parameter_problem({c.name: _plain(c.value) for c in changes})
            result.successful = not result.reason
        return result

    def _take_change(self, changes: Sequence[Any]) -> None:
        changed = {change.name: _plain(change.value) for change in changes}
        self.parameters.update(changed)
        if hasattr(self, 'on_parameters'):
            # The node's own reaction (rebuild a filter, new gains): from the next control step.
            self.on_parameters(changed)

    def check_parameters(self) -> None:
        """Raise ParameterError for a given parameter (file or -p) the node does not declare."""
        unknown = [name for name in self._given if name not in self._specs]
        if unknown:
            raise ParameterError(f"unknown parameter '{unknown[0]}' for node '{self.get_name()}' "
                                 '(given in a params file or with -p; the node has no such '
                                 'parameter)')

    def watch_parameters(self) -> None:
        """
        From now on, decide every change of a parameter (`run` calls it once the node is built).

        Not before: rclpy runs these callbacks for each declaration too.
        """
        self.add_on_set_parameters_callback(self._check_change)
        self.add_post_set_parameters_callback(self._take_change)

    # communication on the topics of the contract (bellows_ros/interfaces.py)
    def publisher(self, topic: Any) -> Any:
        """Create a publisher on a topic of the contract (bellows_ros/interfaces.py)."""
        return self.create_publisher(messages.message_class(topic.ros_type), topic.name,
                                     self._qos(topic))

    def subscription(self, topic: Any, callback: Callable[[Any], None], *,
                     newest_only: bool = False, raw: bool = False) -> Any:
        """
        Create a subscription to a topic of the contract (bellows_ros/interfaces.py).

        `newest_only`: best effort, the newest few (rclpy's sensor-data profile), for a reader
        that acts on the present, such as a controller. A reliable reader delivers in order: after
        one lost sample it gets no later one until the lost one is repaired, and every sample of
        that wait arrives too old to act on (docs/interfaces.md, "QoS").
        `raw`: `callback` gets the serialized message (bytes), e.g. for a `JointStateReader`.
        """
        qos = qos_profile_sensor_data if newest_only else self._qos(topic)
        return self.create_subscription(messages.message_class(topic.ros_type), topic.name,
                                        callback, qos, raw=raw)

    def sample_subscription(self, topic: Any, callback: Callable[[Any], None], *,
                            newest_only: bool = False) -> Any:
        """
        Subscribe to a JointState sample topic serialized; `callback` gets a `JointStateSample`.

        The 1 kHz readers take their samples this way: reading the bytes costs less than
        rclpy's message object (runtime/joint_state_cdr.py). Bytes that are no JointState are
        dropped with a warning (at most one per 10 s).
        """
        read = JointStateReader()

        def take(serialized):
            try:
                sample = read(serialized)
            except ValueError as exc:
                self.get_logger().warn(f'{topic.name}: dropped a message that is no JointState '
                                       f'({exc})', throttle_duration_sec=10.0)
                return
            callback(sample)
        return self.subscription(topic, take, newest_only=newest_only, raw=True)

    @staticmethod
    def _qos(topic: Any) -> Any:
        return LATCHED if topic.latched else topic.depth


class Node(_BellowsNode, rclpy.node.Node):
    """A bellows node: an rclpy.node.Node with a parameter table and the topic contract."""


class LifecycleNode(_BellowsNode, rclpy.lifecycle.LifecycleNode):
    """A managed bellows node: an rclpy.lifecycle.LifecycleNode (`ros2 lifecycle`)."""


# Where the process is with respect to SIGINT/SIGTERM: while a node is being built a signal
# interrupts at once (KeyboardInterrupt); while it spins, a signal only sets `stop`, which the spin
# loop sees within one slice (the executor runs in C++ and returns to Python at least every
# SPIN_SLICE); once clean-up has begun, further signals are ignored (a terminal's Ctrl-C reaches a
# launched node twice: from the terminal and from `ros2 launch`). rclpy's own handlers are off:
# they shut the context down at once, before a node's close() could vent or publish its counts.
_signals = {'spinning': False, 'stop': False, 'closing': False}


def _on_signal(signum, frame):
    if _signals['closing']:
        return
    _signals['stop'] = True
    if not _signals['spinning']:
        raise KeyboardInterrupt


def executor() -> Any:
    """Return the executor the nodes spin on: the EventsExecutor, else rclpy's single-threaded."""
    if EventsExecutor is not None:
        return EventsExecutor()
    return SingleThreadedExecutor()


def spin(node_executor: Any, until: Callable[[], bool]) -> None:
    """Spin `node_executor` in slices of SPIN_SLICE s until `until()` or rclpy's shutdown."""
    never = Future()  # bounded slices: see the module docstring
    while not until() and rclpy.ok():
        node_executor.spin_until_future_complete(never, timeout_sec=SPIN_SLICE)


def run(node_class: Any, args: Optional[Sequence[str]] = None) -> int:
    """
    Run one node until Ctrl-C/SIGTERM; a user mistake is one line on stderr and exit status 2.

    Builds `node_class()` (which declares its parameters up front), then checks that every
    given parameter was declared. A node with a `done` attribute runs until it is true, then
    `finish()` is called (the scenario). A node may define `close()` for its own clean-up
    (devices, threads); it runs before the node is destroyed. A node that declares
    `realtime_priority` and `cpu_latency_limit` gets them here (runtime/realtime.py).

    `node_class` may be a sequence of node classes: one process, one executor (nodes/arm_graph.py).
    Nodes are built in that order and closed in the reverse order.
    """
    from bellows_ros.runtime import realtime

    classes = tuple(node_class) if isinstance(node_class, (list, tuple)) else (node_class,)
    program = os.path.basename(sys.argv[0]) if args is None else classes[0].__name__
    # Installed whatever the shell gave: a shell starts background jobs with SIGINT ignored, and
    # ros2 launch stops nodes with SIGINT.
    _signals.update(spinning=False, stop=False, closing=False)
    signal.signal(signal.SIGTERM, _on_signal)
    signal.signal(signal.SIGINT, _on_signal)
    nodes, latency_requests = [], []
    try:
        _init(args)
        node_executor = executor()
        for cls in classes:
            nodes.append(cls())
        if EventsExecutor is None:
            nodes[0].get_logger().info('this rclpy has no EventsExecutor: spinning on the '
                                       'SingleThreadedExecutor (about 3x the CPU per message)')
        for node in nodes:
            node.check_parameters()
            node.watch_parameters()
            realtime.request(node)
            latency_requests.append(realtime.limit_cpu_latency(node))
            node_executor.add_node(node)
        # Everything built so far (modules, type support, model tables) lives as long as the
        # node: keep the cyclic collector from walking it again and again in 1 kHz callbacks.
        gc.freeze()
        _signals['spinning'] = True
        spin(node_executor, lambda: _signals['stop'] or getattr(nodes[0], 'done', False))
        if getattr(nodes[0], 'done', False):
            nodes[0].finish()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception as exc:
        if isinstance(exc, (BellowsError,) + USER_ERRORS):
            return _user_error(program, exc)
        raise
    finally:
        _signals['closing'] = _signals['stop'] = True
        for node in reversed(nodes):
            if hasattr(node, 'close'):
                node.close()
            node.destroy_node()
        rclpy.try_shutdown()
        for request in latency_requests:
            if request is not None:
                os.close(request)
    return 0


def _init(args: Optional[Sequence[str]]) -> None:
    """rclpy.init without its signal handlers; a malformed `--ros-args` is a ParameterError."""
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except RuntimeError as exc:  # rcl's argument errors (UnknownROSArgsError, RCLError)
        text = str(exc)
        if text.startswith('['):  # UnknownROSArgsError: the list of unknown arguments
            unknown = text.strip('[]').split(',')[0].strip().strip("'")
            raise ParameterError(f"--ros-args: unknown argument '{unknown}'") from None
        # rcl appends the C source locations of the error (', at /path/file.c:123'): drop them.
        message = ' '.join(text.split()).split(', at /')[0]
        raise ParameterError(message.removeprefix('failed to initialize rcl: ')) from None


def _user_error(program: str, exc: Exception) -> int:
    message = ' '.join(str(exc).split())  # rcl's messages span lines
    message = message.removeprefix(f'{program}: ')  # node errors often name the node already
    print(f'{program}: error: {message}', file=sys.stderr, flush=True)
    return 2
