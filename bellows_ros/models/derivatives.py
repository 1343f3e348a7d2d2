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
Rates of sampled signals: Ψ̇ from Ψ and Ψ̈ from Ψ̇, the one estimator of the project [ours].

Paper A measures no joint rate, so Ψ̇ and Ψ̈ are estimated from the samples. The driver (Ψ̇ of the
encoder-less arm), the model node (Ψ̈ of (2)) and identification (Ψ̇, Ψ̈ of a record without those
columns) all use the first-order backward difference of this module:

    ẋ_k = (x_k − x_{k−1}) / (t_k − t_{k−1})

It is causal, so a node can compute it sample by sample (`rate`) and an offline tool over a whole
record (`rates`); the two give the same floats on the same data. Where the time does not advance
(a repeated or out-of-order stamp) the previous estimate is held; before the second sample the
estimate is `initial` (0: at rest).

Delay and noise, for a uniform step h:
- Delay: the difference is the slope of the chord, i.e. the rate at t_k − h/2 to O(h²): the
  estimate lags the true rate by h/2 (0.5 ms at 1 kHz).
- Noise gain: white noise of standard deviation σ on x gives σ·√2/h on ẋ (the coefficients
  are +1, −1). Applied twice (Ψ̈ from an estimated Ψ̇) the delay is h and the gain σ·√6/h²
  (coefficients +1, −2, +1).
No smoothing is applied: the sensors' own filters and, for identification, the zero-phase input
filter (`bellows_ros.identify.segment.filter_inputs`) set the bandwidth.
"""
import numpy as np


def rate(x, x_previous, dt, held=0.0):
    """
    Backward difference (x − x_previous)/dt, units of x per s; `held` if dt ≤ 0 or no previous.

    The streaming form: call once per sample with the previous sample (None before the second) and
    the last estimate as `held`.
    """
    if x_previous is None or not dt > 0.0:
        return held
    return (x - x_previous) / dt


def rates(t, x, initial=0.0):
    """
    Backward differences of `x` over the times `t` (s), one per sample, as an array.

    The batch form of `rate`: element k is rate(x[k], x[k−1], t[k] − t[k−1], element k−1), and
    element 0 is `initial`.
    """
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    out = np.full(x.shape, float(initial))
    if len(x) < 2:
        return out
    dt = np.diff(t)
    advancing = dt > 0.0
    step = np.divide(np.diff(x), dt, out=np.zeros_like(dt), where=advancing)
    # Hold the last estimate where time does not advance: index of the latest advancing row.
    latest = np.maximum.accumulate(np.where(advancing, np.arange(1, len(x)), 0))
    out[1:] = np.where(latest > 0, step[np.maximum(latest, 1) - 1], initial)
    return out
