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
Air leak (models/actuator_effects/air_leak.py): the sealed gas escapes.

A leak switched on mid-run takes over at the next step, from where the gas was.
"""
from actuator_runs import DT, PARAMS, PLANT, run
import numpy as np
import pytest

from bellows_ros.models.actuator import gas_amount
from bellows_ros.models.actuator_geometry import P_ATM
from bellows_ros.models.actuator_plant import ActuatorPlant


@pytest.mark.parametrize('x_c0', [0.040, -0.020])
def test_air_leak_decays_pressure_towards_ambient(x_c0):
    plant = ActuatorPlant(PARAMS, PLANT, {'air_leak': {'conductance': 2e-10}}, seed=1, x_c0=x_c0)
    sealed = ActuatorPlant(PARAMS, PLANT, seed=1, x_c0=x_c0)
    p_start = plant.pressure
    samples = run(plant, 8.0, x_s=0.0)
    reference = run(sealed, 8.0, x_s=0.0)
    first = np.mean([s.p for s in samples[:500]])
    last = np.mean([s.p for s in samples[-500:]])
    assert abs(last - P_ATM) < 0.8 * abs(first - P_ATM)            # closer to ambient
    assert np.sign(last - P_ATM) == np.sign(p_start - P_ATM)      # but does not cross it
    assert abs(np.mean([s.p for s in reference[-500:]]) - sealed.pressure) < 5.0
    assert (plant.gas < PARAMS.p_ref) == (p_start > P_ATM)        # gas left, or came in


def test_a_leak_switched_on_mid_run_takes_over_at_the_next_step_with_continuous_state():
    plant = ActuatorPlant(PARAMS, PLANT, seed=1, x_c0=0.040)
    sealed = ActuatorPlant(PARAMS, PLANT, seed=1, x_c0=0.040)
    run(plant, 0.2, x_s=0.0)
    run(sealed, 0.2, x_s=0.0)
    gas, x_c, p = plant.gas, plant.x_nut, plant.pressure
    assert plant.pressure > P_ATM + 1e4 and plant.strengths()['air_leak'] == 0.0
    plant.set_strengths({'air_leak': 2e-9})
    # Nothing changes until the plant steps: the swap happens in the stepping thread.
    assert (plant.gas, plant.x_nut, plant.pressure, plant.effects) == (gas, x_c, p, {})
    assert plant.strengths()['air_leak'] == 2e-9
    plant.step(DT, 0.0, x_s_imposed=0.0)
    sealed.step(DT, 0.0, x_s_imposed=0.0)
    # One step of the leak: the gas falls by dN = dt P c (P - P_atm), from where it was.
    expected_drop = DT * p * 2e-9 * (p - P_ATM)
    assert plant.effects == {'air_leak': {'conductance': 2e-9}}
    assert 0.0 < (sealed.gas - plant.gas) and plant.x_nut == sealed.x_nut
    drop = (gas - plant.gas) * _amount_per_p_ref(plant)  # p_ref is proportional to the amount
    assert drop == pytest.approx(expected_drop, rel=1e-6)
    run(plant, 2.0, x_s=0.0)
    assert plant.pressure < p - 0.3 * (p - P_ATM)            # the leak drains it
    # Off again (strength 0): the gas amount stays where the leak left it.
    plant.set_strengths({'air_leak': 0.0})
    plant.step(DT, 0.0, x_s_imposed=0.0)
    held = plant.gas
    run(plant, 0.5, x_s=0.0)
    assert plant.gas == held and plant.effects == {}


def _amount_per_p_ref(plant):
    """Gas amount N (Pa·m³) per Pa of p_ref at the plant's present volumes."""
    return gas_amount(plant.params, 2.0) - gas_amount(plant.params, 1.0)
