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
The rclpy runtime: the nodes on ROS 2 itself (what `ros2 run` and `ros2 launch` start).

The same names as the DDS runtime (`dds_node`): the `Runtime` Protocol of runtime/contract.py, so
`runtime.node.run` uses either unchanged. `Node` is an `rclpy.node.Node`, the base every bellows
node is composed with here (`NodeClass.on(rclpy_runtime)`): any rclpy executor spins it. Import
fails with ImportError where rclpy or the message packages are absent.

Public rclpy API only, but for `WaitLoop` (what `run` spins a node with, for speed): rclpy has no
public wait set, so it uses rclpy's own (`rclpy.impl.implementation_singleton`, as rclpy's
executors do).

The nodes' messages travel as serialized CDR: publishers and subscriptions are rclpy's own (same
types, type hashes, QoS and graph entries as any rclpy node), but a message is encoded and decoded
by runtime/cdr.py and handed to rclpy as bytes (`publish(bytes)`, `raw=True` subscriptions).
`msg` holds cdr's plain classes. rclpy's conversion of each message between Python objects and C
structs, then rmw_cyclonedds_cpp's introspection serializer, cost the model node more CPU per
sample than its model (docs/bench_log.md, 2026-11-23).
"""
import importlib
import inspect
import sys
import time
import types

import rclpy
import rclpy.duration
import rclpy.exceptions
import rclpy.executors
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
import rclpy.node
import rclpy.qos
import rclpy.serialization
import rclpy.signals
import rclpy.time
from rclpy.waitable import NumberOfEntities

from bellows_ros.errors import ParameterError
from bellows_ros.runtime import cdr, ros_args
from bellows_ros.runtime.parameters import check_type, descriptor_message

NAME = 'rclpy'

msg = types.SimpleNamespace(**{short: cdr.plain_class(ros_name)
                               for short, ros_name in cdr.USED_TYPES.items()})
# The service types the nodes offer (cdr.USED_SERVICES), as rclpy's own classes.
srv = types.SimpleNamespace(**{
    name.rsplit('/', 1)[1]: getattr(importlib.import_module(name.rsplit('/', 1)[0].replace(
        '/', '.')), name.rsplit('/', 1)[1]) for name in cdr.USED_SERVICES})


def service_message(ros_name):
    """Return the class of a message type inside a service: rclpy's own, as its services use."""
    package, _, name = ros_name.split('/')
    return getattr(importlib.import_module(f'{package}.msg'), name)


Time = rclpy.time.Time
Duration = rclpy.duration.Duration
SENSOR_DATA = rclpy.qos.qos_profile_sensor_data
# Reliable, transient local, depth 1: a late joiner gets the last message (a latched state).
LATCHED = rclpy.qos.QoSProfile(depth=1, reliability=rclpy.qos.ReliabilityPolicy.RELIABLE,
                               durability=rclpy.qos.DurabilityPolicy.TRANSIENT_LOCAL)

# Raised by a spinning executor when something else shut rclpy's context down.
INTERRUPTED = (rclpy.executors.ExternalShutdownException,)
# A user's mistake in a node name, namespace, topic name or parameter, as rclpy reports it.
USER_ERRORS = (rclpy.exceptions.ParameterException, rclpy.exceptions.InvalidNodeNameException,
               rclpy.exceptions.InvalidNamespaceException,
               rclpy.exceptions.InvalidTopicNameException)

_MAX_WAIT_S = 0.1  # longest wait in C, so SIGINT/SIGTERM are acted on promptly
_SLOW_PERIOD = 0.02  # s between waits that include services, guard conditions and waitables
# Messages taken per ready subscription per round, and rounds per wait (then timers get a turn).
_BATCH = 4
_MAX_ROUNDS = 64


def init(args=None):
    """rclpy.init; a malformed `--ros-args` (or parameter file) is a ParameterError."""
    # The DDS runtime's reading first: the same mistakes get the same one-line messages. Kept:
    # the parameters given to each node (parameter_overrides) are read from it.
    global _ros_args
    _ros_args = ros_args.parse(sys.argv if args is None else args, strict=False)[0]
    try:
        # Without rclpy's signal handlers: they shut the context down at SIGINT, before a node's
        # close() could publish its final counts. SIGINT is then Python's KeyboardInterrupt, raised
        # when the executor's wait returns (spin wakes at least every _MAX_WAIT_S for that).
        rclpy.init(args=args, signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    except RuntimeError as exc:  # rclpy's argument errors are RuntimeErrors (public behaviour)
        text = str(exc)
        if text.startswith('['):  # UnknownROSArgsError: the list of unknown arguments, as text
            unknown = text.strip('[]').split(',')[0].strip().strip("'")
            raise ParameterError(f"--ros-args: unknown argument '{unknown}'") from None
        # rcl appends the C source locations of the error (', at /path/file.c:123'): drop them.
        message = ' '.join(text.split()).split(', at /')[0]
        raise ParameterError(message.removeprefix('failed to initialize rcl: ')) from None


# --ros-args of the process, as runtime/ros_args.py reads them (init; else sys.argv's, as rclpy).
_ros_args = None


class Node(rclpy.node.Node):
    """
    rclpy's Node, moving messages of cdr's plain classes as serialized bytes.

    Any other message class (rclpy's own) takes rclpy's usual path. A parameter given (file or
    -p) with another type than its declared default is a ParameterError (rcl's rule, the DDS
    runtime's message).
    """

    def declare_parameter(self, name, value=None, descriptor=None, ignore_override=False):
        if not ignore_override:
            given = parameter_overrides(self)
            if name in given:
                check_type(self.get_name(), name, value, given[name])
        return super().declare_parameter(name, value, descriptor, ignore_override)

    def create_publisher(self, msg_type, topic, qos_profile, **kwargs):
        if not hasattr(msg_type, '__ros_type__'):
            return super().create_publisher(msg_type, topic, qos_profile, **kwargs)
        publisher = super().create_publisher(rclpy_type(msg_type), topic, qos_profile, **kwargs)
        return CdrPublisher(publisher, _steps(msg_type))

    def create_subscription(self, msg_type, topic, callback, qos_profile, **kwargs):
        if not hasattr(msg_type, '__ros_type__'):
            return super().create_subscription(msg_type, topic, callback, qos_profile, **kwargs)
        steps, ros_type = _steps(msg_type), rclpy_type(msg_type)
        malformed = [0]

        def on_bytes(data):
            if data[:2] != cdr.HEADER[:2]:  # another encapsulation (big endian): rclpy re-encodes
                data = rclpy.serialization.serialize_message(
                    rclpy.serialization.deserialize_message(data, ros_type))
            try:
                message = cdr.decode(steps, msg_type, data)
            except ValueError as error:  # not a message of this type: dropped, said once
                malformed[0] += 1
                if malformed[0] == 1:
                    self.get_logger().warn(f'{topic}: message dropped: {error} (further ones '
                                           'are dropped silently)')
                return
            callback(message)
        return super().create_subscription(ros_type, topic, on_bytes, qos_profile, raw=True,
                                           **kwargs)


class CdrPublisher:
    """An rclpy publisher that takes cdr's plain messages (the rest of its API unchanged)."""

    def __init__(self, publisher, steps):
        self.publisher = publisher
        self._steps = steps

    def publish(self, message):
        self.publisher.publish(cdr.encode(self._steps, message))

    def __getattr__(self, name):
        return getattr(self.publisher, name)


def rclpy_type(plain_type):
    """Return the rclpy class of a plain message class (`sensor_msgs/msg/JointState`)."""
    package, kind, name = plain_type.__ros_type__.split('/')
    return getattr(importlib.import_module(f'{package}.{kind}'), name)


_plans = {}


def _steps(plain_type):
    if plain_type not in _plans:
        steps = cdr.plan(plain_type.__ros_type__, cdr.plain_class)
        if steps is None:
            raise TypeError(f'{plain_type.__ros_type__}: no CDR plan (runtime/cdr.py)')
        _plans[plain_type] = steps
    return _plans[plain_type]


def descriptor(spec):
    """Return rcl_interfaces/ParameterDescriptor of a Spec (rclpy's class): parameters.py."""
    return descriptor_message(spec, service_message)


def parameter_overrides(node):
    """
    {name: value} of every parameter given to `node` (files, -p), declared or not.

    Read from the process's --ros-args by runtime/ros_args.py (rcl's rules, as the DDS runtime):
    rclpy keeps its own reading in the node, with no public accessor.
    """
    global _ros_args
    if _ros_args is None:  # rclpy.init was called by someone else: with sys.argv, by default
        _ros_args = ros_args.parse(sys.argv, strict=False)[0]
    return {name: value for name, (value, _) in ros_args.parameter_overrides(
        _ros_args, node.get_fully_qualified_name()).items()}


class WaitLoop:
    """
    One node's entities served from one reused wait set: rclpy's executor, made lean.

    rclpy's SingleThreadedExecutor builds a new wait set, with a context manager around every
    handle, for each wait, and hands out one message per ready subscription per wait; at the
    1 kHz sample topics that cost the model node about three times its model's own time
    (`bellows bench --only graph`, `graph.rclpy*` against `graph.*`). Here the wait set is built
    once per set of entities and each wait serves every ready subscription in rounds of up to
    `_BATCH` messages (as the DDS runtime does: the two halves of a sample stay in step after a
    stall), then ready timers, services (the parameter services `ros2 param` talks to), guard
    conditions and waitables (QoS event handlers). Callbacks run in the calling thread, one at a
    time, as in the single-threaded executor.
    """

    def __init__(self, node):
        self.node = node
        self._shape = None
        self._wait_set = None
        self._entities = ((), (), (), (), ())
        self._with_info = {}  # id(subscription) -> its callback takes (message, MessageInfo)
        self._next_slow = 0.0

    def _refresh(self):
        """Read the node's entities again; a new wait set only when they changed."""
        node = self.node
        entities = (list(node.subscriptions), list(node.timers), list(node.services),
                    list(node.guards), list(node.waitables))
        shape = tuple(tuple(id(e) for e in group) for group in entities)
        if shape != self._shape:
            subscriptions, timers, services, guards, waitables = entities
            counts = NumberOfEntities(len(subscriptions), len(guards), len(timers), 0,
                                      len(services))
            for waitable in waitables:
                counts += waitable.get_num_entities()
            self._wait_set = _rclpy.WaitSet(
                counts.num_subscriptions, counts.num_guard_conditions, counts.num_timers,
                counts.num_clients, counts.num_services, counts.num_events,
                node.context.handle)
            self._shape = shape
            self._with_info = {id(s): _takes_info(s.callback) for s in subscriptions}
        self._entities = entities

    def once(self, timeout_sec):
        """
        Wait up to `timeout_sec` (None: _MAX_WAIT_S) and serve whatever is ready.

        Subscriptions and timers are waited on every time; services, guard conditions and
        waitables (and the list of entities itself) only every `_SLOW_PERIOD`, which keeps the
        1 kHz cycle short: a `ros2 param` request is answered within that period (or the next
        wait's end on an idle node).
        """
        now = time.monotonic()
        slow = now >= self._next_slow
        if slow:
            self._refresh()
            self._next_slow = now + _SLOW_PERIOD
        subscriptions, timers, services, guards, waitables = self._entities
        wait_set = self._wait_set
        wait_set.clear_entities()
        for subscription in subscriptions:
            wait_set.add_subscription(subscription.handle)
        for timer in timers:
            wait_set.add_timer(timer.handle)
        if slow:
            for service in services:
                wait_set.add_service(service.handle)
            for guard in guards:
                wait_set.add_guard_condition(guard.handle)
            for waitable in waitables:
                waitable.add_to_wait_set(wait_set)
        timeout = _MAX_WAIT_S if timeout_sec is None else min(timeout_sec, _MAX_WAIT_S)
        wait_set.wait(round(timeout * 1e9))
        if not self.node.context.ok():
            raise rclpy.executors.ExternalShutdownException()
        ready = set(wait_set.get_ready_entities('subscription'))
        if ready:
            self._serve_subscriptions([s for s in subscriptions if s.handle.pointer in ready])
        ready = set(wait_set.get_ready_entities('timer'))
        for timer in timers:
            if timer.handle.pointer in ready and timer.handle.is_timer_ready():
                timer.handle.call_timer()
                timer.callback()
        if not slow:
            return
        ready = set(wait_set.get_ready_entities('service'))
        for service in services:
            if service.handle.pointer in ready:
                request, header = service.handle.service_take_request(service.srv_type.Request)
                if header is not None:
                    service.send_response(
                        service.callback(request, service.srv_type.Response()), header)
        ready = set(wait_set.get_ready_entities('guard_condition'))
        for guard in guards:
            if guard.handle.pointer in ready and guard.callback is not None:
                guard.callback()
        for waitable in waitables:
            if waitable.is_ready(wait_set):
                _run_to_completion(waitable.execute(waitable.take_data()))

    def _serve_subscriptions(self, subscriptions):
        for _ in range(_MAX_ROUNDS):
            full = False  # a full batch: that subscription may hold more, go round again
            for subscription in subscriptions:
                with_info = self._with_info[id(subscription)]
                for _ in range(_BATCH):
                    taken = subscription.handle.take_message(subscription.msg_type,
                                                             subscription.raw)
                    if taken is None:
                        break
                    if with_info:
                        subscription.callback(*taken)
                    else:
                        subscription.callback(taken[0])
                else:
                    full = True
            if not full:
                return


def _takes_info(callback):
    """Whether a subscription's callback takes (message, MessageInfo): rclpy's own rule."""
    try:
        inspect.signature(callback).bind(object())
        return False
    except TypeError:
        return True


def _run_to_completion(coroutine):
    """Run a coroutine that does not wait for anything (rclpy's waitables' `execute`)."""
    try:
        coroutine.send(None)
    except StopIteration:
        return
    coroutine.close()
    raise RuntimeError('a waitable awaited something; the lean loop cannot run it')


_loops = {}


def _loop(node):
    if node not in _loops:
        _loops[node] = WaitLoop(node)
    return _loops[node]


def spin_once(node, timeout_sec=None):
    _loop(node).once(timeout_sec)


def ok():
    return rclpy.ok()


def shutdown():
    global _ros_args
    _loops.clear()
    _ros_args = None
    rclpy.try_shutdown()
