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
Identification (30-33) recovers a known segment from noisy quasi-static + dynamic bench records.

Truth: config/segment.yaml, full paper-A physics. Records at 1 kHz with the issue's noise: pressure
1 kPa, angle 1e-3 rad, torque 0.05 N·m (std; Ψ̇ 5e-3 rad/s). The search starts from a wrong
material. Judged against the raw measured τ_ext on records the fit never saw: the issue's ≤ 1.2
σ_τ, for the fitted model and (as a check of the pipeline) the true parameters; and the Fig. 10
hysteresis from the fitted parameters.
"""
import numpy as np
import pytest

from bellows_ros.config.segment import (load_segment_identify_params, load_segment_params,
                                        load_segment_plant_params)
from bellows_ros.identify.segment import (fig10_torques, fit_segment, least_squares, predict,
                                          prediction_errors)
from bellows_ros.models.ogden import free_strain
from bellows_ros.models.segment_plant import FULL_MODEL, NO_NOISE
from bellows_ros.papers.segment_experiments import (dynamic_record, fig10_record,
                                                    quasi_static_record)

PLANT = load_segment_plant_params()
CUTOFF = load_segment_identify_params().input_cutoff  # Hz, segment.identify.input_cutoff

NOISE = {'p': 1000.0, 'psi': 1e-3, 'psi_dot': 5e-3, 'tau': 0.05}
DT = 1e-3  # 1 kHz, like the segment's sensors
DURATION = (90.0, 30.0)  # s of quasi-static and dynamic record
FIG10 = (6.7, 9.1)  # paper A's measured |τ_ext| before / after the excursion, N·m


def bench_records(truth, noise, seeds):
    """
    Join a dynamic and a quasi-static record with a 1 s time gap.

    Separate runs: the input filter treats them apart. Dynamic first, so that the fit's training
    part (first 70 %) has both kinds of motion and its held-out part is the end of the
    quasi-static run.
    """
    dynamic = dynamic_record(truth, PLANT, FULL_MODEL, noise, seed=seeds[1],
                             duration=DURATION[1], dt=DT)
    quasi = quasi_static_record(truth, PLANT, FULL_MODEL, noise, seed=seeds[0],
                                duration=DURATION[0], dt=DT)
    offset = {'t': dynamic['t'][-1] + 1.0}
    return {k: np.concatenate([dynamic[k], quasi[k] + offset.get(k, 0.0)]) for k in quasi}


@pytest.fixture(scope='module')
def fitted():
    truth = load_segment_params()
    start = truth.replace(ogden_mu=(9000.0, 150.0), ogden_gamma=(3.5, 4.0), restoring_c_psi0=1.0,
                          restoring_c_psi0_p=0.2, actuator_theta=(0.0,) * 8)
    fit = fit_segment(start, bench_records(truth, NOISE, (11, 12)), CUTOFF, seed=1, starts=2,
                      max_evaluations=150, progress=False)
    return truth, fit


@pytest.mark.slow
def test_fitted_model_is_within_the_noise_on_unseen_records(fitted):
    truth, fit = fitted
    sigma = NOISE['tau']
    assert fit.input_cutoff == CUTOFF and fit.rate == pytest.approx(1 / DT)
    # the criterion: unseen noisy 1 kHz records (quasi-static + dynamic), the fitted
    # model's prediction pipeline (input filter + model) against the raw measured torque
    noisy = bench_records(truth, NOISE, (31, 32))
    # measured: fitted 0.0572 N·m, true parameters 0.0530 N·m
    assert prediction_errors(truth, noisy, CUTOFF)['model'][0] <= 1.2 * sigma
    assert prediction_errors(fit.params, noisy, CUTOFF)['model'][0] <= 1.2 * sigma
    # the last 30 % of the fitted record (rows the fit did not see; measured 0.0599, the true
    # parameters 0.0535 on the same rows)
    assert fit.heldout['model'][0] <= 1.5 * sigma
    # the input filter is what makes this possible: unfiltered, even the true parameters miss it
    assert prediction_errors(truth, noisy, 0.0)['model'][0] > 1.4 * sigma
    # the filter costs little on noise-free records (its own bias, well under the noise)
    clean = bench_records(truth, NO_NOISE, (21, 22))
    assert prediction_errors(truth, clean, 0.0)['model'][0] < 1e-9  # exact yardstick
    assert prediction_errors(truth, clean, CUTOFF)['model'][0] < 0.4 * sigma
    assert prediction_errors(fit.params, clean, CUTOFF)['model'][0] < 0.8 * sigma
    # the paper's comparison: the refitted previous model is far worse on the held-out rows
    assert fit.heldout['previous'][0] > 5 * fit.heldout['model'][0]


@pytest.mark.slow
def test_fit_reproduces_the_fig10_hysteresis(fitted):
    truth, fit = fitted
    fit_before, fit_after, prev_before, prev_after = fig10_torques(fit.params, PLANT)
    assert fit_after >= 1.1 * fit_before
    assert fit_before == pytest.approx(FIG10[0],
                                       rel=0.1) and fit_after == pytest.approx(FIG10[1], rel=0.1)
    assert prev_before == prev_after  # the previous model has no memory
    # the prediction pipeline (filtered noisy inputs) does not smear it: a noisy Fig. 10 record
    record, before, after = fig10_record(truth, PLANT, FULL_MODEL, NOISE, seed=5)
    model = predict(fit.params, record, CUTOFF)[0]
    assert model[after] >= 1.1 * model[before]
    assert model[before] == pytest.approx(FIG10[0], rel=0.1)
    assert model[after] == pytest.approx(FIG10[1], rel=0.1)
    # the material is identified where the data can see it: the stretch-load curve of (22) over the
    # loads p_rel·R met in the records (the four Ogden constants themselves trade off, and the two
    # terms may swap)
    assert min(fit.params.ogden_gamma) > 2.0
    for load in (2e3, 5e3, 1e4, 2e4, 3e4):
        assert free_strain(load, *fit.params.ogden_mu, *fit.params.ogden_gamma) == pytest.approx(
            free_strain(load, *truth.ogden_mu, *truth.ogden_gamma), rel=0.02)


def test_least_squares_plain_and_with_the_doctors_ridge():
    """
    (32), the one linear solve: ridge 0 is least squares, ridge > 0 the scaled ridge minimiser.

    Ridge 0 is the least-squares θ (checked against the normal equations); ridge > 0 is the
    minimiser of |Xθ - Y|² + ridge |diag(scale) θ|² (checked against the augmented system
    [X; √ridge diag(scale)] solved by SVD). An unexcited column gets 0.
    """
    rng = np.random.default_rng(41)
    x = rng.standard_normal((400, 5)) * np.array([1.0, 10.0, 100.0, 1e-2, 3.0])
    y = x @ rng.standard_normal(5) + 0.01 * rng.standard_normal(400)
    plain = least_squares(x, y)
    np.testing.assert_allclose(plain, np.linalg.solve(x.T @ x, x.T @ y), rtol=1e-9)
    scale = np.sqrt(np.mean(x * x, axis=0))
    for ridge in (1e-6, 1e-2, 10.0):
        augmented = np.vstack([x, np.sqrt(ridge) * np.diag(scale)])
        expected = np.linalg.lstsq(augmented, np.concatenate([y, np.zeros(5)]), rcond=None)[0]
        np.testing.assert_allclose(least_squares(x, y, ridge, scale), expected, rtol=1e-8)
    shrunk = least_squares(x, y, 10.0, scale)
    assert np.linalg.norm(shrunk * scale) < np.linalg.norm(plain * scale)
    np.testing.assert_allclose(least_squares(x, y, 1e-12, scale), plain, rtol=1e-6)
    dead = np.column_stack([x, np.zeros(400)])
    assert least_squares(dead, y)[-1] == 0.0
    assert least_squares(dead, y, 1e-6, np.ones(6))[-1] == 0.0
