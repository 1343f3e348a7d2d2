"""The rclpy runtime: the nodes on ROS 2 itself (what `ros2 run` and `ros2 launch` start).

The same names as the DDS runtime (`dds_node`), so `runtime.node.run` uses either unchanged. Import
fails with ImportError where rclpy or the message packages are absent.
"""
import sys
import types

import rclpy
import rclpy.duration
import rclpy.exceptions
import rclpy.executors
import rclpy.node
import rclpy.qos
import rclpy.signals
import rclpy.time
from builtin_interfaces.msg import Time as TimeMsg
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Vector3, Wrench, WrenchStamped
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64, Header

from bellows_ros.errors import ParameterError
from bellows_ros.runtime import ros_args

NAME = 'rclpy'

msg = types.SimpleNamespace(
    Time=TimeMsg, Header=Header, Float64=Float64, JointState=JointState, Vector3=Vector3,
    Wrench=Wrench, WrenchStamped=WrenchStamped, KeyValue=KeyValue,
    DiagnosticStatus=DiagnosticStatus, DiagnosticArray=DiagnosticArray, Clock=Clock)

Time = rclpy.time.Time
Duration = rclpy.duration.Duration
SENSOR_DATA = rclpy.qos.qos_profile_sensor_data

# Raised by a spinning executor when something else shut rclpy's context down.
INTERRUPTED = (rclpy.executors.ExternalShutdownException,)
# A user's mistake in a node name, namespace, topic name or parameter, as rclpy reports it.
USER_ERRORS = (rclpy.exceptions.ParameterException, rclpy.exceptions.InvalidNodeNameException,
               rclpy.exceptions.InvalidNamespaceException,
               rclpy.exceptions.InvalidTopicNameException)

_executor = None
_MAX_WAIT_S = 0.1  # longest wait in C, so SIGINT/SIGTERM are acted on promptly


def init(args=None):
    """rclpy.init; a malformed `--ros-args` (or parameter file) is a ParameterError."""
    # The DDS runtime's reading first: the same mistakes get the same one-line messages.
    ros_args.parse(sys.argv if args is None else args, strict=False)
    try:
        # Without rclpy's signal handlers: they shut the context down at SIGINT, before a node's
        # close() could publish its final counts. SIGINT is then Python's KeyboardInterrupt, raised
        # when the executor's wait returns (spin wakes at least every _MAX_WAIT_S for that).
        rclpy.init(args=args, signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    except _rclpy.UnknownROSArgsError as exc:
        # rclpy's message is the list of unknown arguments, as text.
        unknown = str(exc).strip("[]").split(',')[0].strip().strip("'")
        raise ParameterError(f"--ros-args: unknown argument '{unknown}'") from None
    except (_rclpy.RCLError, _rclpy.RCLInvalidROSArgsError) as exc:
        # rcl appends the C source locations of the error (', at /path/file.c:123'): drop them.
        message = ' '.join(str(exc).split()).split(', at /')[0]
        raise ParameterError(message.removeprefix('failed to initialize rcl: ')) from None


def create_node(name):
    return rclpy.node.Node(name)


def parameter_overrides(node):
    """{name: value} of every parameter given to `node` (files, -p), declared or not."""
    # rclpy keeps them in the node (rcl resolves files and -p rules); no public accessor exists.
    return {name: parameter.value for name, parameter in node._parameter_overrides.items()}


def _the_executor():
    # One executor for the process, reused by spin and spin_once (rclpy.spin_once would build
    # and tear down a wait set around every call).
    global _executor
    if _executor is None:
        _executor = rclpy.executors.SingleThreadedExecutor()
    return _executor


def spin(node):
    executor = _the_executor()
    executor.add_node(node)
    try:
        while rclpy.ok():
            executor.spin_once(timeout_sec=_MAX_WAIT_S)
    finally:
        executor.remove_node(node)


def spin_once(node, timeout_sec=None):
    executor = _the_executor()
    if node not in executor.get_nodes():
        executor.add_node(node)
    executor.spin_once(timeout_sec=timeout_sec)


def ok():
    return rclpy.ok()


def shutdown():
    global _executor
    if _executor is not None:
        _executor.shutdown()
        _executor = None
    rclpy.try_shutdown()
