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

"""Identification of the actuator model from synthetic records of the plant."""
import dataclasses

import numpy as np
import pytest

from bellows_ros.config.actuator import load_actuator_params, load_actuator_plant_params
from bellows_ros.identify.actuator import calibrate_stiffness, fit_actuator, GasLost
from bellows_ros.models.actuator import stiffness, without_bulging
from bellows_ros.models.actuator_geometry import e_v, P_ATM
from bellows_ros.papers.actuator_experiments import volume_test_series

PLANT = load_actuator_plant_params()

TRUTH = load_actuator_params()


def bulge_volume(params, x_c, x_s, p):
    """V_tube + E_V,c + E_V,s: what the augmented model adds to the geometric volumes, m³."""
    return params.v_tube + e_v(params.chamber, x_c, p)[0] + e_v(params.spring, x_s, p)[0]


@pytest.fixture(scope='module')
def series():
    return volume_test_series(TRUTH, PLANT, seed=21, duration=8.0)


@pytest.fixture(scope='module')
def start():
    """
    Return starting parameters: wrong tube, force curve and fitted E_V terms.

    The kept E_V terms are the YAML's.
    """
    def fitted_terms_zeroed(bellows):
        kept = {0, 1, 2, 5, 9}
        return dataclasses.replace(bellows, e_v=tuple(a if k in kept else 0.0
                                                      for k, a in enumerate(bellows.e_v)))
    return dataclasses.replace(TRUTH, v_tube=5e-6, f_mts=(900.0, -2000.0, 0.0),
                               e_f=(0.5, 1e-5, 300.0, -1.01325),
                               chamber=fitted_terms_zeroed(TRUTH.chamber),
                               spring=fitted_terms_zeroed(TRUTH.spring))


@pytest.mark.slow
def test_identification_recovers_e_v_within_0_4_ml(series, start):
    fit = fit_actuator(start, series['x_c'], series['x_s'], series['p'], series['f'],
                       run=series['run'])
    x_c, x_s, p = series['x_c'], series['x_s'], series['p']
    error_ml = (bulge_volume(fit.params, x_c, x_s, p) - bulge_volume(TRUTH, x_c, x_s, p)) * 1e6
    assert np.max(np.abs(error_ml)) < 0.4
    # The start really was wrong by more than that.
    start_error = (bulge_volume(start, x_c, x_s, p) - bulge_volume(TRUTH, x_c, x_s, p)) * 1e6
    assert np.max(np.abs(start_error)) > 5.0
    assert fit.params.v_tube == pytest.approx(TRUTH.v_tube, abs=1e-6)
    # Errors reported the paper's way, at the level of the sensor noise.
    assert fit.volume_error_ml[0] < 0.05 and fit.force_error_n[0] < 0.1
    # The first run sealed 92 % of the nominal gas.
    assert fit.params.p_ref == pytest.approx(0.92 * TRUTH.p_ref, rel=2e-3)
    # The identified model predicts the stiffness figures of the truth.
    nominal = dataclasses.replace(fit.params, p_ref=TRUTH.p_ref)
    for x_c_point in (-0.02, 0.02):
        assert stiffness(nominal,
                         x_c_point) == pytest.approx(stiffness(TRUTH, x_c_point), rel=0.01)


@pytest.mark.slow
def test_geometric_baseline_fits_worse_on_bulging_data(series, start):
    full = fit_actuator(start, series['x_c'], series['x_s'], series['p'], series['f'],
                        run=series['run'])
    base = fit_actuator(without_bulging(start), series['x_c'], series['x_s'], series['p'],
                        series['f'],
                        run=series['run'], wall_bulging=False, force_error=False)
    assert base.volume_error_ml[0] > 1.5 * full.volume_error_ml[0]
    assert base.force_error_n[0] > 2.0 * full.force_error_n[0]


def test_calibration_hits_the_papers_stiffness():
    detuned = dataclasses.replace(TRUTH, f_mts=tuple(0.7 * a for a in TRUTH.f_mts),
                                  e_f=(3.0,) + TRUTH.e_f[1:])
    assert abs(stiffness(detuned, -0.02) - 1483.0) > 100.0
    calibrated = calibrate_stiffness(detuned)
    assert stiffness(calibrated, -0.02) == pytest.approx(1483.0, rel=1e-6)
    assert stiffness(calibrated, 0.02) == pytest.approx(1975.0, rel=1e-6)


def test_the_gas_a_leak_took_is_the_same_read_whole_or_in_chunks():
    """`GasLost`: ∫ P (P - P_atm) dt from each fill's first row, carried across chunks."""
    t = np.arange(0.0, 10.0, 1e-3)
    p = 1.2e5 + 3e4 * np.sin(t)
    run = (t > 6.0).astype(int)
    whole = GasLost().add(t, p, run)
    lost = GasLost()
    chunks = np.concatenate([lost.add(t[k:k + 777], p[k:k + 777], run[k:k + 777])
                             for k in range(0, len(t), 777)])
    assert np.allclose(chunks, whole, rtol=1e-12, atol=1e-6)
    second = int(np.argmax(run))
    assert whole[0] == 0.0 and whole[second] == 0.0   # a new fill has lost nothing yet
    g = p * (p - P_ATM)
    assert whole[4000] == pytest.approx(np.trapezoid(g[:4001], t[:4001]), rel=1e-9)
    assert whole[-1] == pytest.approx(np.trapezoid(g[second:], t[second:]), rel=1e-9)
