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

"""Inverse stiffness map: round trips, monotonicity, clear errors outside the achievable range."""
import numpy as np
import pytest

from bellows_ros.config.actuator import load_actuator_params
from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator import pressure, stiffness
from bellows_ros.models.stiffness_map import (compression_for_pressure, compression_for_stiffness,
                                              stiffness_branch, stiffness_range)

PARAMS = load_actuator_params()


@pytest.mark.parametrize('gas', [None, 90e3, 97e3, 101325.0, 104e3, 125e3])
def test_round_trip_stiffness_compression_stiffness(gas):
    k_min, k_max = stiffness_range(PARAMS, gas)
    targets = np.linspace(k_min, k_max, 41)
    x = [compression_for_stiffness(PARAMS, k, gas) for k in targets]
    back = np.array([stiffness(PARAMS, v, gas) for v in x])
    assert np.max(np.abs(back / targets - 1.0)) < 0.005
    assert all(b > a for a, b in zip(x, x[1:]))      # monotone


def test_outside_the_range_names_the_range():
    k_min, k_max = stiffness_range(PARAMS)
    for k in (k_min * 0.98, k_max * 1.02):
        with pytest.raises(ParameterError, match='achievable range') as info:
            compression_for_stiffness(PARAMS, k)
        assert f'{k_min:.1f}' in str(info.value) and f'{k_max:.1f}' in str(info.value)


def test_more_gas_raises_the_low_end_and_buckles_sooner():
    low_gas, high_gas = stiffness_range(PARAMS, 95e3), stiffness_range(PARAMS, 105e3)
    assert high_gas[0] > low_gas[0]
    # the rising branch ends at the buckling peak, reached at a smaller compression with more gas
    assert stiffness_branch(PARAMS,
                            105e3)[1] < stiffness_branch(PARAMS, 95e3)[1] < PARAMS.chamber.x_max


def test_branch_is_the_rising_one_and_the_range_is_its_ends():
    x_low, x_high = stiffness_branch(PARAMS)
    assert x_low == PARAMS.chamber.x_min and x_high < PARAMS.chamber.x_max
    k_min, k_max = stiffness_range(PARAMS)
    assert k_max == pytest.approx(stiffness(PARAMS, x_high), rel=1e-9)
    assert k_max > max(stiffness(PARAMS, x) for x in np.linspace(x_low, PARAMS.chamber.x_max, 60))
    # a stiffness the falling branch also gives is mapped onto the rising branch
    k_end = stiffness(PARAMS, PARAMS.chamber.x_max)
    assert compression_for_stiffness(PARAMS, k_end) < x_high
    # with a little more gas the buckled spring ends below the elongated end: that low a stiffness
    # is not on the branch used, and the error says so
    gas = 106e3
    k_below = 0.5 * (stiffness(PARAMS, PARAMS.chamber.x_max,
                               gas) + stiffness_range(PARAMS, gas)[0])
    with pytest.raises(ParameterError, match='past the peak'):
        compression_for_stiffness(PARAMS, k_below, gas)


def test_compression_for_pressure_round_trip():
    for target in (92e3, 101325.0, 115e3):
        x = compression_for_pressure(PARAMS, target, x_s=0.004)
        assert pressure(PARAMS, x, 0.004) == pytest.approx(target, rel=1e-6)
    assert compression_for_pressure(PARAMS, 101325.0) == pytest.approx(PARAMS.x_c_ref, abs=1e-6)
    with pytest.raises(ParameterError, match='achievable range'):
        compression_for_pressure(PARAMS, 200e3)
