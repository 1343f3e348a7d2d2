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
Test session set-up: DDS on loopback for every test and every node process it starts.

ROS 2's own switch (`ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`) keeps discovery and traffic on
this machine; test_loopback_only.py counts the packets a whole simulated launch sends off it. The
simulated CAN bus joins its multicast group on loopback by itself (hardware/arm_bus.py). Graph
tests draw a ROS_DOMAIN_ID of their own, so tests do not hear each other's nodes.
"""
import os
import signal

from node_processes import LOOPBACK_ENVIRONMENT, SESSION, session_processes
import pytest

os.environ.setdefault('MPLBACKEND', 'Agg')
os.environ.update(LOOPBACK_ENVIRONMENT)
os.environ[SESSION] = str(os.getpid())


def pytest_report_header(config):
    import rclpy
    from node_processes import ros2_cli_missing
    try:
        from rclpy.experimental.events_executor import EventsExecutor  # noqa: F401
        executor = 'EventsExecutor'
    except ImportError:
        executor = 'no EventsExecutor'
    missing = ros2_cli_missing()
    rmw = os.environ.get('RMW_IMPLEMENTATION') or 'default RMW'
    cli = 'skipped: ' + missing if missing else 'yes'
    return (f'rclpy from {os.path.dirname(rclpy.__file__)} ({executor}, {rmw}); '
            f'ros2 command line: {cli}')


def pytest_collection_modifyitems(config, items):
    """
    In the parallel phase, modules with a slow test first (scripts/test.sh).

    pytest-xdist hands whole modules to its workers in collection order (scripts/test.sh turns its
    own reordering, by test count, off). A slow module of one test (test_sourced_ros, 40 s) ran
    alone at the end of the phase while the other worker idled; the quick modules now fill the
    end instead. The order within a module is kept.
    """
    if 'PYTEST_XDIST_WORKER' not in os.environ:  # a serial run keeps the usual order
        return
    slow = {item.module.__name__ for item in items if item.get_closest_marker('slow')}
    items.sort(key=lambda item: item.module.__name__ not in slow)


@pytest.fixture(autouse=True)
def no_process_left_running():
    """
    Every process a test starts, it stops: one left running skews every test after it.

    A leftover node on a colliding ROS_DOMAIN_ID answers another test's commands, so the leak is
    an error of the test that left it; the process is killed here so that it stops at one.
    """
    before = session_processes()
    yield
    left = {pid: name for pid, name in session_processes().items() if pid not in before}
    for pid in left:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    assert not left, f'the test left processes running (killed now): {sorted(left.values())}'


@pytest.fixture
def ros_context():
    """
    Yield an rclpy context of the test's own, on a free domain; shut it down after the test.

    rclpy's signal handlers stay off: the test process's are pytest's.
    """
    import rclpy
    from rclpy.signals import SignalHandlerOptions
    from node_processes import free_domain
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=int(free_domain()),
               signal_handler_options=SignalHandlerOptions.NO)
    yield context
    rclpy.try_shutdown(context=context)


@pytest.fixture
def build_node(ros_context):
    """
    Return `build(node_class, **parameters)`: a node in `ros_context` with those parameters.

    After the test each node built is closed (its devices, where it has any) and destroyed, the
    last built first.
    """
    from rclpy.parameter import Parameter
    built = []

    def build(node_class, **parameters):
        node = node_class(context=ros_context, parameter_overrides=[
            Parameter(name, value=value) for name, value in parameters.items()])
        built.append(node)
        return node
    yield build
    for node in reversed(built):
        if hasattr(node, 'close'):
            node.close()
        node.destroy_node()
