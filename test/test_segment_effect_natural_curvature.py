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

"""Natural curvature (models/segment_effects/natural_curvature.py): a pressure-driven rest."""
import pytest

from bellows_ros.config.segment import load_segment_params, load_segment_plant_params
from bellows_ros.models.segment_plant import NO_NOISE, SegmentPlant

PARAMS, PLANT = load_segment_params(), load_segment_plant_params()


def held_torque(effects, pressure):
    """Measured torque holding psi = 0 with chain 1 at `pressure` (chain 2 at ambient), N·m."""
    plant = SegmentPlant(PARAMS, PLANT, effects, NO_NOISE)
    for _ in range(1500):
        sample = plant.step(1e-3, pressure, PARAMS.p0, psi_imposed=0.0)
    return sample.tau_ext


def test_the_rest_angle_moves_with_the_pressure_only_with_the_effect():
    pressures = (PARAMS.p0, 3e5, 6e5)
    shift = [held_torque({'natural_curvature': {}}, p) - held_torque({}, p) for p in pressures]
    assert shift[0] == pytest.approx(0.0, abs=1e-9)     # Ψ_j0(p0) = 0: nothing at ambient
    assert 0.0 < abs(shift[1]) < abs(shift[2])          # grows with the chain's pressure
