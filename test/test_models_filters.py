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
The vectorised operators of the candidate causes agree with their step-by-step definitions.

And the held-out blocks and decision rule behave as documented.
"""
from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np

from bellows_ros.doctor import scoring
from bellows_ros.models.filters import lag, play, recurrence, relax, reversals


def loop_play(x, width):
    y, out = x[0], []
    for value in x:
        y = min(max(y, value - width / 2), value + width / 2)
        out.append(y)
    return np.array(out)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000), st.floats(0.0, 3.0))
def test_play_scan_equals_the_loop(seed, width):
    x = np.cumsum(np.random.default_rng(seed).normal(size=700))
    np.testing.assert_allclose(play(x, width), loop_play(x, width), atol=1e-12)


def test_recurrence_equals_the_loop_even_when_strongly_decaying():
    rng = np.random.default_rng(1)
    a = 1.0 - rng.uniform(0.0, 0.05, 5000)      # exp(-sum) underflows without chunking
    b = rng.normal(size=5000)
    x = np.empty(5000)
    x[0] = 2.0
    for k in range(4999):
        x[k + 1] = a[k] * x[k] + b[k]
    np.testing.assert_allclose(recurrence(a, b, 2.0), x, rtol=1e-9, atol=1e-9)


def test_lag_and_relax_step_responses():
    dt, tau = 1e-3, 0.05
    t = np.arange(0, 0.5, dt)
    step = np.where(t >= 0.1, 1.0, 0.0)
    y = lag(step, dt, tau)
    k = int(round((0.1 + tau) / dt))          # one time constant after the step
    assert abs(y[k] - (1 - np.exp(-1))) < 0.02
    z = relax(step, dt, tau)
    assert abs(z[int(round(0.1 / dt))] - 1.0) < 1e-12 and abs(z[k] - np.exp(-1)) < 0.02


def test_blocks_hold_out_every_sample_once_and_guard_training():
    masks = scoring.block_masks(1000)
    tested = np.sum([test for _, test in masks], axis=0)
    assert np.all(tested == 1)
    for train, test in masks:
        assert not np.any(train & test)
        edges = np.flatnonzero(np.diff(test.astype(int)))
        for edge in edges:   # no training sample right next to a held-out block
            assert not train[max(edge - 2, 0):edge + 3].any()


def test_reversal_count_ignores_noise():
    t = np.linspace(0, 4 * np.pi, 4000)
    x = np.sin(t) + np.random.default_rng(0).normal(0, 0.01, t.size)
    assert reversals(x, 0.1) == 4
    assert reversals(np.linspace(0, 1, 100), 0.1) == 0


def test_ljung_box_separates_white_from_correlated():
    rng = np.random.default_rng(2)
    white = rng.normal(size=5000)
    q, p = scoring.ljung_box(white, 20)
    assert p > 0.001
    correlated = lag(white, 1.0, 5.0)
    assert scoring.ljung_box(correlated, 20)[1] < 1e-6
    assert abs(scoring.noise_floor(np.cumsum(np.ones(5000)) * 1e-3 + white) - 1.0) < 0.1
