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
A child process for test_runtime_contract.py: one runtime ($BELLOWS_RUNTIME) against the contract.

Prints one JSON object: what the Protocols say of the runtime and its node, and what the node did
(parameters, a publish/subscribe roundtrip between two nodes of this process, a timer). On rclpy
the nodes are spun by rclpy's own SingleThreadedExecutor as well as by the runtime's loop.
"""
import importlib
import inspect
import json
import pkgutil
import sys
import time

from bellows_ros.errors import ParameterError
import bellows_ros.nodes
from bellows_ros.runtime import contract, Node, select_runtime
from bellows_ros.runtime.parameters import Spec

TOPIC = '/contract_probe/x'
SPECS = (Spec('gain', 1.0, 'a gain', low=0.0, high=10.0, read_only=False),)


class Talker(Node):
    """Declares a Spec and a plain parameter, publishes on a timer."""

    def __init__(self, **kwargs):
        super().__init__('contract_talker', **kwargs)
        self.values = self.declare_specs(SPECS)
        self.values['label'] = self.declare_parameter('label', 'none').value
        self.publisher_ = self.create_publisher(self.msg.Float64, TOPIC, 10)
        self.ticks = 0
        self.timer = self.create_timer(0.01, self.tick)

    def tick(self):
        self.ticks += 1
        self.publisher_.publish(self.msg.Float64(data=float(self.ticks)))


class Listener(Node):
    """Takes what the talker publishes."""

    def __init__(self, **kwargs):
        super().__init__('contract_listener', **kwargs)
        self.received = []
        self.subscription_ = self.create_subscription(self.msg.Float64, TOPIC,
                                                      lambda m: self.received.append(m.data), 10)


def spin_until(spin, done, seconds=20.0):
    end = time.monotonic() + seconds
    while not done() and time.monotonic() < end:
        spin()
    return done()


def node_classes():
    """Every bellows node class of bellows_ros/nodes (what the executables run)."""
    found = set()
    for module in pkgutil.iter_modules(bellows_ros.nodes.__path__):
        loaded = importlib.import_module(f'bellows_ros.nodes.{module.name}')
        found.update(value for value in vars(loaded).values() if inspect.isclass(value)
                     and issubclass(value, Node) and value is not Node)
    return sorted(found, key=lambda cls: cls.__name__)


def main():
    runtime = select_runtime()
    out = {'runtime': runtime.NAME, 'runtime_protocol': isinstance(runtime, contract.Runtime)}
    try:
        contract.check(runtime)
        out['check'] = ''
    except TypeError as error:
        out['check'] = str(error)
    runtime.init(['contract_probe', '--ros-args', '-p', 'contract_talker:gain:=2.5',
                  '-p', 'contract_talker:label:=given', '-p', 'contract_listener:gain:=3'])
    talker, listener = Talker.on(runtime)(), Listener.on(runtime)()
    out['node_protocol'] = all(isinstance(n, contract.RuntimeNode) for n in (talker, listener))
    out['entity_protocols'] = [isinstance(talker.publisher_, contract.Publisher),
                               isinstance(listener.subscription_, contract.Subscription),
                               isinstance(talker.timer, contract.Timer),
                               isinstance(talker.get_clock(), contract.Clock),
                               isinstance(talker.get_logger(), contract.Logger)]
    classes = node_classes()
    out['node_classes'] = {cls.__name__: issubclass(cls.on(runtime), runtime.Node)
                           for cls in classes}
    out['rclpy_node'] = False
    if runtime.NAME == 'rclpy':
        import rclpy.node
        out['rclpy_node'] = all(isinstance(n, rclpy.node.Node) for n in (talker, listener))
        out['node_classes'] = {cls.__name__: issubclass(cls.on(runtime), rclpy.node.Node)
                               for cls in classes}
    out['values'] = talker.values
    out['get_parameter'] = talker.get_parameter('gain').value
    out['has_parameter'] = [talker.has_parameter('gain'), talker.has_parameter('nothing')]
    # An integer given for a double declared: rcl's rule, a ParameterError on both runtimes.
    try:
        listener.declare_parameter('gain', 1.0)
        out['mistyped'] = ''
    except ParameterError as error:
        out['mistyped'] = str(error)
    talker.watch_parameters()
    out['fqn'] = talker.get_fully_qualified_name()
    out['roundtrip'] = spin_until(lambda: (runtime.spin_once(talker, timeout_sec=0.01),
                                           runtime.spin_once(listener, timeout_sec=0.01)),
                                  lambda: len(listener.received) >= 5)
    out['timer'] = talker.ticks
    if runtime.NAME == 'rclpy':
        # Real rclpy nodes: rclpy's own executor spins both, in one process.
        import rclpy.executors
        executor = rclpy.executors.SingleThreadedExecutor()
        executor.add_node(talker)
        executor.add_node(listener)
        before = len(listener.received)
        out['executor_roundtrip'] = spin_until(lambda: executor.spin_once(timeout_sec=0.01),
                                               lambda: len(listener.received) >= before + 5)
        executor.shutdown()
    for node in (listener, talker):
        node.destroy_node()
    runtime.shutdown()
    print(json.dumps(out), flush=True)


if __name__ == '__main__':
    sys.exit(main())
