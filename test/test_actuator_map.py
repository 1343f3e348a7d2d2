"""Inverse stiffness map: round trips, monotonicity, clear errors outside the achievable range."""
import numpy as np
import pytest

from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator import load_actuator_params, pressure, stiffness
from bellows_ros.models.stiffness_map import (compression_for_pressure, compression_for_stiffness,
                                              stiffness_range)

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


def test_range_is_wider_with_more_gas():
    low_gas = stiffness_range(PARAMS, 95e3)
    high_gas = stiffness_range(PARAMS, 105e3)
    assert high_gas[0] > low_gas[0] and high_gas[1] > low_gas[1]


def test_compression_for_pressure_round_trip():
    for target in (92e3, 101325.0, 115e3):
        x = compression_for_pressure(PARAMS, target, x_s=0.004)
        assert pressure(PARAMS, x, 0.004) == pytest.approx(target, rel=1e-6)
    assert compression_for_pressure(PARAMS, 101325.0) == pytest.approx(PARAMS.x_c_ref, abs=1e-6)
    with pytest.raises(ParameterError, match='achievable range'):
        compression_for_pressure(PARAMS, 200e3)
