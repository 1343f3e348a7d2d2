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
Fitting candidate models and scoring them on held-out blocks of time.

A *model* here is the baseline with zero or more candidate causes switched on. It is described by
its nonlinear physical parameters (time constants, conductances, widths ...) with bounds, and a
`predict(theta, train)` function that returns the predicted measured signal over the whole record
(dynamic effects need the whole history) after solving any linear coefficients by least squares on
the `train` rows only. The doctor never sees more than this interface.

A system with several measured outputs (the actuator: pressure and force) passes `y` as a 2-D
array, one row per output, each divided by its own noise floor; predictions have the same shape,
masks select columns (samples in time), and every RMSE is then in units of the noise floors.

Held-out scoring (docs/doctor.md): the record is cut into `BLOCKS` contiguous blocks of time, dealt
into `FOLDS` folds. For each fold the model is refitted on the other folds' blocks and its residual
is taken on the blocks it did not see; every sample is held out exactly once, and the held-out RMSE
is over all of them.

Decision rule: an extension *pays* when its held-out gain over the current model is at least
`MIN_GAIN` and its held-out log-likelihood gain beats a BIC penalty for the parameters it adds.
"""
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.optimize import least_squares

# A cause must cut the held-out RMSE of the current model by at least this fraction
# (docs/doctor.md).
MIN_GAIN = 0.10
# Contiguous blocks of time, and folds they are dealt into (each fold holds out BLOCKS / FOLDS).
BLOCKS = 20
FOLDS = 5
# Samples left out of training on each side of a held-out block (fraction of a block).
GUARD = 0.1
# A fit whose held-out RMSE is above FAILURE_NOISE × the (averaged) noise floor and above
# FAILURE_INSAMPLE × its own in-sample RMSE has failed numerically or extrapolated: a model that
# misses physics is about as wrong on the rows it was fitted to (the segment baselines of the test
# records: held-out / in-sample 1.0-1.9), so such a score names no cause (docs/doctor.md).
FAILURE_NOISE = 100.0
FAILURE_INSAMPLE = 10.0
# Function evaluations of a held-out refit (warm-started from the fit on all data).
FOLD_NFEV = 25
# Function evaluations of each start of a multi-start fit before the best is refined.
SCOUT_NFEV = 8


@dataclass
class Model:
    """
    The baseline plus the causes in `causes`, ready to fit.

    names, x0, lower, upper: nonlinear parameters (scaled so that O(1) steps are meaningful).
    predict(theta, train) -> (prediction over the whole record, dict of linear coefficients).
    physical(theta, linear) -> dict of physical parameters for the report (SI units).
    n_linear: number of linear coefficients solved inside `predict` (counts in the penalty).
    """

    causes: tuple
    names: list
    x0: list
    lower: list
    upper: list
    predict: Callable
    physical: Callable
    n_linear: int = 0
    starts: list = field(default_factory=list)

    @property
    def n_params(self):
        return len(self.names) + self.n_linear


@dataclass
class Fit:
    theta: np.ndarray
    linear: dict
    prediction: np.ndarray
    cost: float


def fit(model, y, train, x0=None, max_nfev=60):
    """
    Least-squares fit of `model` to `y` on the boolean mask `train`.

    Starts are `x0` (a warm start) if given, else `model.x0` and `model.starts`; with several, each
    gets `SCOUT_NFEV` evaluations and the best is refined with `max_nfev`. Returns a `Fit`.
    """
    def residual(theta):
        prediction, _ = model.predict(theta, train)
        return (prediction - y)[..., train].ravel()

    if not model.names:
        prediction, linear = model.predict(np.empty(0), train)
        return Fit(np.empty(0), linear, prediction, _cost(prediction, y, train))
    starts = [x0] if x0 is not None else [model.x0] + list(model.starts)

    def solve(start, budget):
        start = np.clip(np.asarray(start, float), model.lower, model.upper)
        return least_squares(residual, start, bounds=(model.lower, model.upper),
                             x_scale='jac', max_nfev=budget, diff_step=1e-3)

    if len(starts) > 1:
        # Several starts: a short run from each, then only the best is run to convergence.
        scouts = [solve(start, SCOUT_NFEV) for start in starts]
        best = solve(min(scouts, key=lambda s: s.cost).x, max_nfev)
    else:
        best = solve(starts[0], max_nfev)
    prediction, linear = model.predict(best.x, train)
    return Fit(best.x, linear, prediction, _cost(prediction, y, train))


def _cost(prediction, y, mask):
    return float(np.mean((prediction - y)[..., mask] ** 2))


def block_masks(n, blocks=BLOCKS, folds=FOLDS, guard=GUARD):
    """
    (train, test) boolean masks of each fold.

    The record is cut into `blocks` contiguous blocks of time; fold k holds out blocks k, k +
    folds, k + 2 folds, ... Spreading each fold's held-out time over the record keeps every
    training set covering the whole range of the operating conditions (so the score measures the
    model, not an extrapolation to an unseen pressure), while each held-out block stays long
    compared with the dynamics of the causes. `guard` (fraction of a block) is left out of training
    on both sides of a held-out block.
    """
    edges = np.linspace(0, n, blocks + 1).astype(int)
    pad = int(guard * n / blocks)
    masks = []
    for fold in range(folds):
        test = np.zeros(n, bool)
        train = np.ones(n, bool)
        for lo, hi in zip(edges[fold:-1:folds], edges[fold + 1::folds]):
            test[lo:hi] = True
            train[max(0, lo - pad):min(n, hi + pad)] = False
        masks.append((train, test))
    return masks


@dataclass
class Score:
    """A model fitted on all data (`full`) and its held-out residual (`heldout`, per sample)."""

    model: Model
    full: Fit
    heldout: np.ndarray

    @property
    def rmse(self):
        return float(np.sqrt(np.mean(self.heldout ** 2)))

    def output_rmse(self, index):
        """Held-out RMSE of output `index` of a multi-output model (in its scaled units)."""
        return float(np.sqrt(np.mean(self.heldout[index] ** 2)))

    @property
    def insample_rmse(self):
        """RMSE of the fit on all data, over all data."""
        return float(np.sqrt(self.full.cost))

    def params(self):
        return self.model.physical(self.full.theta, self.full.linear)


def score(model, y, warm=None):
    """
    Fit `model` to all of `y`, then refit per held-out block and collect the held-out residuals.

    The block refits are warm-started; `warm` optionally gives a start for the full fit.
    """
    n = np.shape(y)[-1]
    everything = np.ones(n, bool)
    full = fit(model, y, everything, x0=warm)
    heldout = np.empty(np.shape(y))
    for train, test in block_masks(n):
        fold = fit(model, y, train, x0=full.theta if model.names else None, max_nfev=FOLD_NFEV)
        heldout[..., test] = (fold.prediction - y)[..., test]
    return Score(model, full, heldout)


def heldout_failure(score, noise):
    """
    Tell why the held-out score of `score` is not a measure of its model, or return None.

    That is a held-out RMSE above `FAILURE_NOISE` × `noise` (the averaged noise floor) while the
    same model fits all the data to within 1 / `FAILURE_INSAMPLE` of that. Such a gap is not
    physics a cause could remove but a fold refit gone wrong (an ill-posed solve, or a fold whose
    training rows never see the conditions of its held-out blocks), and comparing causes against
    it would name whichever breaks least.
    """
    held, fitted = score.rmse, score.insample_rmse
    if not np.isfinite(held) or (held > FAILURE_NOISE * noise
                                 and held > FAILURE_INSAMPLE * fitted):
        ratio = f'{held / noise:.0f} ×' if noise > 0 else 'far above'
        return (f'numerical failure of the held-out refits: held-out RMSE {held:.4g} is {ratio} '
                f'the noise floor while the fit on all data reaches {fitted:.4g}')
    return None


def gain(extended_rmse, baseline_rmse):
    """1 - extended / baseline (the `gain` of report.json)."""
    return float(1.0 - extended_rmse / baseline_rmse) if baseline_rmse > 0 else 0.0


def bic_delta(candidate, current):
    """
    Return the change of a BIC-like criterion on held-out residuals.

    n ln(MSE ratio) + k ln(n), with n the number of held-out samples and k the number of parameters
    the candidate adds.

    Negative means the candidate is worth its added parameters. With thousands of samples this
    penalty is small; the minimum gain is then the binding part of the rule.
    """
    n = candidate.heldout.size
    added = max(candidate.model.n_params - current.model.n_params, 0)
    ratio = np.mean(candidate.heldout ** 2) / np.mean(current.heldout ** 2)
    return float(n * np.log(ratio) + added * np.log(n))


def pays(candidate, current):
    """Decision rule: held-out gain ≥ MIN_GAIN and the BIC-like criterion decreases."""
    return gain(candidate.rmse, current.rmse) >= MIN_GAIN and bic_delta(candidate, current) < 0


def at_edge(score, cause, margin=0.005):
    """
    Names of `cause`'s fitted nonlinear parameters that ended at a bound of their physical range.

    A cause whose parameter runs to the edge (a sensor lag of 1 ms at 100 Hz, a natural curvature
    steeper than any bellows) is not describing its physics: it is absorbing some other error.
    Unless the bound is a limiting case of the physics (`edges`, `diagnosis`).
    """
    return [name for name, _ in edges(score, cause, margin)]


def edges(score, cause, margin=0.005):
    """
    Return [(name, side)] of `cause`'s fit variables at a bound; side 'lower' or 'upper'.

    `margin` is a fraction of the variable's range.
    """
    model, theta = score.model, score.full.theta
    found = []
    for name, value, lo, hi in zip(model.names, theta, model.lower, model.upper):
        if name.startswith(cause + '.'):
            position = (value - lo) / (hi - lo)
            if position < margin or position > 1.0 - margin:
                found.append((name.split('.', 1)[1], 'lower' if position < 0.5 else 'upper'))
    return found


def autocorrelation(x, max_lag):
    """Sample autocorrelation r_0..r_max_lag (r_0 = 1) via FFT."""
    x = np.asarray(x, float) - np.mean(x)
    n = len(x)
    size = 1 << int(np.ceil(np.log2(2 * n)))
    spectrum = np.fft.rfft(x, size)
    acf = np.fft.irfft(spectrum * np.conj(spectrum), size)[:max_lag + 1]
    return acf / acf[0] if acf[0] > 0 else np.zeros(max_lag + 1)


def ljung_box(residual, lags):
    """
    Ljung-Box Q over lags 1..`lags` and its p-value (chi-square with `lags` dof).

    For white noise Q ≈ lags; structure left in a residual makes Q large.
    """
    from scipy.stats import chi2
    n = len(residual)
    r = autocorrelation(residual, lags)[1:]
    q = float(n * (n + 2) * np.sum(r ** 2 / (n - np.arange(1, lags + 1))))
    return q, float(chi2.sf(q, lags))


def noise_floor(signal):
    """
    Estimate the standard deviation of the white measurement noise on `signal`.

    From its first differences (robust MAD estimate). At 1 kHz the signal itself changes little
    between samples, so the differences are dominated by noise: var(diff) = 2 sigma^2.
    """
    d = np.diff(np.asarray(signal, float))
    d = d - np.median(d)
    return float(1.4826 * np.median(np.abs(d)) / np.sqrt(2))


def noise_floor_local(signal, n=25):
    """
    Estimate the standard deviation of the fast noise on `signal`, whatever its correlation.

    The RMS of `signal` minus its centred running mean over `n` samples, scaled by
    sqrt(n / (n - 1)) (exact for white noise). Unlike the difference estimates it does not assume
    white Gaussian noise: a noise that flips sign from sample to sample (a friction term driven by
    a velocity differenced from a noisy angle) has first differences twice its size. Changes
    slower than `n` samples (the motion) fall out with the running mean.
    """
    x = np.asarray(signal, float)
    if len(x) < n:
        return float(np.std(x))
    mean = np.convolve(x, np.ones(n) / n, mode='valid')
    centre = x[n // 2:n // 2 + len(mean)]
    return float(np.sqrt(np.mean((centre - mean) ** 2) * n / (n - 1)))


def guarded_floor(value, signal):
    """
    Return the noise floor `value` of `signal`, at least 1e-6 of its span (and 1e-12).

    A noise-free column (simulated) would give a floor of zero; this keeps dividing by it finite.
    """
    return max(value, 1e-6 * float(np.ptp(signal)), 1e-12)


def noise_floor_ramps(signal):
    """
    Estimate `noise_floor` from second differences.

    For a signal that is ramped fast for much of the record (the spring force under test-machine
    ramps changes by more than its noise per sample), the first differences carry the ramp's
    slope; the second differences only its kinks. For white noise
    var(second difference) = 6 sigma^2.
    """
    d = np.diff(np.asarray(signal, float), 2)
    d = d - np.median(d)
    return float(1.4826 * np.median(np.abs(d)) / np.sqrt(6))
