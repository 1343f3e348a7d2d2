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

"""Pressure friction (models/segment_effects/pressure_friction.py): friction grows with load."""
import pytest

from bellows_ros.config.segment import load_segment_params, load_segment_plant_params
from bellows_ros.models.segment_plant import NO_NOISE, SegmentPlant

PARAMS, PLANT = load_segment_params(), load_segment_plant_params()


def friction_band(effects, pressure):
    """Measured torque through psi = 0.1 rad moving up minus moving down, both chains at p, N·m."""
    ends = []
    for speed in (0.2, -0.2):      # rad/s, ending at the same angle
        plant = SegmentPlant(PARAMS, PLANT, effects, NO_NOISE)
        psi = 0.1 - 2.0 * speed
        for _ in range(2000):
            psi += speed * 1e-3
            sample = plant.step(1e-3, pressure, pressure, psi_imposed=psi)
        ends.append(sample.tau_ext)
    return ends[0] - ends[1]


def test_the_friction_band_widens_with_the_chains_pressure_only_with_the_effect():
    pressures = (PARAMS.p0, 3e5, 6e5)
    constant = [friction_band({}, p) for p in pressures]
    growing = [friction_band({'pressure_friction': {}}, p) for p in pressures]
    assert constant == pytest.approx([constant[0]] * 3, abs=1e-9)   # c_f alone
    assert growing[0] == pytest.approx(constant[0], abs=1e-9)       # no load at ambient
    assert growing[0] < growing[1] < growing[2]
    assert growing[2] - growing[0] > 1.0                            # N·m: c_f,p of the YAML
