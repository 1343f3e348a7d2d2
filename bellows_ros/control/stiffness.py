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
Stiffness set-point -> chamber compression target, corrected from the measured pressure.

Paper B tunes the spring's stiffness by compressing the air chamber: K = K_s(x_c) (13-17). The
inverse map (`models.stiffness_map`) gives the compression for a target stiffness *for a given
amount of gas*. A slow leak or a temperature change alters that amount, so a fixed x_c would drift
the stiffness. The amount is therefore estimated continuously from the measured pressure at the
measured (x_c, x_s) (`models.actuator.estimate_gas`, the gas law (17)), low-pass filtered (the
estimate is as noisy as the pressure sensor, and the drift it corrects takes seconds to minutes),
and the target compression is recomputed with it.

Where the spring buckles, K(x_c) rises to a peak and falls again; the map (and so this class) uses
the rising branch, from the elongated end stop to the peak (`models.stiffness_map`), and `range()`
is that branch's. A set-point outside it is refused with the range; one that a leak or a
temperature change pushes out of it later is held at the nearest end *and said*: `warning` holds
the reason until the set-point is reachable again.
"""
import math

from bellows_ros.models.actuator import estimate_gas, stiffness
from bellows_ros.models.stiffness_map import (BRANCH, compression_for_stiffness, stiffness_branch,
                                              stiffness_range)


class StiffnessSetpoint:
    """
    Tracks the gas amount and turns stiffness set-points into compression targets.

    params: ActuatorParams; gas_time_constant: s, filter of the gas estimate.
    `update_measurement(x_c, x_s, p, dt)` feeds one sample (m, m, Pa abs, s);
    `target()` -> x_c (m) for the current set-point (None before one is set);
    `estimate()` -> present stiffness (N/m) from the measured state;
    `branch()` -> (x_low, x_high) of the branch of K(x_c) used; `warning`: None, or why the
    target is not the set-point.
    """

    def __init__(self, params, gas_time_constant):
        self.params = params
        self.gas_time_constant = float(gas_time_constant)
        self.gas = params.p_ref
        self.k_target = None
        self.warning = None
        self._x_c = params.x_c_ref

    def set_stiffness(self, k_target):
        """Set the target (N/m). Raises ParameterError (naming the range) when unreachable."""
        compression_for_stiffness(self.params, k_target, self.gas)  # validates the range
        self.k_target = float(k_target)
        self.warning = None

    def range(self):  # noqa: A003 (the public name; a method cannot shadow the builtin)
        """(k_min, k_max), N/m, reachable on the map's branch with the present gas amount."""
        return stiffness_range(self.params, self.gas)

    def branch(self):
        """(x_low, x_high), m: the chamber compressions of the branch of K(x_c) the map uses."""
        return stiffness_branch(self.params, self.gas)

    def update_measurement(self, x_c, x_s, p, dt):
        measured = estimate_gas(self.params, p, x_c, x_s)
        blend = 1.0 - math.exp(-dt / self.gas_time_constant) if self.gas_time_constant > 0 else 1.0
        self.gas += blend * (measured - self.gas)
        self._x_c = x_c

    def target(self):
        if self.k_target is None:
            return None
        k_min, k_max = self.range()
        # The leak may have moved the range under a set-point that used to fit: hold the end, and
        # say so.
        k = min(max(self.k_target, k_min), k_max)
        self.warning = None
        if k != self.k_target:
            self.warning = (f'stiffness set-point {self.k_target:.1f} N/m is no longer reachable '
                            f'(range [{k_min:.1f}, {k_max:.1f}] N/m on the {BRANCH} branch '
                            f'with gas '
                            f'p_ref = {self.gas:.0f} Pa); holding {k:.1f} N/m')
        return compression_for_stiffness(self.params, k, self.gas)

    def estimate(self):
        """Stiffness (N/m) at the measured compression with the estimated gas amount."""
        return stiffness(self.params, self._x_c, self.gas)
