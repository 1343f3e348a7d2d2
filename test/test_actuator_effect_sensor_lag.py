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

"""Sensor lag (models/actuator_effects/sensor_lag.py): the reading follows by τ."""
from actuator_runs import fast_spring_step, PARAMS, PLANT, run
import numpy as np
import pytest

from bellows_ros.models.actuator_plant import ActuatorPlant


def test_sensor_lag_delays_the_pressure_reading():
    tau = 0.05
    lagged = ActuatorPlant(PARAMS, PLANT, {'sensor_lag': {'time_constant': tau}}, noise=False)
    direct = ActuatorPlant(PARAMS, PLANT, noise=False)
    a = run(lagged, 1.0, x_s=lambda t: fast_spring_step(t, rise=0.002))
    b = run(direct, 1.0, x_s=lambda t: fast_spring_step(t, rise=0.002))
    t = np.array([s.t for s in a])
    pa, pb = np.array([s.p for s in a]), np.array([s.p for s in b])
    p0, p1 = pb[0], pb[-1]
    # Time to reach 63 % of the step, measured from the direct sensor's crossing.
    level = p0 + 0.632 * (p1 - p0)
    delay = t[np.argmax(pa > level)] - t[np.argmax(pb > level)]
    assert delay == pytest.approx(tau, rel=0.2)
    assert abs(pa[-1] - pb[-1]) < 1.0         # same value once settled
