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
Buckling (models/actuator_effects/buckling.py): the model's buckling term.

The plant's spring force is `actuator.buckling_force` with the YAML's onset, k_b times `scale`.
"""
from actuator_runs import PARAMS, PLANT
import pytest

from bellows_ros.models.actuator import evaluate
from bellows_ros.models.actuator_plant import ActuatorPlant, effect_parameters, model_params


def test_buckling_effect_is_the_models_buckling_term():
    from bellows_ros.models.actuator import without_buckling
    forces = {}
    for effects in ((), ('buckling',), {'buckling': {'scale': 0.5}}):
        plant = ActuatorPlant(PARAMS, PLANT, effects, noise=False, x_c0=0.045)
        sample = plant.step(1e-3, 0.0, x_s_imposed=0.012)
        forces[str(effects)] = sample.f
        expected = evaluate(model_params(PARAMS, effect_parameters(PLANT, effects)), sample.x_c,
                            0.012)[1]
        assert sample.f == pytest.approx(expected, abs=1e-9)
    plain, full, half = forces.values()
    assert full < half < plain - 1.0          # the buckled spring pushes back less
    assert plain == pytest.approx(
        evaluate(without_buckling(model_params(PARAMS)), 0.045 - 0.0, 0.012)[1], rel=1e-3)
