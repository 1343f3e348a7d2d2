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

"""Stiffness set-point -> compression, with the gas-amount correction (no ROS)."""
import pytest

from bellows_ros.config.actuator import load_actuator_params, load_actuator_plant_params
from bellows_ros.control.pd import PDController, PDGains
from bellows_ros.control.stiffness import StiffnessSetpoint
from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator import pressure, stiffness
from bellows_ros.models.actuator_plant import ActuatorPlant
from bellows_ros.models.stiffness_map import stiffness_range

PLANT = load_actuator_plant_params()

PARAMS = load_actuator_params()


def test_target_inverts_the_model():
    k_min, k_max = stiffness_range(PARAMS)
    k = 0.5 * (k_min + k_max)
    setpoint = StiffnessSetpoint(PARAMS, gas_time_constant=1.0)
    assert setpoint.target() is None
    setpoint.set_stiffness(k)
    assert stiffness(PARAMS, setpoint.target()) == pytest.approx(k, rel=1e-3)


def test_unreachable_setpoint_names_the_range():
    setpoint = StiffnessSetpoint(PARAMS, gas_time_constant=1.0)
    with pytest.raises(ParameterError, match='outside the achievable range'):
        setpoint.set_stiffness(50.0)
    assert setpoint.k_target is None


@pytest.mark.slow
def test_leak_is_corrected_from_the_measured_pressure():
    """With air_leak on, the corrected controller holds K; a fixed x_c would drift."""
    # 3x the YAML's leak: a visible drift in 30 s. wall_bulging and buckling make the plant's
    # physics that of the model the controller inverts (E_V and buckling on), as on the actuator.
    leak = {'air_leak': {'conductance': 3e-11}, 'wall_bulging': {}, 'buckling': {}}
    k_min, k_max = stiffness_range(PARAMS)
    k_target = k_min + 0.4 * (k_max - k_min)
    gains = PDGains(kp=400.0, kd=0.0, velocity_cutoff=50.0, duty_max=0.8, deadband=2e-5)
    results = {}
    for corrected in (True, False):
        plant = ActuatorPlant(PARAMS, PLANT, effects=leak, noise=False)
        setpoint = StiffnessSetpoint(PARAMS, gas_time_constant=1.0 if corrected else 1e12)
        setpoint.set_stiffness(k_target)
        pd, dt, x = PDController(gains), 2e-3, plant.x_nut
        for k in range(int(30.0 / dt)):
            sample = plant.step(dt, pd.update(setpoint.target(), x, dt))
            x = plant.x_from_counts(sample.encoder_counts)
            if corrected:
                setpoint.update_measurement(x, sample.x_s, sample.p, dt)
        results[corrected] = stiffness(plant.params, plant.x_nut, plant.gas)
    assert results[True] == pytest.approx(k_target, rel=0.01)
    assert abs(results[False] - k_target) > 3 * abs(results[True] - k_target)


def test_setpoint_pushed_out_of_reach_by_the_gas_is_held_and_said():
    setpoint = StiffnessSetpoint(PARAMS, gas_time_constant=0.0)
    k_min, k_max = stiffness_range(PARAMS)
    setpoint.set_stiffness(k_min + 5.0)
    assert setpoint.warning is None
    x_c = setpoint.target()
    assert setpoint.branch()[0] <= x_c <= setpoint.branch()[1]
    # the gas warms up (more gas as p_ref): the measured pressure says the low end rose above the
    # set-point
    p = pressure(PARAMS, x_c, 0.0, 1.05 * PARAMS.p_ref)
    setpoint.update_measurement(x_c, 0.0, p, 1e-3)
    assert setpoint.target() == pytest.approx(PARAMS.chamber.x_min)
    assert 'no longer reachable' in setpoint.warning and 'rising branch' in setpoint.warning
