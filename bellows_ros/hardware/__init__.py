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
The devices behind the driver: the arm on CAN, the actuator board on serial, and their simulations.

Every device implements one contract, `device.Device` (start, read a sample, write a command,
vent, health, close): the drivers (`arm_bus`, `actuator_board`) and their simulated twins at
protocol level (`sim_arm_bus`, `sim_actuator_board`). Each link has a protocol (`can_protocol`
with config/arm.dbc, `serial_protocol`). The other modules are their internals.
"""
__all__ = [
    'device',             # the device contract every device implements
    'arm_bus',             # the soft arm on CAN (python-can, cantools)
    'actuator_board',      # the actuator board on serial (pyserial)
    'can_protocol',        # the arm's CAN frames (config/arm.dbc)
    'serial_protocol',     # the board's serial frames (docs/protocols.md)
    'sim_arm_bus',         # the simulated arm: the firmware side of the CAN protocol
    'sim_actuator_board',  # the simulated board: the firmware side on a pseudo-terminal
    'faults',              # fault switches of the simulated devices
]
