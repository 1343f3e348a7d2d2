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
The doctor's fitting and held-out scoring (doctor/scoring.py) on arrays with known answers.

Models here are tiny closed forms (a decay with a fitted time constant, a constant mean), so that
what `fit` and `score` must return can be written down; the metrics (gain, the BIC-like criterion,
the decision rule, the failure verdict, the noise floors) are checked on residuals whose RMSEs are
exact. The block masks and the Ljung-Box test are held by test_models_filters.py.
"""
import math

import numpy as np
import pytest

from bellows_ros.doctor import scoring
from bellows_ros.doctor.scoring import noise_floor, noise_floor_local

DT = 1e-3
T = np.linspace(0.0, 10.0, 2000)


def decay_model(y):
    """Model y ≈ a exp(-t / tau) + b: tau fitted (0.1-10 s), a and b solved on the train rows."""
    def predict(theta, train):
        x = np.column_stack([np.exp(-T / theta[0]), np.ones_like(T)])
        coef = np.linalg.lstsq(x[train], y[train], rcond=None)[0]
        return x @ coef, {'a': coef[0], 'b': coef[1]}

    def physical(theta, linear):
        return {'decay': {'tau': float(theta[0]), **linear}}

    return scoring.Model(('decay',), ['decay.tau'], [1.0], [0.1], [10.0], predict, physical,
                         n_linear=2, starts=[[5.0]])


def mean_model(y):
    """No nonlinear parameter: the prediction is the mean of the training rows."""
    def predict(theta, train):
        return np.full(len(y), np.mean(y[train])), {'mean': float(np.mean(y[train]))}

    return scoring.Model((), [], [], [], [], predict, lambda theta, linear: {'baseline': linear},
                         n_linear=1)


def known(heldout, n_params=1, cost=0.0):
    """Return a `Score` with the given held-out residual, parameter count and in-sample cost."""
    model = scoring.Model((), [f'p{k}' for k in range(n_params)], [], [], [], None, None)
    return scoring.Score(model, scoring.Fit(np.zeros(n_params), {}, None, cost),
                         np.asarray(heldout, float))


def alternating(size, n=1000):
    """±size, alternating: RMSE exactly `size`."""
    return size * (-1.0) ** np.arange(n)


def test_fit_recovers_a_time_constant_and_solves_the_linear_part_on_the_train_rows():
    rng = np.random.default_rng(4)
    y = 3.0 * np.exp(-T / 2.0) + 0.5 + rng.normal(0.0, 0.01, T.size)
    train = T < 7.0
    y[~train] += 100.0      # rows outside `train` must not enter the fit
    result = scoring.fit(decay_model(y), y, train)
    assert result.theta[0] == pytest.approx(2.0, rel=0.02)
    assert result.linear['a'] == pytest.approx(3.0, rel=0.02)
    assert result.linear['b'] == pytest.approx(0.5, abs=0.01)
    # the cost is the mean squared residual over the training rows only
    assert result.cost == pytest.approx(np.mean((result.prediction - y)[train] ** 2))
    assert result.cost < 2e-4


def test_a_model_without_nonlinear_parameters_is_solved_once():
    y = np.arange(10.0)
    train = np.arange(10) < 4
    result = scoring.fit(mean_model(y), y, train)
    assert result.theta.size == 0 and result.linear == {'mean': 1.5}
    assert result.cost == pytest.approx(np.mean((1.5 - y[:4]) ** 2))


def test_every_sample_is_scored_by_a_refit_that_did_not_see_it():
    rng = np.random.default_rng(1)
    y = rng.normal(0.0, 1.0, 1000) + np.linspace(0.0, 5.0, 1000)
    result = scoring.score(mean_model(y), y)
    expected = np.empty_like(y)
    for train, test in scoring.block_masks(len(y)):
        expected[test] = np.mean(y[train]) - y[test]
    np.testing.assert_allclose(result.heldout, expected, rtol=0, atol=1e-12)
    assert result.full.linear['mean'] == pytest.approx(np.mean(y))   # the fit on all data
    assert result.rmse > result.insample_rmse   # held out, the trend is not fitted


def test_the_rmses_of_a_score_over_outputs_and_in_sample():
    score = known([[3.0, -3.0, 3.0, -3.0], [1.0, -1.0, 1.0, -1.0]], cost=4.0)
    assert score.output_rmse(0) == pytest.approx(3.0)
    assert score.output_rmse(1) == pytest.approx(1.0)
    assert score.rmse == pytest.approx(math.sqrt(5.0))      # over both outputs' samples
    assert score.insample_rmse == pytest.approx(2.0)


def test_a_cause_pays_on_gain_and_its_added_parameters():
    current = known(alternating(1.0), n_params=3)
    better = known(alternating(0.85), n_params=4)
    slightly = known(alternating(0.95), n_params=4)
    assert scoring.gain(better.rmse, current.rmse) == pytest.approx(0.15)
    # n ln(MSE ratio) + k ln(n) on the held-out samples
    assert scoring.bic_delta(better, current) == pytest.approx(
        1000 * math.log(0.85 ** 2) + math.log(1000))
    assert scoring.pays(better, current)
    assert not scoring.pays(slightly, current)      # 5 % < MIN_GAIN
    # The same gain on 20 samples does not pay for 3 added parameters: the BIC rises.
    few = known(alternating(1.0, 20), n_params=1)
    costly = known(alternating(0.85, 20), n_params=4)
    assert scoring.gain(costly.rmse, few.rmse) >= scoring.MIN_GAIN
    assert scoring.bic_delta(costly, few) > 0 and not scoring.pays(costly, few)
    assert scoring.gain(1.0, 0.0) == 0.0


def test_a_heldout_score_far_above_noise_and_its_own_fit_is_a_failure():
    broken = known(alternating(500.0), cost=1.0)           # in-sample RMSE 1
    message = scoring.heldout_failure(broken, 1.0)
    assert message.startswith('numerical failure of the held-out refits')
    assert '500 ×' in message and 'reaches 1' in message
    assert 'far above' in scoring.heldout_failure(broken, 0.0)
    # as wrong in-sample as held out: a model missing physics, not a broken refit
    assert scoring.heldout_failure(known(alternating(500.0), cost=100.0 ** 2), 1.0) is None
    assert scoring.heldout_failure(known(alternating(50.0), cost=1.0), 1.0) is None
    assert scoring.heldout_failure(known([np.nan, 1.0], cost=1.0), 1.0) is not None


def test_edges_are_the_causes_own_variables_at_a_bound():
    model = scoring.Model(('lag',), ['lag.tau', 'lag.gain', 'lag.mid', 'other.x'], [],
                          [0, 0, 0, 0], [1.0, 10.0, 1.0, 1.0], None, None)
    theta = np.array([0.004, 9.99, 0.5, 0.0])         # within 0.5 % of the range of a bound
    score = scoring.Score(model, scoring.Fit(theta, {}, None, 0.0), np.zeros(1))
    assert scoring.edges(score, 'lag') == [('tau', 'lower'), ('gain', 'upper')]
    assert scoring.at_edge(score, 'lag') == ['tau', 'gain']
    assert scoring.edges(score, 'other') == [('x', 'lower')]
    assert scoring.edges(score, 'lag', margin=0.001) == []


def test_autocorrelation_of_known_sequences():
    n = 1000
    flip = (-1.0) ** np.arange(n)
    r = scoring.autocorrelation(flip, 3)
    np.testing.assert_allclose(r, [1.0, -(n - 1) / n, (n - 2) / n, -(n - 3) / n], atol=1e-12)
    np.testing.assert_array_equal(scoring.autocorrelation(np.full(50, 2.0), 4), np.zeros(5))


def test_second_differences_see_the_noise_under_fast_ramps():
    rng = np.random.default_rng(3)
    sigma = 0.05
    # a triangle ramped by ±1 per sample: first differences jump by 2, twenty times sigma
    triangle = np.abs((np.arange(20000) % 400) - 200.0)
    noisy = triangle + rng.normal(0.0, sigma, triangle.size)
    assert scoring.noise_floor_ramps(noisy) == pytest.approx(sigma, rel=0.05)
    assert noise_floor(noisy) > 3 * sigma          # what the second differences avoid
    assert noise_floor(np.linspace(0, 50, 20000) + rng.normal(0.0, sigma, 20000)) == \
        pytest.approx(sigma, rel=0.05)


def test_a_noise_free_column_gets_a_floor_above_zero():
    ramp = np.linspace(0.0, 2.0, 100)
    assert scoring.guarded_floor(noise_floor(ramp), ramp) == pytest.approx(2e-6)
    assert scoring.guarded_floor(0.0, np.zeros(10)) == 1e-12
    assert scoring.guarded_floor(0.3, ramp) == 0.3


def test_the_local_floor_sizes_a_noise_that_flips_sign_where_differences_do_not():
    rng = np.random.default_rng(2)
    white = rng.standard_normal(50000)
    flipping = 0.4 * np.tanh(10.0 * np.diff(0.001 * rng.standard_normal(50001)) / DT)
    slow = np.sin(np.arange(50000) * DT * 2 * math.pi / 12.0)     # a motion, 12 s period
    assert noise_floor_local(white + slow) == pytest.approx(1.0, rel=0.03)
    assert noise_floor_local(flipping + slow) == pytest.approx(np.std(flipping), rel=0.1)
    assert noise_floor(flipping) > 1.5 * np.std(flipping)        # what the local floor avoids
