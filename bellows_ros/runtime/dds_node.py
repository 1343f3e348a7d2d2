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
A node on plain Cyclone DDS with rclpy's interface, for machines without ROS 2.

Only what the bellows nodes use: parameters (declared up front, from `--params-file` / `-p`),
publishers and subscriptions with ROS 2's wire conventions, timers for low-rate work, a logger, and
a clock that follows `/clock` when `use_sim_time` is set. One node per process.

Wire conventions (what `rmw_cyclonedds_cpp` in Jazzy does, so ROS 2 nodes interoperate):
- topic `/x` is DDS topic `rt/x`; type `pkg/msg/T` is `pkg::msg::dds_::T_` (see messages.py);
- data representation XCDR1 (plain CDR, little endian), as the RMW requests;
- participant USER_DATA `enclave=/;`; every reader and writer carries USER_DATA
  `typehash=RIHS01_<sha256>;` (rmw_dds_common's `encode_type_hash_for_user_data_qos`);
- default QoS: reliable, keep-last 10, volatile (rclpy's default profile);
- the ROS graph: every participant publishes rmw_dds_common/ParticipantEntitiesInfo on the DDS
  topic `ros_discovery_info` (reliable, transient local, keep-last 1): its GUID and, per node, the
  name, namespace and the GUIDs of the node's readers and writers, again whenever one is added.
  This is how `ros2 node list` and `ros2 topic info -v` on a ROS 2 machine attribute endpoints to
  nodes.

Execution model, like rclpy's single-threaded executor: subscription and timer callbacks run in
the thread that calls `spin_once`, one at a time. Publishing is allowed from any thread (the
driver's 1 kHz sampling loop publishes from its own thread).
"""
from dataclasses import dataclass
import math
import os
import sys
import threading
import time
import uuid

from cyclonedds.core import (DDSException, GuardCondition, InstanceState, Policy, Qos,
                             ReadCondition, SampleState, ViewState, WaitSet)
from cyclonedds.domain import Domain, DomainParticipant
from cyclonedds.internal import InvalidSample
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from bellows_ros.errors import ParameterError
from bellows_ros.runtime import parameter_services, ros_args
from bellows_ros.runtime.messages import (message_class, msg,  # noqa: F401 (msg: the interface)
                                          type_hash)
from bellows_ros.runtime.parameters import check_type, descriptor_message
from bellows_ros.runtime.services import fields_of, srv  # noqa: F401 (srv: the interface)

NAME = 'dds'


def service_message(ros_name):
    """Return the class of a message type inside a service (lifecycle_msgs/msg/State)."""
    return message_class(ros_name)


INTERRUPTED = ()  # SIGINT arrives as KeyboardInterrupt, as in plain Python
USER_ERRORS = ()  # every user mistake is already a ParameterError

# Longest time spin_once blocks in C: Python only handles SIGINT between bytecodes.
_MAX_WAIT_S = 0.1
# Samples taken per subscription per round, and rounds per spin_once (then timers get a turn).
_BATCH = 4
_MAX_ROUNDS = 64


class _Context:
    """
    Process-wide state.

    The DDS participant, the parsed `--ros-args`, the nodes (for the ROS graph).
    """

    def __init__(self):
        self.participant = None
        self.args = ros_args.RosArgs()
        self.shutdown = threading.Event()
        self.topics = {}
        self.nodes = []
        self.graph_writer = None
        # domain id -> its configured Cyclone domain, kept for the process's life
        self.domains = {}


_context = _Context()


def init(args=None):
    """
    Parse `--ros-args` from `args` (default `sys.argv`) and join the DDS domain.

    The domain is `$ROS_DOMAIN_ID` (default 0), as in ROS 2, configured for
    `$ROS_AUTOMATIC_DISCOVERY_RANGE` and `$ROS_STATIC_PEERS` as rmw_cyclonedds_cpp does
    (`discovery_config`). Returns the non-ROS arguments.
    """
    argv = list(sys.argv if args is None else args)
    _context.args, rest = ros_args.parse(argv)
    domain_text = os.environ.get('ROS_DOMAIN_ID', '') or '0'
    if not domain_text.isdigit() or int(domain_text) > 232:
        raise ParameterError(f"ROS_DOMAIN_ID='{domain_text}': expected an integer 0..232")
    domain_id = int(domain_text)
    if domain_id not in _context.domains:
        # The discovery fragment goes before CYCLONEDDS_URI's configuration, as in the RMW.
        config = discovery_config(os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE', ''),
                                  os.environ.get('ROS_STATIC_PEERS', ''))
        config += os.environ.get('CYCLONEDDS_URI', '')
        _context.domains[domain_id] = Domain(domain_id, config=config) if config else None
    _context.participant = DomainParticipant(
        domain_id, qos=Qos(Policy.Userdata(data=b'enclave=/;')))
    _context.shutdown.clear()
    _context.topics = {}
    _context.nodes = []
    info = message_class(_GRAPH_TYPE)
    _context.graph_writer = DataWriter(
        _context.participant, Topic(_context.participant, 'ros_discovery_info', info),
        qos=Qos(Policy.Reliability.Reliable(duration(milliseconds=100)),
                Policy.History.KeepLast(1), Policy.Durability.TransientLocal,
                Policy.DataRepresentation(use_cdrv0_representation=True),
                Policy.Userdata(data=f'typehash={type_hash(_GRAPH_TYPE)};'.encode())))
    _publish_graph()
    return rest


# What the tests, the benchmarks and the simulated launches run with: ROS 2's own switch for
# discovery on this host, and Cyclone bound to the loopback interface with multicast off.
LOOPBACK_ENVIRONMENT = {
    'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST',
    'CYCLONEDDS_URI': ('<CycloneDDS><Domain><General><Interfaces><NetworkInterface name="lo"/>'
                       '</Interfaces><AllowMulticast>false</AllowMulticast></General></Domain>'
                       '</CycloneDDS>'),
}


def discovery_config(discovery_range, static_peers):
    """
    Return the Cyclone XML fragment rmw_cyclonedds_cpp (Jazzy) puts before `$CYCLONEDDS_URI`.

    `discovery_range` is `$ROS_AUTOMATIC_DISCOVERY_RANGE`: LOCALHOST (multicast off, this host
    as the peer), OFF (no discovery beyond the process), SUBNET (the default: multicast), or
    SYSTEM_DEFAULT (Cyclone's own settings); `static_peers` is `$ROS_STATIC_PEERS` (`;`-separated).
    """
    discovery_range = (discovery_range or 'SUBNET').upper()
    if discovery_range not in ('LOCALHOST', 'OFF', 'SUBNET', 'SYSTEM_DEFAULT'):
        discovery_range = 'LOCALHOST'  # rcl: an unknown value means localhost only
    peers = [p for p in static_peers.split(';') if p] if discovery_range in (
        'LOCALHOST', 'SUBNET') else []
    if discovery_range == 'LOCALHOST':
        peers.insert(0, 'localhost')
    if discovery_range == 'SYSTEM_DEFAULT' or (discovery_range == 'SUBNET' and not peers):
        return ''
    config = '<CycloneDDS><Domain>'
    if discovery_range in ('LOCALHOST', 'OFF'):
        config += '<General><AllowMulticast>false</AllowMulticast></General>'
    if discovery_range == 'OFF':
        config += (f'<Discovery><ParticipantIndex>none</ParticipantIndex>'
                   f'<Tag>ros_discovery_off_{os.getpid()}</Tag>')
    else:
        config += ('<Discovery><ParticipantIndex>auto</ParticipantIndex>'
                   '<MaxAutoParticipantIndex>32</MaxAutoParticipantIndex>')
    if peers:
        config += '<Peers>' + ''.join(f'<Peer address="{p}"/>' for p in peers) + '</Peers>'
    return config + '</Discovery></Domain></CycloneDDS>,'


def ok():
    return _context.participant is not None and not _context.shutdown.is_set()


def shutdown():
    """Leave the domain: delete every node's entities, then the participant's."""
    _context.shutdown.set()
    for node in list(_context.nodes):
        node.destroy_node()
    _delete(_context.graph_writer, *_context.topics.values(), _context.participant)
    _context.participant = None
    _context.topics = {}
    _context.nodes = []
    _context.graph_writer = None


def _delete(*entities):
    """
    Delete DDS entities now, in the order given: children before their parent.

    cyclonedds-python deletes an entity in its `__del__`. Left to the garbage collector, a node's
    entities sit in reference cycles (a ReadCondition holds its reader, a callback its node), are
    collected at a random moment in no particular order, and a reader or participant deleted
    before what hangs on it corrupted the heap: a test process that joined and left the domain
    some tens of times crashed in a later write. `__del__` deletes once and then forgets the
    handle, so an entity deleted here is not deleted again.
    """
    for entity in entities:
        if entity is not None:
            entity.__del__()


_GRAPH_TYPE = 'rmw_dds_common/msg/ParticipantEntitiesInfo'


def _gid(entity):
    """rmw_dds_common/Gid of a DDS entity: its 16-byte GUID, as rmw_cyclonedds_cpp fills it."""
    return message_class('rmw_dds_common/msg/Gid')(data=list(entity.guid.bytes))


def _publish_graph():
    """Publish this participant's nodes and their endpoints on `ros_discovery_info`."""
    node_info = message_class('rmw_dds_common/msg/NodeEntitiesInfo')
    nodes = [node_info(node_namespace=node.get_namespace(), node_name=node.get_name(),
                       reader_gid_seq=[_gid(e.reader)
                                       for e in node._subscriptions + node._services],
                       writer_gid_seq=[_gid(w) for w in node._writers]
                       + [_gid(s.writer) for s in node._services])
             for node in _context.nodes]
    _context.graph_writer.write(message_class(_GRAPH_TYPE)(
        gid=_gid(_context.participant), node_entities_info_seq=nodes))


# --- QoS
# -------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class QoSProfile:
    """The QoS settings the nodes choose between (reliable or best effort, keep-last depth)."""

    depth: int = 10
    reliable: bool = True
    transient_local: bool = False


SENSOR_DATA = QoSProfile(depth=5, reliable=False)  # rclpy's qos_profile_sensor_data
# Reliable, transient local, depth 1: a late joiner gets the last message (a latched state).
LATCHED = QoSProfile(depth=1, reliable=True, transient_local=True)


def _qos(profile, ros_type, user_data=''):
    if isinstance(profile, int):
        profile = QoSProfile(depth=profile)
    reliability = (Policy.Reliability.Reliable(duration(milliseconds=100)) if profile.reliable
                   else Policy.Reliability.BestEffort)
    durability = (Policy.Durability.TransientLocal if profile.transient_local
                  else Policy.Durability.Volatile)
    return Qos(reliability, Policy.History.KeepLast(profile.depth), durability,
               Policy.DataRepresentation(use_cdrv0_representation=True),
               Policy.Userdata(data=f'{user_data}typehash={type_hash(ros_type)};'.encode()))


# --- time
# ------------------------------------------------------------------------------------------

class Time:
    """A point in time, in nanoseconds (rclpy.time.Time's interface)."""

    def __init__(self, nanoseconds=0, seconds=0.0):
        self.nanoseconds = int(nanoseconds) + int(round(seconds * 1e9))

    def to_msg(self):
        sec, nanosec = divmod(self.nanoseconds, 1_000_000_000)
        return message_class('builtin_interfaces/msg/Time')(sec=sec, nanosec=nanosec)

    @classmethod
    def from_msg(cls, stamp):
        return cls(nanoseconds=stamp.sec * 1_000_000_000 + stamp.nanosec)

    def seconds_nanoseconds(self):
        return divmod(self.nanoseconds, 1_000_000_000)


class Duration:
    """A span of time, in nanoseconds (rclpy.duration.Duration's interface)."""

    def __init__(self, seconds=0.0, nanoseconds=0):
        self.nanoseconds = int(nanoseconds) + int(round(seconds * 1e9))


class Clock:
    """System time, or the last `/clock` message when `use_sim_time` is on (0 before the first)."""

    def __init__(self):
        self.sim_time = None

    def now(self):
        if self.sim_time is not None:
            return Time(nanoseconds=self.sim_time)
        return Time(nanoseconds=time.time_ns())


# --- logging
# ---------------------------------------------------------------------------------------

class Logger:
    """ROS 2's console format: `[LEVEL] [time] [node]: message`, on stderr."""

    _ORDER = {level: i for i, level in enumerate(ros_args.LOG_LEVELS)}

    def __init__(self, name, level):
        self.name, self.level = name, self._ORDER[level]

    def _log(self, level, message):
        if self._ORDER[level] >= self.level:
            stamp = time.time()
            print(f'[{level.upper()}] [{stamp:.9f}] [{self.name}]: {message}', file=sys.stderr,
                  flush=True)

    def debug(self, message):
        self._log('debug', message)

    def info(self, message):
        self._log('info', message)

    def warn(self, message):
        self._log('warn', message)

    warning = warn

    def error(self, message):
        self._log('error', message)

    def fatal(self, message):
        self._log('fatal', message)


# --- parameters
# ------------------------------------------------------------------------------------

@dataclass
class Parameter:
    name: str
    value: object


# --- entities
# --------------------------------------------------------------------------------------

class Publisher:
    def __init__(self, writer, topic_name):
        self._writer, self.topic_name = writer, topic_name

    def publish(self, msg):  # noqa: F811 (rclpy's parameter name)
        self._writer.write(msg)

    def wait_for_all_acked(self, timeout=Duration(seconds=-1)):
        """
        Block until every matched reliable reader acknowledged all samples, or `timeout` passes.

        `timeout` is a Duration, negative = forever; True when all were acknowledged.
        """
        wait = duration(infinite=True) if timeout.nanoseconds < 0 else timeout.nanoseconds
        # DataWriter.wait_for_acks of cyclonedds 11.0.1 raises AttributeError on a timeout (it
        # names `Exception.DDS_RETCODE_TIMEOUT`); the C call's return code is unambiguous.
        code = self._writer._wait_for_acks(self._writer._ref, wait)
        if code not in (0, DDSException.DDS_RETCODE_TIMEOUT):
            raise DDSException(code, f'waiting for acknowledgements on {self.topic_name}')
        return code == 0

    def get_subscription_count(self):
        return self._writer.get_publication_matched_status().current_count


class Subscription:
    def __init__(self, reader, callback, topic_name):
        self.reader, self.callback, self.topic_name = reader, callback, topic_name
        self.condition = ReadCondition(reader, SampleState.NotRead | ViewState.Any
                                       | InstanceState.Alive)

    def get_publisher_count(self):
        return self.reader.get_subscription_matched_status().current_count


class Service:
    """
    A service on the wire of rmw_cyclonedds_cpp (runtime/services.py): requests taken, answered.

    Answered in the spinning thread, one request at a time, as rclpy's executor does.
    """

    # How long an answer waits for the client's reply reader to be matched (rmw_cyclonedds_cpp
    # waits the same in rmw_send_response before it gives up on a request).
    MATCH_WAIT = 0.1  # s

    def __init__(self, srv_type, name, callback, reader, writer):
        self.srv_type, self.service_name, self.callback = srv_type, name, callback
        self.reader, self.writer = reader, writer
        self.condition = ReadCondition(reader, SampleState.NotRead | ViewState.Any
                                       | InstanceState.Alive)

    def serve(self):
        for request in self.reader.take(N=8, condition=self.condition):
            if isinstance(request, InvalidSample):
                continue
            plain = self.srv_type.Request(**fields_of(request))
            response = self.callback(plain, self.srv_type.Response())
            reply = self.srv_type.WireResponse(client_guid=request.client_guid,
                                               sequence_number=request.sequence_number,
                                               **fields_of(response))
            end = time.monotonic() + self.MATCH_WAIT
            while not self.writer.get_publication_matched_status().current_count \
                    and time.monotonic() < end:
                time.sleep(0.005)
            self.writer.write(reply)


class Timer:
    """Periodic callback on the steady clock (low-rate work only: diagnostics, set-points)."""

    def __init__(self, period, callback):
        self.period, self.callback = float(period), callback
        self.next_due = time.monotonic() + self.period
        self.cancelled = False

    def cancel(self):
        self.cancelled = True


class Node:
    """rclpy.node.Node's interface on Cyclone DDS (the subset the bellows nodes use)."""

    def __init__(self, node_name, *, namespace=''):
        if _context.participant is None:
            raise RuntimeError('call init() before creating a node')
        args = _context.args
        namespace = namespace if namespace.startswith('/') else '/' + namespace
        self._name, self._namespace = ros_args.node_identity(args, node_name, namespace)
        self._logger = Logger(self._name, args.log_level)
        fqn = self._namespace.rstrip('/') + '/' + self._name
        self._overrides = ros_args.parameter_overrides(args, fqn)
        self._parameters, self._descriptors = {}, {}
        self._on_set, self._post_set = [], []  # parameter callbacks, as rclpy's
        self._subscriptions, self._timers, self._writers = [], [], []
        self._services = []
        self._waitset = WaitSet(_context.participant)
        self._wakeup = GuardCondition(_context.participant)
        self._waitset.attach(self._wakeup)
        self._clock = Clock()
        _context.nodes.append(self)
        # What rclpy's Node offers: `ros2 param list/get/set/describe` reach this node too.
        self._parameter_services = parameter_services.ParameterServices(self, srv)
        # rclpy's /parameter_events: every declaration and change, for rqt_reconfigure and
        # `ros2 param` watchers (depth 1000, reliable, volatile: rclpy's
        # qos_profile_parameter_events).
        self._parameter_events = self.create_publisher(
            message_class('rcl_interfaces/msg/ParameterEvent'), '/parameter_events',
            QoSProfile(depth=1000))
        _publish_graph()
        if self.declare_parameter('use_sim_time', False).value:
            self._clock.sim_time = 0
            self.create_subscription(message_class('rosgraph_msgs/msg/Clock'), '/clock',
                                     self._on_clock, QoSProfile(depth=1, reliable=False))

    def _on_clock(self, msg):  # noqa: F811 (the callback's message, as in rclpy)
        self._clock.sim_time = Time.from_msg(msg.clock).nanoseconds

    # names
    def get_name(self):
        return self._name

    def get_fully_qualified_name(self):
        return self._namespace.rstrip('/') + '/' + self._name

    def get_namespace(self):
        return self._namespace

    def resolve_topic_name(self, topic):
        return ros_args.resolve_topic(_context.args, topic, self._name, self._namespace)

    # parameters
    def declare_parameter(self, name, value=None, descriptor=None):
        if name in self._parameters:
            raise ParameterError(f"parameter '{name}' declared twice")
        if name in self._overrides:
            override, source = self._overrides[name]
            try:
                check_type(self._name, name, value, override)
            except ParameterError as exc:
                raise ParameterError(f'{source}: {exc}') from None
            value = override
        self._parameters[name] = Parameter(name, value)
        self._descriptors[name] = descriptor
        self._publish_parameter_event(new=[self._parameters[name]])
        return self._parameters[name]

    def _publish_parameter_event(self, new=(), changed=()):
        def entries(parameters):
            return [message_class('rcl_interfaces/msg/Parameter')(
                name=p.name, value=parameter_services.to_message(p.value)) for p in parameters]
        self._parameter_events.publish(message_class('rcl_interfaces/msg/ParameterEvent')(
            stamp=self._clock.now().to_msg(), node=self.get_fully_qualified_name(),
            new_parameters=entries(new), changed_parameters=entries(changed)))

    def parameter_names(self):
        return list(self._parameters)

    def describe_parameter(self, name):
        """rcl_interfaces/ParameterDescriptor of a declared parameter."""
        spec = self._descriptors.get(name)
        described = (descriptor_message(spec, message_class) if spec is not None else
                     message_class('rcl_interfaces/msg/ParameterDescriptor')(name=name))
        described.type = parameter_services.type_id(self._parameters[name].value)
        return described

    def add_on_set_parameters_callback(self, callback):
        """`callback([Parameter]) -> SetParametersResult` decides whether a change is taken."""
        self._on_set.append(callback)

    def add_post_set_parameters_callback(self, callback):
        """`callback([Parameter])` is told every change taken."""
        self._post_set.append(callback)

    def set_parameter(self, name, value):
        """Change one parameter as rclpy does (declared, same type, callbacks); the result."""
        return self.set_parameters_atomically({name: value})

    def set_parameters_atomically(self, values):
        """Change every parameter of {name: value}, or none; rcl_interfaces/SetParametersResult."""
        result = message_class('rcl_interfaces/msg/SetParametersResult')(successful=True)
        for name, value in values.items():
            if name not in self._parameters:
                result.successful, result.reason = False, f"parameter '{name}' is not declared"
            elif value is None:
                result.successful, result.reason = False, f"parameter '{name}': no value given"
            else:
                try:
                    check_type(self._name, name, self._parameters[name].value, value)
                except ParameterError as exc:
                    result.successful, result.reason = False, str(exc)
            if not result.successful:
                return result
        changes = [Parameter(name, value) for name, value in values.items()]
        for callback in self._on_set:
            result = callback(changes)
            if not result.successful:
                return result
        for change in changes:
            self._parameters[change.name] = change
        self._publish_parameter_event(changed=changes)
        for callback in self._post_set:
            callback(changes)
        return result

    def declare_parameters(self, namespace, parameters):
        prefix = f'{namespace}.' if namespace else ''
        return [self.declare_parameter(prefix + name, value) for name, value in parameters]

    def get_parameter(self, name):
        if name not in self._parameters:
            raise ParameterError(f"parameter '{name}' is not declared")
        return self._parameters[name]

    def has_parameter(self, name):
        return name in self._parameters

    def undeclared_overrides(self):
        """(name, source) of every given parameter the node did not declare."""
        return [(name, source) for name, (_, source) in self._overrides.items()
                if name not in self._parameters]

    # entities
    def _topic(self, msg_type, topic):
        resolved = self.resolve_topic_name(topic)
        key = (resolved, msg_type.__ros_type__)
        if key not in _context.topics:
            _context.topics[key] = Topic(_context.participant, 'rt' + resolved, msg_type)
        return resolved, _context.topics[key]

    def create_publisher(self, msg_type, topic, qos_profile=10):
        resolved, dds_topic = self._topic(msg_type, topic)
        writer = DataWriter(_context.participant, dds_topic,
                            qos=_qos(qos_profile, msg_type.__ros_type__))
        self._writers.append(writer)
        _publish_graph()
        return Publisher(writer, resolved)

    def create_subscription(self, msg_type, topic, callback, qos_profile=10):
        resolved, dds_topic = self._topic(msg_type, topic)
        reader = DataReader(_context.participant, dds_topic,
                            qos=_qos(qos_profile, msg_type.__ros_type__))
        subscription = Subscription(reader, callback, resolved)
        self._waitset.attach(subscription.condition)
        self._subscriptions.append(subscription)
        _publish_graph()
        return subscription

    def create_service(self, srv_type, srv_name, callback, qos_profile=10):
        """Offer a service answering `callback(request, response) -> response` (services.py)."""
        resolved = self.resolve_topic_name(srv_name)
        # One id for the pair, as rmw_cyclonedds_cpp writes it: clients match reader to writer.
        service_id = f'serviceid={uuid.uuid4().hex[:16]};'
        request_topic = Topic(_context.participant, f'rq{resolved}Request', srv_type.WireRequest)
        reply_topic = Topic(_context.participant, f'rr{resolved}Reply', srv_type.WireResponse)
        reader = DataReader(_context.participant, request_topic,
                            qos=_qos(qos_profile, srv_type.name + '_Request', service_id))
        writer = DataWriter(_context.participant, reply_topic,
                            qos=_qos(qos_profile, srv_type.name + '_Response', service_id))
        service = Service(srv_type, resolved, callback, reader, writer)
        self._waitset.attach(service.condition)
        self._services.append(service)
        _publish_graph()
        return service

    def create_timer(self, timer_period_sec, callback):
        timer = Timer(timer_period_sec, callback)
        self._timers.append(timer)
        return timer

    def get_logger(self):
        return self._logger

    def get_clock(self):
        return self._clock

    def destroy_node(self):
        if self._waitset is None:  # destroyed already
            return
        self._wakeup.set(True)
        endpoints = self._subscriptions + self._services
        for endpoint in endpoints:
            self._waitset.detach(endpoint.condition)
        self._waitset.detach(self._wakeup)
        _delete(*[e.condition for e in endpoints], *[e.reader for e in endpoints],
                *[s.writer for s in self._services], *self._writers, self._wakeup, self._waitset)
        self._subscriptions, self._timers, self._writers, self._services = [], [], [], []
        self._waitset = self._wakeup = None
        if self in _context.nodes and _context.graph_writer is not None:
            _context.nodes.remove(self)
            _publish_graph()

    # execution
    def _spin_once(self, timeout_sec):
        now = time.monotonic()
        wait = _MAX_WAIT_S if timeout_sec is None else min(timeout_sec, _MAX_WAIT_S)
        timers = [t for t in self._timers if not t.cancelled]
        if timers:
            wait = min(wait, max(0.0, min(t.next_due for t in timers) - now))
        if wait > 0:
            self._waitset.wait(duration(seconds=wait))
        # Round-robin in small batches, as rclpy's executor serves one ready entity at a time:
        # after a stall, messages of two topics that belong together (the driver's /joint_states
        # and /bellows/chambers halves of a sample) are then handled in step, not one topic's
        # whole backlog first.
        for _ in range(_MAX_ROUNDS):
            full = False  # a full batch: that reader may hold more, go round again
            for subscription in self._subscriptions:
                samples = subscription.reader.take(N=_BATCH, condition=subscription.condition)
                full = full or len(samples) == _BATCH
                for sample in samples:
                    if not isinstance(sample, InvalidSample):  # state changes carry no data
                        subscription.callback(sample)
            if not full:
                break
        for service in self._services:
            service.serve()
        now = time.monotonic()
        for timer in timers:
            if now >= timer.next_due:
                # Skip missed periods rather than bursting to catch up.
                timer.next_due += timer.period * max(1, math.floor((now - timer.next_due)
                                                                   / timer.period) + 1)
                timer.callback()


def spin_once(node, timeout_sec=None):
    node._spin_once(timeout_sec)


def descriptor(spec):
    """Return a parameter's descriptor: the DDS runtime keeps the Spec itself (parameters.py)."""
    return spec


def parameter_overrides(node):
    """{name: value} of every parameter given to `node` (files, -p), declared or not."""
    return {name: value for name, (value, _) in node._overrides.items()}
