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
The node base (runtime/node.py) in this process: parameters, topics, lifecycle and `run`.

Small subclasses of `Node` and `LifecycleNode` are built in an rclpy context of the test's own,
on a domain of their own, with their `--ros-args`: the Spec of each parameter decides its value
at start and every change once the node watches its parameters, a given parameter the node does
not declare is refused by name, topics of the contract get their QoS. `run` is called as a node's
`main` calls it: it stops when the node is done, on SIGTERM, or when rclpy is shut down, closes
the node, and turns a user's mistake into one line and exit status 2.
"""
from array import array
import gc
import math
import os
import signal
import threading

from node_processes import free_domain
import pytest
import rclpy
from rclpy.context import Context
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, ReliabilityPolicy
from rclpy.serialization import serialize_message

from bellows_ros import interfaces
from bellows_ros.errors import ParameterError
from bellows_ros.runtime import node as base
from bellows_ros.runtime.messages import msg
from bellows_ros.runtime.parameters import Spec

SPECS = (
    Spec('gain', 0.5, 'loop gain', low=0.0, high=10.0, read_only=False),
    Spec('mode', 'fast', 'how the loop runs', choices=('fast', 'slow'), read_only=False),
    Spec('port', '/dev/null', 'a port the node opens at start'),   # read-only: the default
    Spec('segments', [1], 'segments served', low=1, high=4, items=(1, 4), unique=True),
    Spec('weights', [1.0, 1.0], 'weight of each segment', low=0.0, high=10.0, items=(1, 4),
         read_only=False),
)
DEFAULTS = {spec.name: spec.default for spec in SPECS}


class Probe(base.Node):
    """A bellows node with the table above; 7.0 is a gain its own rule refuses."""

    def __init__(self, **kwargs):
        super().__init__('probe', **kwargs)
        self.declared = self.declare_specs(SPECS)
        self.taken = []

    def parameter_problem(self, changes):
        return 'a gain of 7 shakes the arm' if changes.get('gain') == 7.0 else ''

    def on_parameters(self, changed):
        self.taken.append(changed)


@pytest.fixture
def ros(monkeypatch):
    """Build a node of `cls` with `ros_args` in an rclpy context of its own; end all after."""
    monkeypatch.setenv('ROS_DOMAIN_ID', free_domain())
    made = []

    def build(cls, *ros_args, **kwargs):
        context = Context()
        rclpy.init(args=['test', '--ros-args', *ros_args], context=context)
        made.append((context, None))
        node = cls(context=context, **kwargs)
        made[-1] = (context, node)
        return node
    yield build
    for context, node in made:
        if node is not None:
            node.destroy_node()
        context.try_shutdown()


def test_stamp_ns_is_integer_nanoseconds():
    stamp = msg.Header().stamp
    stamp.sec, stamp.nanosec = 1_700_000_000, 999_999_999
    assert base.stamp_ns(stamp) == 1_700_000_000_999_999_999
    assert isinstance(base.stamp_ns(stamp), int)   # no float rounding of a 1 ns step


def test_the_defaults_or_the_given_values_are_declared_as_python_values(ros):
    plain = ros(Probe)
    assert plain.declared == DEFAULTS == plain.parameters
    given = ros(Probe, '-p', 'gain:=2.5', '-p', 'segments:=[2, 3]', '-p', 'mode:=slow')
    assert given.declared == {**DEFAULTS, 'gain': 2.5, 'segments': [2, 3], 'mode': 'slow'}
    assert type(given.parameters['segments']) is list   # rclpy hands over an array.array
    assert given.get_parameter('gain').value == 2.5
    given.check_parameters()   # everything given is declared


def test_each_spec_is_the_parameters_descriptor(ros):
    node = ros(Probe)
    gain, port, segments = node.describe_parameters(['gain', 'port', 'segments'])
    assert (gain.description, gain.read_only) == ('loop gain', False)
    assert [(r.from_value, r.to_value) for r in gain.floating_point_range] == [(0.0, 10.0)]
    assert port.read_only and not port.floating_point_range and not port.integer_range
    assert [(r.from_value, r.to_value) for r in segments.integer_range] == [(1, 4)]


@pytest.mark.parametrize('given, needle', [
    ('gain:=20.0', "parameter 'gain' = 20.0: expected 0..10"),
    ('gain:=3', "parameter 'gain' must be a double, got an integer 3"),
    ('mode:=medium', "parameter 'mode' = 'medium': expected one of 'fast', 'slow'"),
    ('segments:=[2, 2]', "parameter 'segments' = [2, 2]: an element is given twice"),
    ('segments:=[]', 'a parameter is given as an empty array ([])'),
])
def test_a_bad_value_given_at_start_is_refused_naming_the_parameter(ros, given, needle):
    with pytest.raises(ParameterError) as refused:
        ros(Probe, '-p', given)
    assert str(refused.value).startswith('probe: ') and needle in str(refused.value)


def test_a_given_parameter_the_node_does_not_declare_is_an_error(ros):
    node = ros(Probe, '-p', 'gian:=2.0', '-p', 'use_sim_time:=true')
    with pytest.raises(ParameterError, match="unknown parameter 'gian' for node 'probe'"):
        node.check_parameters()
    # rclpy's own parameters are the node's too
    ros(Probe, '-p', 'use_sim_time:=true').check_parameters()


def test_a_change_while_running_is_decided_by_the_spec_and_the_nodes_rule(ros):
    node = ros(Probe)
    node.declare_parameter('free', 1)   # a parameter without a Spec: the node reads it once
    node.watch_parameters()

    def change(*parameters):
        return node.set_parameters_atomically(list(parameters))

    # (bounds and read_only are the descriptor's too: rclpy may refuse first, in its words)
    for refused, reason in [
            (Parameter('gain', value=20.0), 'gain'),
            (Parameter('port', value='/dev/ttyUSB0'), 'read-only'),
            (Parameter('mode', value='medium'), "parameter 'mode' = 'medium': expected one of"),
            (Parameter('free', value=2), "parameter 'free' is read-only"),
            (Parameter('gain', value=7.0), 'a gain of 7 shakes the arm')]:
        result = change(refused)
        assert not result.successful and reason in result.reason, result.reason
    # one bad change refuses the whole set: nothing of it is taken
    assert not change(Parameter('gain', value=2.0), Parameter('mode', value='medium')).successful
    assert node.parameters == DEFAULTS and node.get_parameter('gain').value == 0.5
    assert node.taken == []

    assert change(Parameter('gain', value=2.0), Parameter('mode', value='slow')).successful
    assert node.parameters == {**DEFAULTS, 'gain': 2.0, 'mode': 'slow'}
    assert node.taken == [{'gain': 2.0, 'mode': 'slow'}]
    # an array arrives as `ros2 param set` sends it (array.array); the node gets a list
    assert not change(Parameter('weights', value=array('d', [0.5, -1.0]))).successful
    assert change(Parameter('weights', value=array('d', [0.5, 2.0]))).successful
    assert node.taken[-1] == {'weights': [0.5, 2.0]} and type(node.taken[-1]['weights']) is list
    assert type(node.parameters['weights']) is list


def test_contract_topics_get_their_qos_and_the_nodes_namespace(ros):
    node = ros(Probe, namespace='/arm_a')
    latched = node.publisher(interfaces.ESTOP)
    assert latched.topic_name == '/bellows/estop'   # absolute on purpose
    assert latched.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL
    assert latched.qos_profile.reliability == ReliabilityPolicy.RELIABLE
    assert latched.qos_profile.depth == 1
    command = node.publisher(interfaces.PRESSURE_COMMAND)
    assert command.topic_name == '/arm_a/bellows/pressure_command'
    assert command.qos_profile.depth == interfaces.COMMAND_DEPTH
    assert command.qos_profile.durability == DurabilityPolicy.VOLATILE
    reliable = node.subscription(interfaces.JOINT_STATES, lambda m: None)
    newest = node.subscription(interfaces.JOINT_STATES, lambda m: None, newest_only=True)
    assert reliable.qos_profile.reliability == ReliabilityPolicy.RELIABLE
    assert reliable.qos_profile.depth == interfaces.SAMPLE_DEPTH
    assert newest.qos_profile.reliability == ReliabilityPolicy.BEST_EFFORT


def test_a_sample_subscription_reads_joint_states_and_drops_other_bytes(ros):
    node = ros(Probe)
    samples = []
    subscription = node.sample_subscription(interfaces.JOINT_STATES, samples.append)
    message = msg.JointState(name=['segment_1'], position=[0.25], velocity=[-1.5],
                             effort=[math.nan])
    message.header.stamp.sec, message.header.stamp.nanosec = 12, 345
    # what the executor hands a raw subscription: the serialized message
    subscription.callback(serialize_message(message))
    subscription.callback(b'\x00\x01 no JointState')
    assert len(samples) == 1
    sample = samples[0]
    assert (sample.stamp_ns, sample.name, sample.position, sample.velocity) == \
        (12_000_000_345, ('segment_1',), (0.25,), (-1.5,))
    assert math.isnan(sample.effort[0])


class Managed(base.LifecycleNode):
    """A managed bellows node that records its transitions."""

    def __init__(self, **kwargs):
        super().__init__('managed', **kwargs)
        self.declared = self.declare_specs(SPECS[:1])
        self.transitions = []

    def on_configure(self, previous):
        self.transitions.append(('configure', previous.label))
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, previous):
        self.transitions.append(('activate', previous.label))
        return TransitionCallbackReturn.SUCCESS


def test_a_lifecycle_node_has_the_parameter_table_and_rcl_lifecycle(ros):
    with pytest.raises(ParameterError, match="managed: parameter 'gain' = -1.0"):
        ros(Managed, '-p', 'gain:=-1.0')
    node = ros(Managed, '-p', 'gain:=1.5')
    node.check_parameters()
    node.watch_parameters()
    assert node.declared == {'gain': 1.5}
    assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS
    assert node.trigger_activate() == TransitionCallbackReturn.SUCCESS
    assert node.transitions == [('configure', 'unconfigured'), ('activate', 'inactive')]
    assert not node.set_parameters([Parameter('gain', value=11.0)])[0].successful
    assert node.set_parameters([Parameter('gain', value=3.0)])[0].successful
    assert node.parameters == {'gain': 3.0}


# --- run: the node's main -----------------------------------------------------------------------

# The run tests spin the process's executor and signal the process: alone, after the others.
@pytest.fixture
def run(monkeypatch):
    """Run node classes as their `main` does, on a domain of their own; restore signal handlers."""
    monkeypatch.setenv('ROS_DOMAIN_ID', free_domain())
    handlers = {signum: signal.getsignal(signum) for signum in (signal.SIGINT, signal.SIGTERM)}
    threads = set(threading.enumerate())
    yield lambda classes, *ros_args: base.run(classes, ['node', '--ros-args', *ros_args])
    for signum, handler in handlers.items():
        signal.signal(signum, handler)
    gc.unfreeze()   # run freezes what was built, for a node process's life
    assert set(threading.enumerate()) <= threads, 'run left threads running'
    assert not rclpy.ok()


# A node that run failed to stop ends itself after this many ticks of its 10 ms timer, saying so:
# a broken `run` fails its test instead of hanging it (ticks, not seconds: a loaded host ticks
# slower, and a working run stops within a few).
BACKSTOP_TICKS = 1000


def recording(events, name, end=lambda node: None):
    """Return a node class `name` recording what run does with it; `end(node)` on each tick."""
    def __init__(self, **kwargs):
        base.Node.__init__(self, name.lower(), **kwargs)
        events.append(f'{name} built')
        self.ticks = 0
        self.create_timer(0.01, lambda: tick(self))

    def tick(node):
        node.ticks += 1
        if node.ticks == BACKSTOP_TICKS:
            events.append(f'{name} not stopped by run')
            node.done = True
        elif node.ticks == 2 * BACKSTOP_TICKS:   # nor by being done
            rclpy.shutdown()
        end(node)

    def close(self):
        events.append(f'{name} closed')

    def finish(self):
        events.append(f'{name} finished')
    return type(name, (base.Node,), {'__init__': __init__, 'close': close, 'finish': finish})


@pytest.mark.realtime
def test_run_ends_a_done_node_with_finish_then_close(run):
    events = []

    def done(node):
        node.done = True
    assert run(recording(events, 'Scenario', done)) == 0
    assert events == ['Scenario built', 'Scenario finished', 'Scenario closed']


@pytest.mark.realtime
@pytest.mark.parametrize('stop', ['sigterm', 'sigint', 'shutdown'])
def test_run_stops_on_a_signal_or_rclpys_shutdown_and_closes_in_reverse(run, stop):
    events = []

    def end(node):
        if node.ticks > 1:   # one signal or shutdown: run stops on it
            return
        if stop == 'shutdown':
            rclpy.shutdown()
        else:
            os.kill(os.getpid(), signal.SIGTERM if stop == 'sigterm' else signal.SIGINT)
    assert run([recording(events, 'First', end), recording(events, 'Second')]) == 0
    # built in order, closed in the reverse order; not finished: the node was not done
    assert events == ['First built', 'Second built', 'Second closed', 'First closed']


class Given(Probe):
    """The probe, done at its first tick: run either refuses it at start or ends it."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.create_timer(0.01, lambda: setattr(self, 'done', True))

    def finish(self):
        pass


@pytest.mark.realtime
def test_a_user_mistake_is_one_line_and_exit_status_2(run, capfd):
    class Broken(base.Node):
        def __init__(self, **kwargs):
            super().__init__('broken', **kwargs)
            raise ParameterError('Broken: the port /dev/nothing is no serial device')

    assert run(Broken) == 2
    assert capfd.readouterr().err == \
        'Broken: error: the port /dev/nothing is no serial device\n'
    assert run(Given, '-p', 'gain:=2.0') == 0
    capfd.readouterr()
    assert run(Given, '-p', 'extra:=1') == 2
    err = capfd.readouterr().err.strip().splitlines()
    assert err[-1] == ("Given: error: unknown parameter 'extra' for node 'probe' (given in a "
                       'params file or with -p; the node has no such parameter)'), err
    assert run(Given, '--no-such-flag') == 2
    assert "Given: error: --ros-args: unknown argument '--no-such-flag'" in capfd.readouterr().err
