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
The runtime contract as code: what the bellows nodes use of a runtime, and of its node class.

Two implementations: `rclpy_runtime` (its `Node` is an `rclpy.node.Node`) and `dds_node` (plain
Cyclone DDS with ROS 2's wire conventions). A bellows node class (runtime/node.py `Node`) is
composed with the runtime's `Node` (`NodeClass.on(runtime)`), so everything below is what it
may call on `self`; the names and signatures are rclpy's. test/test_runtime_contract.py holds
both runtimes to these Protocols and to their behaviour (parameters, a publish/subscribe
roundtrip, a timer).
"""
from types import ModuleType
from typing import Any, Callable, Optional, Protocol, runtime_checkable


@runtime_checkable
class Publisher(Protocol):
    """What `create_publisher` returns."""

    topic_name: str

    def publish(self, msg: Any) -> None: ...

    def get_subscription_count(self) -> int: ...

    def wait_for_all_acked(self, timeout: Any = ...) -> bool: ...


@runtime_checkable
class Subscription(Protocol):
    """What `create_subscription` returns."""

    topic_name: str

    def get_publisher_count(self) -> int: ...


@runtime_checkable
class Timer(Protocol):
    """What `create_timer` returns."""

    def cancel(self) -> None: ...


@runtime_checkable
class Clock(Protocol):
    """What `get_clock` returns: `now()` is the runtime's `Time` (ROS time with use_sim_time)."""

    def now(self) -> Any: ...


@runtime_checkable
class Logger(Protocol):
    """What `get_logger` returns."""

    def debug(self, message: str) -> Any: ...

    def info(self, message: str) -> Any: ...

    def warn(self, message: str) -> Any: ...

    def error(self, message: str) -> Any: ...

    def fatal(self, message: str) -> Any: ...


@runtime_checkable
class RuntimeNode(Protocol):
    """The runtime's node class, as the bellows nodes use it (rclpy.node.Node's names)."""

    def get_name(self) -> str: ...

    def get_namespace(self) -> str: ...

    def get_fully_qualified_name(self) -> str: ...

    def get_logger(self) -> Logger: ...

    def get_clock(self) -> Clock: ...

    # parameters: a value given (file, -p) of another type than the default is a ParameterError
    def declare_parameter(self, name: str, value: Any = None,
                          descriptor: Any = None) -> Any: ...

    def get_parameter(self, name: str) -> Any: ...

    def has_parameter(self, name: str) -> bool: ...

    def add_on_set_parameters_callback(self, callback: Callable[[list], Any]) -> None: ...

    def add_post_set_parameters_callback(self, callback: Callable[[list], None]) -> None: ...

    # entities
    def create_publisher(self, msg_type: type, topic: str, qos_profile: Any) -> Publisher: ...

    def create_subscription(self, msg_type: type, topic: str, callback: Callable[[Any], None],
                            qos_profile: Any) -> Subscription: ...

    def create_service(self, srv_type: Any, srv_name: str,
                       callback: Callable[[Any, Any], Any]) -> Any: ...

    def create_timer(self, timer_period_sec: float, callback: Callable[[], None]) -> Timer: ...

    def destroy_node(self) -> None: ...


@runtime_checkable
class Runtime(Protocol):
    """
    A runtime module: `rclpy_runtime` or `dds_node` (runtime/node.py `select_runtime`).

    `msg`: the message classes the nodes use (cdr.USED_TYPES), `srv`: the service types
    (cdr.USED_SERVICES); `Node`: the base class a bellows node is composed with (a `RuntimeNode`);
    `parameter_overrides(node)`: {name: value} given to the node (files, -p), read by
    runtime/ros_args.py on both; `descriptor(spec)`: a Spec as the runtime's parameter
    descriptor; `INTERRUPTED`, `USER_ERRORS`: exception tuples `run` treats as an end and as a
    user's mistake.
    """

    NAME: str
    msg: Any
    srv: Any
    Node: type
    Time: type
    Duration: type
    SENSOR_DATA: Any
    LATCHED: Any
    INTERRUPTED: tuple
    USER_ERRORS: tuple

    def service_message(self, ros_name: str) -> type: ...

    def init(self, args: Optional[list] = None) -> Any: ...

    def spin_once(self, node: Any, timeout_sec: Optional[float] = None) -> None: ...

    def ok(self) -> bool: ...

    def shutdown(self) -> None: ...

    def descriptor(self, spec: Any) -> Any: ...

    def parameter_overrides(self, node: Any) -> dict: ...


def check(runtime: ModuleType) -> None:
    """Raise TypeError naming what `runtime` (a module) or its `Node` class lacks."""
    missing = [name for name in _members(Runtime) if not hasattr(runtime, name)]
    missing += [f'Node.{name}' for name in _members(RuntimeNode)
                if not hasattr(getattr(runtime, 'Node', None), name)]
    if missing:
        raise TypeError(f"runtime {getattr(runtime, '__name__', runtime)} lacks "
                        + ', '.join(missing))


def _members(protocol: type) -> list:
    names = set(getattr(protocol, '__annotations__', {}))
    names.update(name for name, value in vars(protocol).items()
                 if callable(value) and not name.startswith('_'))
    return sorted(names)
