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
The actuator's drive train: motor, gearbox, lead screw and encoder (paper B, section II-A).

Its own module because both the simulated actuator (`actuator_plant`) and the actuator board's
driver (encoder scale, through `bellows_ros.config.hardware`) need it, and the driver needs none
of the gas and force physics of `actuator`.
"""
from dataclasses import dataclass
import math


@dataclass(frozen=True)
class Drive:
    """
    Motor, gearbox and lead screw (section II-A): a Pololu-class 12 V DC gear motor.

    supply_voltage V; resistance Ω; inductance H; torque_constant N·m/A (= back-EMF V·s/rad);
    rotor_inertia kg·m²; viscous_friction N·m·s/rad (motor side); gear_ratio (100:1);
    counts_per_rev: encoder counts per motor turn; lead: m per lead-screw turn (20 TPI = 1.27 mm);
    efficiency: lead screw (< 0.5, so it is not back-drivable).
    """

    supply_voltage: float
    resistance: float
    inductance: float
    torque_constant: float
    rotor_inertia: float
    viscous_friction: float
    gear_ratio: float
    counts_per_rev: int
    lead: float
    efficiency: float

    @property
    def metres_per_count(self):
        return self.lead / (self.gear_ratio * self.counts_per_rev)

    @property
    def max_speed(self):
        """Chamber speed (m/s) at full duty with no load: no-load motor speed through the drive."""
        k = self.torque_constant
        omega = k * self.supply_voltage / (k * k + self.resistance * self.viscous_friction)
        return omega / (2.0 * math.pi) / self.gear_ratio * self.lead
