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
Heat exchange (models/actuator_effects/heat_exchange.py): heat, then relax.

The gas heats on a fast compression, then relaxes to the isothermal pressure.
"""
from actuator_runs import fast_spring_step, PARAMS, PLANT, run, SIGMA_P
import numpy as np

from bellows_ros.models.actuator import evaluate
from bellows_ros.models.actuator_plant import ActuatorPlant, model_params


def test_heat_exchange_overshoots_on_fast_compression_then_relaxes():
    tau = 0.5
    plant = ActuatorPlant(PARAMS, PLANT, {'heat_exchange': {'time_constant': tau}}, seed=2)
    samples = run(plant, 0.5 + 0.05 + 8 * tau, x_s=fast_spring_step)
    model = model_params(PARAMS)
    excess = np.array([s.p - evaluate(model, s.x_c, s.x_s)[0] for s in samples])
    t = np.array([s.t for s in samples])
    just_after = excess[(t > 0.55) & (t < 0.6)].mean()
    late = excess[t > 0.55 + 6 * tau].mean()
    assert just_after > 30 * SIGMA_P           # hotter gas: pressure above the isothermal value
    assert abs(late) < 0.05 * just_after       # relaxed back to the isothermal (ambient) value
    assert excess[(t > 0.55 + tau) & (t < 0.6 + tau)].mean() < 0.5 * just_after
