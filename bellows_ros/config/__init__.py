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
The config layer: reads the YAML files of `config/` and builds each layer's parameter objects.

The models hold only their dataclasses, checks and physics, and read no file; identification,
the doctor, the drivers, the nodes and the CLI get their parameters from here:

- `config.segment`: config/segment.yaml -> `SegmentParams` (the model, paper A),
  `SegmentPlantParams` (the simulated segment) and `SegmentIdentifyParams` (identification).
- `config.actuator`: config/actuator.yaml -> `ActuatorParams` (the model, paper B) and
  `ActuatorPlantParams` (the simulated drive, sensors and effects).
- `config.hardware`: config/hardware.yaml -> `ActuatorBoardConfig`, `ArmBusConfig` (the drivers);
  it builds no physics object.

A user's file (`--params`, the output of `bellows identify`) is laid over the defaults by
`bellows_ros.io.params.load`, which refuses names the defaults do not have. `config.ranges` holds
the documented ranges of the devices' parameters (the drawn devices of the benches and tests).
"""
__all__ = ['segment', 'actuator', 'hardware', 'ranges']
