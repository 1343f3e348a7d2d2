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
The bellows part of every node, and `main`, which picks the runtime and composes the node with it.

A bellows node subclasses `Node` and is written against the runtime contract (runtime/contract.py:
rclpy.node.Node's names, which both runtimes' node classes implement)::

    class Talker(Node):
        def __init__(self, **kwargs):
            super().__init__('talker', **kwargs)
            self.pub = self.create_publisher(self.msg.Float64, '/x', 10)

    def main(args=None):
        return run(Talker, args)

`Talker.on(runtime)` is the class composed with the runtime's node class (`runtime.Node`), a
subclass of both: on rclpy `rclpy.node.Node`, so a node is spun by any rclpy executor and several
share a process (`rclpy.spin(Talker.on(rclpy_runtime)())`, after `rclpy_runtime.init()`); on the
DDS runtime `dds_node.Node`. `run` does that composition. `Node` adds what is bellows' own:
`declare_specs` (a node's parameter table, checked by `parameters.validate`, the one check, at
start and for every change while running), `publisher`/`subscription` (a topic of
bellows_ros/interfaces.py), `msg` and `srv` (the runtime's message and service classes), the
`parameters` dict kept current, and `runtime`.

A runtime is a module with the same names in both implementations (`rclpy_runtime`, `dds_node`),
the `Runtime` Protocol of runtime/contract.py. `select_runtime` picks one, once, in `run`:
`$BELLOWS_RUNTIME` = `rclpy` or `dds`, else rclpy when it imports. `rclpy_unavailable` asks
a child Python whether rclpy could run the nodes here, for a process (the bench, the tests) that
uses the DDS runtime itself.
"""
import array
import gc
import importlib
import os
import signal
import subprocess
import sys
import threading
from types import ModuleType
from typing import Any, Callable, Optional, Sequence

from bellows_ros.errors import BellowsError, ParameterError
from bellows_ros.runtime.parameters import validate

RUNTIMES = {'rclpy': 'bellows_ros.runtime.rclpy_runtime', 'dds': 'bellows_ros.runtime.dds_node'}


def select_runtime(choice: Optional[str] = None) -> ModuleType:
    """
    Pick the runtime module: `choice` or `$BELLOWS_RUNTIME`, else rclpy when it imports.

    Raises ParameterError for an unknown choice, or when rclpy was asked for and does not import.
    """
    choice = (choice or os.environ.get('BELLOWS_RUNTIME', '')).strip().lower()
    if choice and choice not in RUNTIMES:
        raise ParameterError(f"BELLOWS_RUNTIME='{choice}': expected one of {', '.join(RUNTIMES)}")
    if choice != 'dds':
        try:
            return importlib.import_module(RUNTIMES['rclpy'])
        except ImportError as exc:
            if choice == 'rclpy':
                raise ParameterError(f'BELLOWS_RUNTIME=rclpy: rclpy does not import ({exc}); '
                                     'source your ROS 2 setup.bash') from None
    return importlib.import_module(RUNTIMES['dds'])


def rclpy_unavailable() -> str:
    """
    Tell why rclpy cannot run the nodes here ('' when it can), asking a child Python.

    The child imports rclpy and the message package of every type the nodes use (cdr.USED_TYPES).
    A child, because a process on the DDS runtime must not load a second Cyclone DDS library.
    """
    from bellows_ros.runtime.cdr import USED_TYPES
    packages = sorted({ros_name.split('/')[0] for ros_name in USED_TYPES.values()})
    probe = subprocess.run([sys.executable, '-c', 'import rclpy, '
                            + ', '.join(f'{package}.msg' for package in packages)],
                           capture_output=True, text=True, timeout=60)
    if probe.returncode == 0:
        return ''
    lines = probe.stderr.strip().splitlines()
    return lines[-1] if lines else f'exit status {probe.returncode}'


def stamp_ns(stamp: Any) -> int:
    """builtin_interfaces/Time -> integer nanoseconds."""
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def _plain(value: Any) -> Any:
    """Return a parameter value as declared: rclpy hands arrays over as array.array."""
    return list(value) if isinstance(value, array.array) else value


class Node:
    """
    A bellows node's own part, on either runtime: composed with the runtime's node class.

    `on(runtime)` makes the class a node of that runtime, `NodeClass.on(runtime)`, a subclass
    of both (cached): on rclpy an `rclpy.node.Node`. See the module docstring.
    """

    # The runtime module (rclpy_runtime or dds_node): set on the class `on` returns.
    runtime: ModuleType

    @classmethod
    def on(cls, runtime: ModuleType) -> type:
        """Return this node class composed with `runtime.Node` (one class per pair, cached)."""
        if 'runtime' in cls.__dict__:  # composed already
            return cls
        key = (cls, runtime)
        if key not in _composed:
            _composed[key] = type(cls.__name__, (cls, runtime.Node), {
                'runtime': runtime, '__module__': cls.__module__,
                '__qualname__': cls.__qualname__, '__doc__': cls.__doc__})
        return _composed[key]

    def __init__(self, node_name: str, **kwargs: Any) -> None:
        """Create the node `node_name`; `kwargs` go to the runtime's Node (`namespace`, ...)."""
        runtime = getattr(type(self), 'runtime', None)
        if runtime is None:
            raise TypeError(f'{type(self).__name__} needs a runtime: build it with '
                            f'{type(self).__name__}.on(runtime)()')
        self.msg = runtime.msg
        self.srv = runtime.srv
        self._specs = {}
        # The value of every parameter declared with a Spec, kept current while the node runs.
        self.parameters = {}
        super().__init__(node_name, **kwargs)
        # Every parameter given to this node (files, -p), declared or not: {name: value}.
        self._given = runtime.parameter_overrides(self)

    # parameters
    def declare_specs(self, specs: Sequence[Any]) -> dict:
        """
        Declare every parameter of `specs` (runtime/parameters.py) and check its value.

        The value given (file or -p), else the default, is checked against its Spec
        (`parameters.validate`) before it is declared, the same way on both runtimes; rclpy also
        gets the Spec as the parameter's descriptor. Returns {name: value}.
        """
        values = {}
        for spec in specs:
            validate(self.get_name(), spec, self._given.get(spec.name, spec.default))
            values[spec.name] = _plain(self.declare_parameter(
                spec.name, spec.default, self.runtime.descriptor(spec)).value)
        self._specs.update({spec.name: spec for spec in specs})
        self.parameters.update(values)
        return values

    # A change while running (`ros2 param set`, rqt_reconfigure), the same way on both runtimes:
    # the runtime has checked that the parameter is declared and keeps its type; here its Spec
    # decides (read-only, type, bounds, choices, rule), and the node is told once the change is
    # taken.
    def _check_change(self, changes: Sequence[Any]) -> Any:
        result = self.runtime.service_message('rcl_interfaces/msg/SetParametersResult')(
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
        unknown = [name for name in self._given if not self.has_parameter(name)]
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
        return self.create_publisher(getattr(self.msg, topic.message), topic.name,
                                     self._qos(topic))

    def subscription(self, topic: Any, callback: Callable[[Any], None]) -> Any:
        """Create a subscription to a topic of the contract (bellows_ros/interfaces.py)."""
        return self.create_subscription(getattr(self.msg, topic.message), topic.name, callback,
                                        self._qos(topic))

    def _qos(self, topic: Any) -> Any:
        return self.runtime.LATCHED if topic.latched else topic.depth


_composed = {}


# Where the process is with respect to SIGINT/SIGTERM: while a node is being built a signal
# interrupts at once (KeyboardInterrupt); while it spins, a signal only sets `stop`, which the spin
# loop sees within one wait (a KeyboardInterrupt raised inside a C call of rclpy or Cyclone
# surfaces as some other error, a traceback and exit status 1); once clean-up has begun, further
# signals are ignored (a terminal's Ctrl-C reaches a launched node twice: from the terminal and
# from `ros2 launch`).
_signals = {'spinning': False, 'stop': False, 'closing': False}


def _on_signal(signum, frame):
    if _signals['closing']:
        return
    _signals['stop'] = True
    if not _signals['spinning']:
        raise KeyboardInterrupt


def run(node_class: Any, args: Optional[Sequence[str]] = None,
        runtime: Optional[ModuleType] = None) -> int:
    """
    Run one node until Ctrl-C/SIGTERM; a user mistake is one line on stderr and exit status 2.

    Picks the runtime (`select_runtime`) unless one is given, builds `node_class.on(runtime)()`
    (which must declare its parameters up front), then checks that every given parameter was
    declared.
    A node with a `done` attribute runs until it is true, then `finish()` is called (the scenario).
    A node may define `close()` for its own clean-up (devices, threads); it runs before shutdown.
    A node that declares `realtime_priority` and `cpu_latency_limit` gets them here
    (`realtime.request`, `realtime.limit_cpu_latency`), the latter until it shuts down.

    `node_class` may be a sequence of node classes: a composed process (nodes/arm_graph.py). Each
    node is built in that order, spun in a thread of its own (the first in the main thread, where
    the signals arrive), and closed in the reverse order.
    """
    from bellows_ros.runtime import realtime

    classes = tuple(node_class) if isinstance(node_class, (list, tuple)) else (node_class,)
    program = os.path.basename(sys.argv[0]) if args is None else classes[0].__name__
    # Installed whatever the shell gave: a shell starts background jobs with SIGINT ignored, and
    # ros2 launch stops nodes with SIGINT.
    _signals.update(spinning=False, stop=False, closing=False)
    signal.signal(signal.SIGTERM, _on_signal)
    signal.signal(signal.SIGINT, _on_signal)
    nodes, threads, latency_requests = [], [], []
    try:
        runtime = runtime or select_runtime()
        runtime.init(args)
        for cls in classes:
            nodes.append(cls.on(runtime)())
        for node in nodes:
            node.check_parameters()
            node.watch_parameters()
            realtime.request(node)
            latency_requests.append(realtime.limit_cpu_latency(node))
        # Everything built so far (modules, type store, model tables) lives as long as the node:
        # keep the cyclic collector from walking it again and again in the 1 kHz callbacks.
        gc.freeze()
        _signals['spinning'] = True
        for node in nodes[1:]:
            threads.append(threading.Thread(target=_spin, args=(runtime, node),
                                            name=f'spin-{node.get_name()}', daemon=True))
            threads[-1].start()
        _spin(runtime, nodes[0])
        if getattr(nodes[0], 'done', False):
            nodes[0].finish()
    except KeyboardInterrupt:
        pass
    except Exception as exc:
        # rcl's own argument and parameter errors are user mistakes too; a signal that shut
        # rclpy's context down ends the spin with its own exception.
        if isinstance(exc, BellowsError) or (runtime and isinstance(exc, runtime.USER_ERRORS)):
            return _user_error(program, exc)
        if not (runtime and isinstance(exc, runtime.INTERRUPTED)):
            raise
    finally:
        _signals['closing'] = _signals['stop'] = True
        for thread in threads:
            thread.join(timeout=2.0)  # a spin returns within one wait
        for node in reversed(nodes):
            if hasattr(node, 'close'):
                node.close()
            node.destroy_node()
        if runtime is not None and runtime.ok():
            runtime.shutdown()
        for request in latency_requests:
            if request is not None:
                os.close(request)
    return 0


def _spin(runtime: ModuleType, node: Node) -> None:
    """Spin `node` until a signal, its end (`done`, the scenario) or the runtime's shutdown."""
    while not _signals['stop'] and not getattr(node, 'done', False) and runtime.ok():
        runtime.spin_once(node, timeout_sec=None)


def _user_error(program: str, exc: Exception) -> int:
    message = ' '.join(str(exc).split())  # rcl's messages span lines
    message = message.removeprefix(f'{program}: ')  # node errors often name the node already
    print(f'{program}: error: {message}', file=sys.stderr, flush=True)
    return 2
