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

"""PD position control of the lead screw, against the actuator plant's own drive (no ROS)."""
import pytest

from bellows_ros.config.actuator import load_actuator_params, load_actuator_plant_params
from bellows_ros.control.pd import PDController, PDGains
from bellows_ros.models.actuator_plant import ActuatorPlant

PLANT = load_actuator_plant_params()

GAINS = PDGains(kp=400.0, kd=0.0, velocity_cutoff=50.0, duty_max=0.8, deadband=2e-5)


def test_saturation_deadband_and_sign():
    pd = PDController(GAINS)
    assert pd.update(0.01, 0.0, 1e-3) == 0.8          # far below target: full compress
    assert pd.update(-0.01, 0.0, 1e-3) == -0.8
    assert pd.update(1e-5, 0.0, 1e-3) == 0.0          # inside the dead band
    assert pd.update(1e-3, 0.0, 1e-3) == pytest.approx(0.4)


def test_derivative_acts_on_measurement_only():
    pd = PDController(PDGains(kp=0.0, kd=1.0, velocity_cutoff=1e6, duty_max=1.0, deadband=0.0))
    pd.update(0.0, 0.0, 1e-3)
    # moving up at 0.1 m/s: the derivative term brakes, whatever the target does
    assert pd.update(5.0, 1e-4, 1e-3) == pytest.approx(-0.1, rel=1e-3)


def test_closed_loop_on_the_plant_reaches_target_without_overshoot():
    params = load_actuator_params()
    plant = ActuatorPlant(params, PLANT, noise=False, x_c0=-0.01)
    pd = PDController(GAINS)
    target, dt = 0.015, 1e-3
    minimum = plant.travel_time(-0.01, target) / GAINS.duty_max
    x, peak, settled_at = plant.x_nut, -1.0, None
    for k in range(int(3 * minimum / dt)):
        sample = plant.step(dt, pd.update(target, x, dt))
        x = plant.x_from_counts(sample.encoder_counts)
        peak = max(peak, x)
        if settled_at is None and abs(x - target) < 2.5e-4:
            settled_at = (k + 1) * dt
    assert settled_at is not None and settled_at <= 1.2 * minimum
    assert peak - target <= 0.05 * (target + 0.01)
    assert abs(x - target) < 1e-4
