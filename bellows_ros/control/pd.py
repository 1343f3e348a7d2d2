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
PD position control of the lead screw (paper B, section II: PD control on the chamber compression).

The lead screw is not back-drivable and the motor's electrical and mechanical time constants are
milliseconds, so the chamber behaves like a velocity-commanded integrator: x_c' ~ duty x v_max.
A proportional term alone then closes a first-order loop without overshoot; the derivative term
(on the measurement, not the error, so a set-point step does not kick) damps the motor's own lag.
The encoder velocity is low-pass filtered because differentiating a quantised position at 1 kHz
is mostly noise.
"""
from dataclasses import dataclass
import math


@dataclass(frozen=True)
class PDGains:
    """
    Gains and limits of the PD controller.

    kp: duty per metre of error (1/m); kd: duty per m/s (s/m); velocity_cutoff: Hz of the
    velocity filter; duty_max: output limit (-duty_max..duty_max); deadband: m of error inside
    which the output is zero (stops dithering on the encoder's last count).
    """

    kp: float
    kd: float
    velocity_cutoff: float
    duty_max: float
    deadband: float


class PDController:
    """
    Discrete PD with derivative on the measurement and output saturation.

    `update(target, x, dt)` -> duty in [-duty_max, duty_max]; target and x in m, dt in s.
    """

    def __init__(self, gains):
        self.gains = gains
        self.reset()

    def reset(self):
        self.velocity = 0.0
        self._previous = None

    def update(self, target, x, dt):
        g = self.gains
        if self._previous is not None and dt > 0:
            raw = (x - self._previous) / dt
            blend = 1.0 - math.exp(-2.0 * math.pi * g.velocity_cutoff * dt)
            self.velocity += blend * (raw - self.velocity)
        self._previous = x
        error = target - x
        if abs(error) <= g.deadband:
            return 0.0
        duty = g.kp * error - g.kd * self.velocity
        return max(-g.duty_max, min(g.duty_max, duty))
