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
The runtime contract (runtime/contract.py) held against both runtimes, by one test.

Each runtime runs in a child process (contract_probe.py; the pytest process never imports rclpy):
its module and node class must satisfy the Protocols, and its nodes must behave: a parameter
given with -p wins over the default and passes its Spec, one of another type is refused, a
timer fires, and one node's messages reach another in the same process. On rclpy every node is
an `rclpy.node.Node` (every node class of bellows_ros/nodes composed with rclpy_runtime.Node
subclasses it) and rclpy's own executor spins them too.
"""
import json
from pathlib import Path
import subprocess
import sys

from runtimes import node_env

PROBE = Path(__file__).resolve().parent / 'contract_probe.py'
DOMAIN = '196'
NODE_CLASSES = {'ArmControllerNode', 'DriverNode', 'ModelNode', 'ScenarioNode', 'SimActuatorNode',
                'SimArmNode', 'StiffnessControllerNode'}


def test_each_runtime_keeps_the_contract(runtime, tmp_path):
    result = subprocess.run([sys.executable, str(PROBE)], capture_output=True, text=True,
                            env=node_env(runtime, ROS_DOMAIN_ID=DOMAIN), timeout=120, cwd=tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    out = json.loads(result.stdout.strip().splitlines()[-1])
    assert out['runtime'] == runtime
    assert out['runtime_protocol'] and out['check'] == '', out['check']
    assert out['node_protocol'] and all(out['entity_protocols']), out['entity_protocols']
    assert out['rclpy_node'] == (runtime == 'rclpy')
    # Every node class the executables run is composed with the runtime's node class.
    assert set(out['node_classes']) >= NODE_CLASSES and all(out['node_classes'].values()), \
        out['node_classes']
    assert out['values'] == {'gain': 2.5, 'label': 'given'}
    assert out['get_parameter'] == 2.5
    assert out['has_parameter'] == [True, False]
    mistyped = "parameter 'gain' must be a double, got an integer 3"
    assert mistyped in out['mistyped'], out['mistyped']
    assert out['fqn'] == '/contract_talker'
    assert out['roundtrip'] and out['timer'] >= 5
    if runtime == 'rclpy':
        assert out['executor_roundtrip']
