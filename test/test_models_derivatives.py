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
The rate estimator (bellows_ros.models.derivatives): streaming and batch forms agree.

They give the same numbers, its delay and noise gain are the documented ones, and the users
share it.
"""
import math

import numpy as np
import pytest

from bellows_ros.config.segment import load_segment_plant_params
from bellows_ros.models.derivatives import rate, rates

PLANT = load_segment_plant_params()


def _stream(t, x, initial=0.0):
    out, previous, previous_t, held = [], None, None, initial
    for tk, xk in zip(t.tolist(), x.tolist()):
        held = rate(xk, previous, 0.0 if previous_t is None else tk - previous_t, held)
        out.append(held)
        previous, previous_t = xk, tk
    return np.array(out)


@pytest.mark.parametrize('seed', [1, 2, 3])
def test_streaming_and_batch_forms_give_the_same_numbers(seed):
    """Same floats, on irregular steps with repeated and backward stamps (held estimate)."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.choice([1e-3, 2e-3, 0.0, 0.5e-3], 2000, p=[0.7, 0.1, 0.1, 0.1]))
    t[500] = t[499] - 1e-3  # one stamp out of order
    x = np.cumsum(rng.standard_normal(2000)) * 1e-3
    batch = rates(t, x, initial=0.25)
    np.testing.assert_array_equal(batch, _stream(t, x, initial=0.25))
    assert batch[0] == 0.25
    still = np.flatnonzero(np.diff(t) <= 0) + 1
    assert still.size > 100
    np.testing.assert_array_equal(batch[still], batch[still - 1])  # held where time stands still


def test_rate_of_a_parabola_is_the_slope_half_a_step_back():
    """The documented delay: for x = t², the backward difference is exactly 2 (t - h/2)."""
    h = 1e-3
    t = np.arange(1000) * h
    np.testing.assert_allclose(rates(t, t * t)[1:], 2.0 * (t[1:] - h / 2), rtol=1e-9, atol=1e-12)


def test_noise_gain_is_sqrt2_over_h_and_sqrt6_over_h2_twice():
    """White noise σ on x gives σ√2/h on ẋ and, differenced twice, σ√6/h² (within 3 %)."""
    rng = np.random.default_rng(7)
    h, sigma = 1e-3, 1e-4
    t = np.arange(200_000) * h
    noise = sigma * rng.standard_normal(t.size)
    once = rates(t, noise)[2:]
    twice = rates(t, rates(t, noise))[2:]
    assert np.std(once) == pytest.approx(sigma * math.sqrt(2) / h, rel=0.03)
    assert np.std(twice) == pytest.approx(sigma * math.sqrt(6) / h ** 2, rel=0.03)


def test_short_and_empty_records():
    assert rates([], []).shape == (0,)
    np.testing.assert_array_equal(rates([0.0], [3.0], initial=1.5), [1.5])
    assert rate(1.0, None, 1e-3, held=0.7) == 0.7


def test_the_plant_moves_an_imposed_angle_with_the_same_rates():
    """The simulated segment's Ψ̇, Ψ̈ on an imposed path are the batch rates of that path."""
    from bellows_ros.config.segment import load_segment_params
    from bellows_ros.models.segment_plant import NO_NOISE, SegmentPlant

    params = load_segment_params()
    dt = 1e-3
    t = np.arange(400) * dt
    psi = 0.6 * np.sin(2 * np.pi * 1.5 * t) ** 2
    plant = SegmentPlant(params, PLANT, noise=NO_NOISE, psi0=float(psi[0]))
    true = []
    for value in psi[1:].tolist():
        sample = plant.step(dt, 3e5, params.p0, psi_imposed=value)
        true.append((sample.psi_dot, plant.psi_ddot))
    true = np.array(true)
    psi_dot = rates(t, psi)
    np.testing.assert_allclose(true[:, 0], psi_dot[1:], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(true[:, 1], rates(t, psi_dot)[1:], rtol=1e-9, atol=1e-9)
