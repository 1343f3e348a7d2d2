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
Backlash (models/actuator_effects/backlash.py): a dead band at reversals.

The nut moves back and the plate, and with it the pressure, does not.
"""
from actuator_runs import DT, PARAMS, PLANT, run
import pytest

from bellows_ros.models.actuator_plant import ActuatorPlant


def test_backlash_leaves_a_dead_band_at_reversals():
    width = 0.001
    results = {}
    for name, effects in (('backlash', {'backlash': {'width': width}}), ('tight', None)):
        plant = ActuatorPlant(PARAMS, PLANT, effects, noise=False, x_c0=0.0)
        run(plant, 2.0, 1.0, x_s=0.0)                     # compress, stop, then reverse briefly
        run(plant, 0.3, 0.0, x_s=0.0)
        counts_before, p_before = plant.step(DT, 0.0, 0.0).encoder_counts, plant.pressure
        run(plant, 0.25, -1.0, x_s=0.0)
        sample = plant.step(DT, 0.0, 0.0)
        travel = (counts_before - sample.encoder_counts) * PLANT.drive.metres_per_count
        results[name] = (travel, plant.pressure - p_before)
    travel, dp = results['backlash']
    assert 0.2 * width < travel < 0.9 * width     # the nut did move back ...
    assert dp == 0.0                              # ... but the plate (and the pressure) did not
    travel_tight, dp_tight = results['tight']
    assert travel_tight == pytest.approx(travel, rel=0.05)
    assert dp_tight < -100.0                      # without backlash the pressure falls at once
