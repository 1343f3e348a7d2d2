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
arm_graph: driver_node, model_node and arm_controller_node composed in one process.

The same three nodes, with their own names, parameters, topics and services, as the separate
executables run them (`ros2 run bellows_ros arm_graph --ros-args --params-file
config/nodes_sim.yaml`): a params file's sections reach each by its name, `-p name:=value` all
three. Composition saves the processes' own costs (interpreters, DDS participants, wake-ups):
`bellows bench --only 'graph*'` measures it against separate processes. All three spin on one
executor in the main thread (runtime/node.py `run`): no GIL handed between threads per sample.
"""
from bellows_ros.nodes.arm_controller_node import ArmControllerNode
from bellows_ros.nodes.driver_node import DriverNode
from bellows_ros.nodes.model_node import ModelNode
from bellows_ros.runtime import run

NODES = (DriverNode, ModelNode, ArmControllerNode)


def main(args=None):
    return run(NODES, args)


if __name__ == '__main__':
    raise SystemExit(main())
