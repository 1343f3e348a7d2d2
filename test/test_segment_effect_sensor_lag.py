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

"""Sensor lag (models/segment_effects/sensor_lag.py): only the measured pressure lags."""
import pytest

from bellows_ros.config.segment import load_segment_params, load_segment_plant_params
from bellows_ros.models.segment_plant import NO_NOISE, SegmentPlant

PLANT = load_segment_plant_params()


@pytest.fixture(scope='module')
def params():
    return load_segment_params()


def test_sensor_lag_delays_only_the_measured_pressure(params):
    lagged = SegmentPlant(params, PLANT, {'sensor_lag': {'tau': 0.2}}, NO_NOISE)
    plain = SegmentPlant(params, PLANT, {}, NO_NOISE)
    for _ in range(100):
        a = lagged.step(1e-3, 5e5, params.p0, psi_imposed=0.3)
        b = plain.step(1e-3, 5e5, params.p0, psi_imposed=0.3)
    assert lagged.p1 == pytest.approx(plain.p1)  # the chamber itself is the same
    assert a.p1 < b.p1 - 5e4  # the sensor still reads far below it
    assert a.tau_ext == pytest.approx(b.tau_ext)
