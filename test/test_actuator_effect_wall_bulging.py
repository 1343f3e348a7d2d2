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
Wall bulging (models/actuator_effects/wall_bulging.py): the augmented volume.

With the effect on, the plant's volume is B(5), B(6) with the YAML's E_V.
"""
from actuator_runs import PARAMS, PLANT
import pytest

from bellows_ros.models.actuator import evaluate
from bellows_ros.models.actuator_plant import ActuatorPlant


def test_wall_bulging_adds_volume_under_pressure():
    bulging = ActuatorPlant(PARAMS, PLANT, ['wall_bulging'], noise=False, x_c0=0.045)
    rigid = ActuatorPlant(PARAMS, PLANT, noise=False, x_c0=0.045)
    assert bulging.pressure < rigid.pressure - 500.0
    # With the effect on, the plant is the YAML's augmented model.
    assert bulging.pressure == pytest.approx(evaluate(PARAMS, 0.045, 0.0)[0], rel=1e-9)
