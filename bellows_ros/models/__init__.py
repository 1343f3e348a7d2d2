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
The physics of both papers, as pure functions and small stateful evaluators: no file, no I/O.

Paper A's segment (driving torque, Ogden material, membrane contact) and paper B's actuator (gas,
force, stiffness, geometry, drive train), each with a simulated plant that adds dynamics, sensors
and switchable physical effects. Parameters come in as objects; `bellows_ros.config` builds them
from the YAML files.
"""
__all__ = [
    'segment',            # paper A: parameters, regressors, the 1 kHz driving-torque evaluator
    'segment_plant',      # the simulated segment: valves, dynamics, sensors, effects
    'actuator',           # paper B: gas, force and stiffness of the dual-bellows actuator
    'actuator_plant',     # the simulated actuator: drive, sensors, effects
    'actuator_geometry',  # paper B's bellows geometry and augmented volume
    'actuator_drive',     # motor, gearbox, lead screw and encoder
    'stiffness_map',      # stiffness set-point -> chamber compression
    'ogden',              # paper A's membrane material
    'contact',            # paper A's membrane-rib contact
    'derivatives',        # the one rate estimator of the project
    'actuator_effects',   # the actuator's physical effects, one module each, and their registry
    'segment_effects',    # the segment's physical effects, one module each, and their registry
    'effect_registry',    # how a package of effect modules becomes a registry
    'effect_strengths',   # live effect strengths of a simulated plant
    'filters',            # vectorised lag, relaxation, play operator, recurrence, reversals
    'limits',             # bounds on parameters that size a computation
]
