"""The ROS runtime the nodes run on: rclpy when it imports, else Cyclone DDS with ROS 2's conventions.

Node code is the same either way::

    from bellows_ros.runtime import rt
    class Talker(rt.Node): ...
    def main(args=None):
        return rt.main(Talker, args)

`rt` exposes: `init`, `ok`, `shutdown`, `spin`, `spin_once`, `Node`, `Time` (nanoseconds, to_msg,
from_msg), `Duration` (publishers' `wait_for_all_acked`), `msg` (JointState, WrenchStamped, Float64,
DiagnosticArray, DiagnosticStatus, KeyValue, Clock, Header, Time), `SENSOR_DATA` (best-effort QoS),
`check_parameters(node)` and `main`. `USING_RCLPY` says which one was picked; `BELLOWS_RUNTIME=dds`
forces the DDS runtime.
"""
import gc
import os
import signal
import sys
import types

from bellows_ros.errors import BellowsError, ParameterError


def _load_rclpy():
    import rclpy
    import rclpy.duration
    import rclpy.qos
    import rclpy.time
    from builtin_interfaces.msg import Time as TimeMsg
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from geometry_msgs.msg import Vector3, Wrench, WrenchStamped
    from rosgraph_msgs.msg import Clock
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64, Header

    msg = types.SimpleNamespace(
        Time=TimeMsg, Header=Header, Float64=Float64, JointState=JointState, Vector3=Vector3,
        Wrench=Wrench, WrenchStamped=WrenchStamped, KeyValue=KeyValue,
        DiagnosticStatus=DiagnosticStatus, DiagnosticArray=DiagnosticArray, Clock=Clock)

    from rclpy.executors import ExternalShutdownException

    def undeclared_overrides(node):
        overrides = getattr(node, '_parameter_overrides', {})
        return [(name, 'parameters') for name in overrides if not node.has_parameter(name)]

    return types.SimpleNamespace(
        USING_RCLPY=True, init=lambda args=None: rclpy.init(args=args), ok=rclpy.ok,
        shutdown=rclpy.try_shutdown, spin=rclpy.spin, spin_once=rclpy.spin_once,
        Node=rclpy.node.Node, Time=rclpy.time.Time, Duration=rclpy.duration.Duration, msg=msg,
        SENSOR_DATA=rclpy.qos.qos_profile_sensor_data, undeclared_overrides=undeclared_overrides,
        Interrupted=(KeyboardInterrupt, ExternalShutdownException))


def _load_dds():
    from bellows_ros.runtime import dds_node
    from bellows_ros.runtime.messages import msg
    return types.SimpleNamespace(
        USING_RCLPY=False, init=dds_node.init, ok=dds_node.ok, shutdown=dds_node.shutdown,
        spin=dds_node.spin, spin_once=dds_node.spin_once, Node=dds_node.Node, Time=dds_node.Time,
        Duration=dds_node.Duration, msg=msg, SENSOR_DATA=dds_node.SENSOR_DATA,
        undeclared_overrides=lambda node: node.undeclared_overrides(), Interrupted=(KeyboardInterrupt,))


def _pick():
    if os.environ.get('BELLOWS_RUNTIME', '').lower() != 'dds':
        try:
            return _load_rclpy()
        except ImportError:
            pass
    return _load_dds()


rt = _pick()


def check_parameters(node):
    """Raise ParameterError for a given parameter (file or -p) the node does not declare."""
    unknown = rt.undeclared_overrides(node)
    if unknown:
        name, source = unknown[0]
        raise ParameterError(f"{source}: unknown parameter '{name}' for node '{node.get_name()}'")


def stamp_ns(stamp):
    """builtin_interfaces/Time -> integer nanoseconds."""
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def _raise_interrupt(signum, frame):
    raise KeyboardInterrupt


def main(node_class, args=None):
    """Run one node until Ctrl-C/SIGTERM; a user mistake is one line on stderr and exit status 2.

    `node_class()` must declare its parameters up front; `check_parameters` runs right after.
    A node may define `close()` for its own clean-up (devices, threads); it runs before shutdown.
    A node that declares `realtime_priority` and `cpu_latency_limit` gets them here
    (`realtime.request`, `realtime.limit_cpu_latency`), the latter until it shuts down.
    """
    from bellows_ros.runtime import realtime

    program = os.path.basename(sys.argv[0]) if args is None else node_class.__name__
    signal.signal(signal.SIGTERM, _raise_interrupt)
    # A shell starts background jobs with SIGINT ignored; ros2 launch stops nodes with SIGINT.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    node = None
    latency_request = None
    try:
        rt.init(args=args)
        node = node_class()
        check_parameters(node)
        realtime.request(node)
        latency_request = realtime.limit_cpu_latency(node)
        # Everything built so far (modules, type store, model tables) lives as long as the node:
        # keep the cyclic collector from walking it again and again in the 1 kHz callbacks.
        gc.freeze()
        rt.spin(node)
    except BellowsError as exc:
        message = str(exc).removeprefix(f'{program}: ')  # node errors often name the node already
        print(f'{program}: error: {message}', file=sys.stderr, flush=True)
        return 2
    except rt.Interrupted:
        pass
    finally:
        if node is not None:
            if hasattr(node, 'close'):
                node.close()
            node.destroy_node()
        if rt.ok():
            rt.shutdown()
        if latency_request is not None:
            os.close(latency_request)
    return 0


rt.check_parameters = check_parameters
rt.stamp_ns = stamp_ns
rt.main = main
