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

"""Paper B model: geometry, gas law, force/stiffness, calibration against the paper's figures."""
import math

import numpy as np
import pytest

from bellows_ros.config.actuator import load_actuator_params
from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator import (buckling_force, estimate_gas, evaluate, evaluate_array,
                                         gas_amount, pressure, rest_compression,
                                         rest_length_change, stiffness, stiffness_from_rest,
                                         total_volume, without_buckling, without_bulging)
from bellows_ros.models.actuator_geometry import P_ATM

PARAMS = load_actuator_params()


def test_design_point_is_atmospheric():
    p = pressure(PARAMS, 0.020, 0.0)
    assert p == pytest.approx(P_ATM, rel=0.002)


@pytest.mark.parametrize('params', [PARAMS, without_bulging(PARAMS)],
                         ids=['augmented', 'geometric'])
def test_gas_law_holds_everywhere(params):
    rng = np.random.default_rng(0)
    x_c = rng.uniform(params.chamber.x_min, params.chamber.x_max, 200)
    x_s = rng.uniform(-0.01, 0.03, 200)
    gas = rng.uniform(90e3, 110e3, 200)
    p, _, _ = evaluate_array(params, x_c, x_s, gas)
    amount = gas_amount(params, gas)
    assert np.allclose(p * total_volume(params, x_c, x_s, p), amount, rtol=1e-10)
    # More compression of either bellows means higher pressure.
    assert np.all(evaluate_array(params, x_c + 1e-3, x_s, gas)[0] > p)
    assert np.all(evaluate_array(params, x_c, x_s + 1e-3, gas)[0] > p)


def test_calibrated_stiffness_reproduces_measured_figures():
    assert stiffness(PARAMS, -0.020) == pytest.approx(1483.0, rel=0.03)
    assert stiffness(PARAMS, 0.020) == pytest.approx(1975.0, rel=0.03)


def test_pressures_over_the_test_grid_stay_in_the_papers_band():
    x_c, x_s = np.meshgrid(np.arange(-0.020, 0.0201, 0.005), np.linspace(0.0, 0.020, 21))
    p, _, _ = evaluate_array(PARAMS, x_c, x_s)
    assert p.min() > 87e3 and p.max() < 115e3


@pytest.mark.parametrize('x_c,x_s', [(-0.02, 0.0), (0.0, 0.006), (0.02, 0.012), (0.045, 0.02),
                                     (0.048, 0.008)])
def test_stiffness_is_the_exact_derivative_of_force(x_c, x_s):
    _, _, k = evaluate(PARAMS, x_c, x_s)
    h = 1e-7
    numeric = (evaluate(PARAMS, x_c, x_s + h)[1] - evaluate(PARAMS, x_c, x_s - h)[1]) / (2 * h)
    assert k == pytest.approx(numeric, rel=1e-5)


def test_scalar_and_array_paths_agree():
    rng = np.random.default_rng(1)
    x_c = rng.uniform(-0.02, 0.048, 50)
    x_s = rng.uniform(0.0, 0.03, 50)
    arrays = np.array(evaluate_array(PARAMS, x_c, x_s, 98000.0))
    scalars = np.array([evaluate(PARAMS, a, b, 98000.0) for a, b in zip(x_c, x_s)]).T
    assert np.allclose(arrays, scalars, rtol=1e-12)


def test_estimate_gas_recovers_the_amount_from_a_pressure_reading():
    for gas in (92e3, 101325.0, 108e3):
        p, _, _ = evaluate(PARAMS, 0.031, 0.007, gas)
        assert estimate_gas(PARAMS, p, 0.031, 0.007) == pytest.approx(gas, rel=1e-9)


def test_stiffness_rises_to_a_buckling_peak_then_falls_and_grows_with_gas():
    x = np.linspace(PARAMS.chamber.x_min, PARAMS.chamber.x_max, 72)
    k = np.array([stiffness(PARAMS, v) for v in x])
    peak = int(np.argmax(k))
    assert 0 < peak < len(x) - 1
    assert np.all(np.diff(k[:peak + 1]) > 0) and np.all(np.diff(k[peak:]) < 0)
    # Without buckling, paper B's (7)-(12) alone rise all the way.
    plain = np.array([stiffness(without_buckling(PARAMS), v) for v in x])
    assert np.all(np.diff(plain) > 0)
    assert stiffness(PARAMS, 0.0, 105e3) > stiffness(PARAMS, 0.0, 97e3)


def test_model_reproduces_paper_b_figures_at_once():
    """Section IV-D and Fig. 10 from the default config, one parameter set."""
    assert stiffness(PARAMS, -0.020) == pytest.approx(1483.0, rel=0.03)
    assert stiffness(PARAMS, 0.020) == pytest.approx(1975.0, rel=0.03)
    # "the force curves are nonlinear, and the stiffness is higher at low displacements"
    for x_c in (-0.020, 0.020):
        x_s = np.linspace(0.0, 0.012, 121)
        _, _, k = evaluate_array(PARAMS, x_c, x_s)
        assert k[x_s <= 0.004].mean() > k[x_s >= 0.008].mean()
    # the extended range: curves extended to the spring's rest length, end stop to end stop
    assert stiffness_from_rest(PARAMS, PARAMS.chamber.x_min) == pytest.approx(1332.0, rel=0.05)
    assert stiffness_from_rest(PARAMS, 0.048) == pytest.approx(1913.0, rel=0.05)
    assert PARAMS.chamber.x_max == pytest.approx(0.048)
    # the rest point moves the paper's way: contracted at the elongated end, extended at 48 mm
    assert rest_compression(PARAMS, PARAMS.chamber.x_min) > 0.0 > rest_compression(PARAMS, 0.048)


def test_buckling_force_falls_below_the_unbuckled_force_with_pressure_and_compression():
    b = PARAMS.buckling
    loss = [[-buckling_force(b, x_s, p)[0] for x_s in (0.0, 0.006, 0.012, 0.018)]
            for p in (95e3, 105e3, 115e3, 125e3)]
    loss = np.array(loss)
    assert np.all(loss >= 0.0)
    assert np.all(np.diff(loss, axis=0) > 0) and np.all(np.diff(loss, axis=1) > 0)
    assert loss[0, 0] < 1e-3 * loss[-1, -1]          # nothing below the onset
    # smooth onset: the partials are continuous and match central differences
    for x_s, p in ((0.004, 110e3), (0.012, 120e3), (0.02, 100e3)):
        f, f_x, f_p = buckling_force(b, x_s, p)
        h, hp = 1e-7, 1e-2
        assert f_x == pytest.approx((buckling_force(b, x_s + h, p)[0]
                                     - buckling_force(b, x_s - h, p)[0]) / (2 * h), rel=1e-5)
        assert f_p == pytest.approx((buckling_force(b, x_s, p + hp)[0]
                                     - buckling_force(b, x_s, p - hp)[0]) / (2 * hp), rel=1e-5)
    # the array path is the same function
    x_s = np.array([0.0, 0.01, 0.02])
    assert np.allclose(buckling_force(b, x_s, 120e3, np.exp)[0],
                       [buckling_force(b, v, 120e3)[0] for v in x_s])


def test_buckling_parameters_outside_their_physical_range_are_named(tmp_path):
    path = tmp_path / 'p.yaml'
    path.write_text('/**:\n  ros__parameters:\n    actuator:\n      buckling:\n'
                    '        critical_pressure: 1.0\n')
    with pytest.raises(ParameterError, match='critical_pressure'):
        load_actuator_params(path)


def test_rest_length_contracts_below_and_extends_above_atmospheric():
    assert rest_length_change(PARAMS, 90e3) < 0.0 < rest_length_change(PARAMS, 112e3)
    assert rest_length_change(PARAMS, 95e3) < 0.0 < rest_length_change(PARAMS, 105e3)
    assert rest_length_change(PARAMS, 90e3) < rest_length_change(PARAMS, 100e3)


def test_unknown_parameter_in_user_file_is_named(tmp_path):
    path = tmp_path / 'p.yaml'
    path.write_text('/**:\n  ros__parameters:\n    actuator:\n      gas:\n        v_tub: 1.0e-5\n')
    with pytest.raises(ParameterError, match='v_tub'):
        load_actuator_params(path)


def test_overrides_are_laid_over_the_defaults(tmp_path):
    path = tmp_path / 'p.yaml'
    path.write_text('/**:\n  ros__parameters:\n    actuator:\n      gas:\n        v_tube: '
                    '3.0e-5\n')
    params = load_actuator_params(path)
    assert params.v_tube == 3.0e-5
    assert params.chamber == PARAMS.chamber
    # A larger dead volume softens the gas spring.
    assert stiffness(params, 0.02) < stiffness(PARAMS, 0.02)
    assert not math.isclose(stiffness(params, 0.02), stiffness(PARAMS, 0.02))


def test_spring_force_is_equations_9_to_12_computed_by_hand():
    """F from `evaluate` against (3), (9)-(12) written out here, E_V's slope by differences."""
    params = without_buckling(PARAMS)
    s = params.spring
    c1, c2, c3, c4 = params.e_f
    for x_c, x_s in ((-0.02, 0.0), (0.0, 0.006), (0.02, 0.012), (0.045, 0.025), (0.01, -0.008)):
        p, force, _ = evaluate(params, x_c, x_s)
        dh = x_s / s.n
        big = math.sqrt((s.r_big - s.r_small) ** 2 - (dh ** 2 - 2 * s.h0 * dh) / 4) + s.r_small
        h = 1e-7

        def bulge(x):
            geometric = without_bulging(params)
            return total_volume(params, x_c, x, p) - total_volume(geometric, x_c, x, p)
        # (10): dV/d(nh) = pi/3 (R^2 + r^2 + R r) + dE_V/d(nh), with d(nh) = -dx
        area = (math.pi / 3 * (big ** 2 + s.r_small ** 2 + big * s.r_small)
                - (bulge(x_s + h) - bulge(x_s - h)) / (2 * h))
        f_mts = np.polyval(list(params.f_mts[::-1]) + [0.0], x_s)
        e_f = c1 * math.exp(c2 * p + c3 * dh + c4)                          # (11)
        assert force == pytest.approx((p - P_ATM) * area + f_mts + e_f, rel=1e-7, abs=1e-7)


def test_regression_forms_equal_the_model_functions():
    """The fits' monomials of F_MTS, and their E_F shape times C1 e^(C4 + C2 P_atm), give F's."""
    from bellows_ros.models.actuator import force_error, material_force, material_terms
    x_s = np.linspace(-0.01, 0.03, 9)
    p = np.linspace(85e3, 125e3, 9)
    terms = np.column_stack(material_terms(x_s, len(PARAMS.f_mts)))
    assert np.allclose(terms @ np.array(PARAMS.f_mts), material_force(PARAMS.f_mts, x_s)[0],
                       rtol=1e-12, atol=1e-12)
    c1, c2, c3, c4 = PARAMS.e_f
    n = PARAMS.spring.n
    shape = force_error((1.0, c2, c3, -c2 * P_ATM), n, x_s, p, np.exp)[0]
    assert np.allclose(c1 * math.exp(c4 + c2 * P_ATM) * shape,
                       force_error(PARAMS.e_f, n, x_s, p, np.exp)[0], rtol=1e-12)
