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
One bellows of paper B (models/actuator_geometry.py): B(2)-B(6) and B(10).

The frusta's shape against the volumes and areas, E_V's three forms and its derivatives, on the
default chamber and spring of config/actuator.yaml (Table II) and on E_V coefficients drawn at
random. Lengths m, volumes m³, areas m², pressures Pa abs.
"""
import dataclasses
import math

import numpy as np
import pytest

from bellows_ros.config.actuator import load_actuator_params
from bellows_ros.models.actuator_geometry import (area, Bellows, e_v, frustum_state, P_ATM,
                                                  volume, volume_geo)

PARAMS = load_actuator_params()


def bulged(bellows, seed):
    """`bellows` with 10 E_V coefficients drawn at random (seeded), a few mL each."""
    rng = np.random.default_rng(seed)
    return dataclasses.replace(bellows, e_v=tuple(rng.uniform(-5e-6, 5e-6, 10)))


def test_geometric_volumes_at_rest_match_table_ii():
    assert volume_geo(PARAMS.chamber, 0.0) * 1e6 == pytest.approx(56.9, abs=0.05)
    assert volume_geo(PARAMS.spring, 0.0) * 1e6 == pytest.approx(46.0, abs=0.05)
    # Compression (positive x) shrinks the volume over the working range.
    assert volume_geo(PARAMS.chamber,
                      0.02) < volume_geo(PARAMS.chamber, 0.0) < volume_geo(PARAMS.chamber, -0.02)


def test_geometric_volume_slope_is_the_derivative_of_the_volume():
    from bellows_ros.models.actuator_geometry import volume_geo_slope
    for bellows in (PARAMS.chamber, PARAMS.spring):
        for x in (-0.02, 0.0, 0.015, 0.03):
            h = 1e-7
            numeric = (volume_geo(bellows, x + h) - volume_geo(bellows, x - h)) / (2 * h)
            assert volume_geo_slope(bellows, x) == pytest.approx(numeric, rel=1e-6)
    # The chamber's end stop sits where its volume peaks: extending further would raise P again.
    c = PARAMS.chamber
    assert volume_geo_slope(c, c.x_min) == pytest.approx(0.0, abs=2e-5)


def test_e_v_forms_of_the_newton_solve_and_the_fit_equal_the_polynomial():
    """E_V (5) as a cubic in q (gas-law Newton) and as monomials (fit) against `e_v` itself."""
    from bellows_ros.models.actuator_geometry import e_v, e_v_in_q, e_v_regressors
    rng = np.random.default_rng(3)
    bellows = dataclasses.replace(PARAMS.spring, e_v=tuple(rng.uniform(-5e-6, 5e-6, 10)))
    for x, p in zip(rng.uniform(-0.01, 0.03, 20), rng.uniform(85e3, 125e3, 20)):
        value = e_v(bellows, x, p)[0]
        q = (p - P_ATM) / P_ATM
        c0, c1, c2, c3 = e_v_in_q(bellows, x)
        assert c0 + q * (c1 + q * (c2 + q * c3)) == pytest.approx(value, rel=1e-12, abs=1e-20)
        assert (np.dot(e_v_regressors(bellows, x, p), bellows.e_v)
                == pytest.approx(value, rel=1e-12, abs=1e-20))


@pytest.mark.parametrize('bellows', [PARAMS.chamber, PARAMS.spring], ids=['chamber', 'spring'])
def test_the_large_radius_keeps_the_wall_length_of_b2(bellows):
    """B(3) solves B(2): (R - r)² + (h0 - Δh)²/4 stays (R0 - r)² + h0²/4; R(0) = R0."""
    r, h0 = bellows.r_small, bellows.h0
    wall = (bellows.r_big - r) ** 2 + h0 ** 2 / 4
    for x in np.linspace(bellows.x_min, bellows.x_max, 9):
        radius, d_radius, f = frustum_state(bellows, x)
        dh = x / bellows.n
        assert (radius - r) ** 2 + (h0 - dh) ** 2 / 4 == pytest.approx(wall, rel=1e-12)
        assert f == pytest.approx(radius ** 2 + r ** 2 + radius * r, rel=1e-12)
        step = 1e-8  # dR/dΔh, Δh = x / n
        numeric = (frustum_state(bellows, x + bellows.n * step)[0]
                   - frustum_state(bellows, x - bellows.n * step)[0]) / (2 * step)
        assert d_radius == pytest.approx(numeric, rel=1e-6)
    assert frustum_state(bellows, 0.0)[0] == pytest.approx(bellows.r_big, rel=1e-12)


def test_the_geometric_volume_is_the_volume_of_its_2n_frusta():
    """B(4) against the frusta integrated slice by slice: 2n of height (h0 - Δh)/2, r to R."""
    bellows = PARAMS.chamber
    for x in (bellows.x_min, 0.0, 0.02, bellows.x_max):
        radius = frustum_state(bellows, x)[0]
        height = (bellows.h0 - x / bellows.n) / 2
        z = np.linspace(0.0, height, 20001)
        slices = math.pi * (bellows.r_small + (radius - bellows.r_small) * z / height) ** 2
        by_slices = 2 * bellows.n * float(np.sum((slices[1:] + slices[:-1]) / 2 * np.diff(z)))
        assert volume_geo(bellows, x) == pytest.approx(by_slices, rel=1e-7)


def test_a_bellows_without_e_v_is_geometric_and_one_with_it_adds_it():
    """V = V_geo + E_V (6); A = π/3 (R² + r² + R r) - ∂E_V/∂x (10), ∂A/∂P = 0 when E_V = 0."""
    s = PARAMS.spring
    plain = Bellows(s.r_big, s.r_small, s.wall, s.h0, float(s.n), s.x_min, s.x_max, e_v=[0] * 10)
    assert not plain.bulging and plain.e_v == (0.0,) * 10 and type(plain.n) is int
    bulging = bulged(PARAMS.spring, 1)
    assert bulging.bulging
    for x, p in ((-0.01, 9e4), (0.0, P_ATM), (0.02, 1.2e5)):
        assert volume(plain, x, p) == volume_geo(plain, x) == volume(plain, x, 2 * p)
        assert volume(bulging, x, p) == pytest.approx(
            volume_geo(bulging, x) + e_v(bulging, x, p)[0], rel=1e-14)
        f = frustum_state(plain, x)[2]
        value, _, d_p = area(plain, x, p)
        assert value == pytest.approx(math.pi / 3 * f, rel=1e-14) and d_p == 0.0
        assert area(bulging, x, p)[0] == pytest.approx(
            math.pi / 3 * f - e_v(bulging, x, p)[1], rel=1e-12)


def test_the_partial_derivatives_are_those_of_the_values():
    """E_V (5) and A (10): each returned partial against central differences."""
    bellows = bulged(PARAMS.spring, 2)
    hx, hp = 1e-7, 1.0
    for x, p in ((-0.008, 9.2e4), (0.004, P_ATM), (0.025, 1.18e5)):
        value, e_x, e_p, e_xx, e_xp = e_v(bellows, x, p)

        def ev(x_, p_, k=0):
            return e_v(bellows, x_, p_)[k]
        assert e_x == pytest.approx((ev(x + hx, p) - ev(x - hx, p)) / (2 * hx), rel=1e-6)
        assert e_p == pytest.approx((ev(x, p + hp) - ev(x, p - hp)) / (2 * hp), rel=1e-6)
        assert e_xx == pytest.approx((ev(x + hx, p, 1) - ev(x - hx, p, 1)) / (2 * hx), rel=1e-6)
        assert e_xp == pytest.approx((ev(x, p + hp, 1) - ev(x, p - hp, 1)) / (2 * hp), rel=1e-6)
        a, a_x, a_p = area(bellows, x, p)
        assert a_x == pytest.approx((area(bellows, x + hx, p)[0]
                                     - area(bellows, x - hx, p)[0]) / (2 * hx), rel=1e-6)
        assert a_p == pytest.approx((area(bellows, x, p + hp)[0]
                                     - area(bellows, x, p - hp)[0]) / (2 * hp), rel=1e-6)


def test_floats_and_arrays_give_the_same_numbers():
    bellows = bulged(PARAMS.chamber, 3)
    x = np.linspace(bellows.x_min, bellows.x_max, 7)
    p = np.linspace(9e4, 1.2e5, 7)
    functions = (lambda x_, p_: (volume_geo(bellows, x_),), lambda x_, p_: area(bellows, x_, p_),
                 lambda x_, p_: e_v(bellows, x_, p_), lambda x_, p_: (volume(bellows, x_, p_),))
    for function in functions:
        arrays = function(x, p)
        for k, (a, b) in enumerate(zip(x.tolist(), p.tolist())):
            assert [float(np.asarray(v)[k]) for v in arrays] == \
                pytest.approx(list(function(a, b)), rel=1e-13)
