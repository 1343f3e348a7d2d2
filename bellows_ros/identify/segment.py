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
Identification of the segment driving-torque model (paper A, eqs. 30-33).

Also the Fig. 10 calibration.

Inner problem (32): for fixed nonlinear parameters, θ = [θ_a (8), k_s, k_s,p, c_f, c_f,p] is the
linear least-squares solution of Y = X θ, X = [X_a X_s X_f] (31), Y = τ_motion - τ_ext (30); solved
with `least_squares` (no explicit inverse). Outer problem (33): minimise the inner residual over
(μ1, μ2, γ1, γ2) — which move s̃_a through the strain memory — and the natural-curvature constants
(c_Ψ0, c_Ψ0,p), within bounds (γ_k > 2): Sobol screening, then bounded Nelder-Mead from several
starts (the problem has local minima; see `fit_segment`). The previous model (34) is refitted on
the same rows: θ_prev by least squares on Y - τ_s - τ_f (its τ_s, τ_f are the shared ones of the
YAML, so the stored θ_prev reproduces exactly what `simulate` outputs as tau_prev).

Held-out error: the fit uses the first `1 - holdout` of the rows; RMSE and MAE are reported on the
rest. The strain memory always runs over the whole record (its state needs the history).

Errors in variables: the measured inputs (p1, p2, Ψ, Ψ̇) carry white sensor noise over the whole
0..f_s/2 band, while the signals themselves are band-limited (valve/chamber lag, imposed motion),
and the torque is steep in the pressure (~0.05 N·m per kPa). Both the fit and the prediction
pipeline of the fitted model therefore first low-pass the inputs with a zero-phase Butterworth
filter (`segment.identify.input_cutoff`, `filter_inputs`). The measured torque τ_ext (the target)
is never filtered: errors are against the raw measurement.
"""
from dataclasses import dataclass
import math
import sys

import numpy as np
from scipy import optimize, signal, stats
from scipy.linalg import cho_factor, cho_solve

from bellows_ros.models.derivatives import rates
from bellows_ros.models.segment import (actuator_regressor, contact_lengths, external_torque,
                                        friction_regressor, previous_regressor,
                                        restoring_regressor, scaled_pressure)

# Outer (nonlinear) parameters: name, SegmentParams field, bounds; μ searched in log space.
NONLINEAR = (('mu1', (100.0, 1e5)), ('mu2', (10.0, 1e5)), ('gamma1', (2.05, 12.0)),
             ('gamma2', (2.05, 12.0)), ('c_psi0', (0.1, 20.0)), ('c_psi0_p', (-1.5, 1.5)))
# The outer search runs on at most this many (evenly strided) training rows: on a 1 kHz record a
# stride near 50 Hz biases Algorithm 1 enough to move the optimum into another basin; ~140 Hz does
# not.
SEARCH_ROWS = 12000
REFINE_ROWS = 24000  # ... and its refinement (step 3) on at most this many
POLISH_EVALUATIONS = 40  # full-rate forward runs of the final polish (step 4), ~0.5-1.8 s each
POLISH_STEP = 1e-3  # relative finite-difference step of the polish's Jacobian
INPUT_FILTER_ORDER = 4  # Butterworth order of the input low-pass (applied forward and backward)
MIN_RATE_PER_CUTOFF = 5.0  # below this sampling rate / cutoff the inputs are left unfiltered
FILTERED_INPUTS = ('p1', 'p2', 'psi', 'psi_dot')
GAP_STEPS = 10.0  # a time step longer than this many median steps separates joined records


@dataclass
class Fit:
    """Result of `fit_segment`: fitted params, held-out errors (N·m), and the search trace."""

    params: object
    heldout: dict         # {'model': (rmse, mae), 'previous': (rmse, mae)}
    train_rows: int
    heldout_rows: int
    cost: float           # inner residual RMS on the training rows, N·m
    evaluations: int
    input_cutoff: object = None  # input low-pass cutoff applied, Hz (None: inputs not filtered)
    rate: float = 0.0     # sampling rate of the record (1 / median step), Hz


def filter_inputs(record, cutoff):
    """
    Zero-phase low-pass of the measured inputs p1, p2, Ψ, Ψ̇ (those present) of `record`.

    Butterworth of order INPUT_FILTER_ORDER at `cutoff` Hz, run forward and backward
    (`scipy.signal.sosfiltfilt`: no delay, so the contact state and friction sign stay aligned with
    the torque), at the rate 1 / median time step. A time step over GAP_STEPS median steps marks
    records joined end to end: each piece is filtered on its own (filtering across the join would
    smear the jump between unrelated records into both); pieces too short to pad stay unfiltered.
    τ_ext, τ_motion and t are passed through unchanged. Returns (filtered copy of the record,
    cutoff applied in Hz or None, rate in Hz); the inputs are left as measured (cutoff None) when
    `cutoff` is 0/None or when the rate is below MIN_RATE_PER_CUTOFF × cutoff (the filter would cut
    into the signal band).
    """
    filtered = dict(record)
    t = np.asarray(record['t'], float)
    steps = np.diff(t)
    rate = 1.0 / float(np.median(steps)) if len(t) > 1 else 0.0
    if not cutoff or cutoff <= 0 or rate < MIN_RATE_PER_CUTOFF * cutoff:
        return filtered, None, rate
    sos = signal.butter(INPUT_FILTER_ORDER, cutoff, fs=rate, output='sos')
    joins = np.flatnonzero(steps > GAP_STEPS / rate) + 1
    pieces = [piece for piece in np.split(np.arange(len(t)), joins)
              if len(piece) > 3 * (2 * len(sos) + 1)]  # sosfiltfilt's default edge padding
    if not pieces:
        return filtered, None, rate
    for name in FILTERED_INPUTS:
        if name in record:
            filtered[name] = np.array(record[name], float)
            for piece in pieces:
                filtered[name][piece] = signal.sosfiltfilt(sos, filtered[name][piece])
    return filtered, float(cutoff), rate


def target(params, record):
    """
    Compute Y = τ_motion - τ_ext (30), N·m.

    τ_motion comes from the record if it has the column, else from the model's equation of motion
    (2) with `segment.dynamics` (quasi-static default: 0).
    """
    if 'tau_motion' in record:
        motion = np.asarray(record['tau_motion'], float)
    else:
        t, psi = np.asarray(record['t'], float), np.asarray(record['psi'], float)
        psi_dot = np.asarray(record['psi_dot'], float) if 'psi_dot' in record else rates(t, psi)
        # M Ψ̈ + C Ψ̇ + N(Ψ) of (2): the external torque with no driving torque, negated.
        motion = -external_torque(params, psi, psi_dot, rates(t, psi_dot), 0.0)
    return motion - np.asarray(record['tau_ext'], float)


def regressors(params, record, rows=slice(None)):
    """
    Build the regressor blocks over `record` (Algorithm 1 carried over the selected rows).

    Returns dict X_a (N,8), X_s (N,2), X_f (N,2), X_prev (N,4).
    """
    psi = np.asarray(record['psi'], float)[rows]
    t = np.asarray(record['t'], float)
    psi_dot = (np.asarray(record['psi_dot'], float) if 'psi_dot' in record
               else rates(t, np.asarray(record['psi'], float)))[rows]
    p1, p2 = np.asarray(record['p1'], float)[rows], np.asarray(record['p2'], float)[rows]
    q1, q2 = scaled_pressure(params, p1), scaled_pressure(params, p2)
    sa1, sa2 = contact_lengths(params, psi, p1, p2)
    return {'X_a': actuator_regressor(psi, q1, q2, sa1, sa2),
            'X_s': restoring_regressor(psi, q1, q2, params.restoring_c_psi0,
                                       params.restoring_c_psi0_p),
            'X_f': friction_regressor(psi_dot, q1, q2, params.friction_c_vel),
            'X_prev': previous_regressor(psi, q1, q2)}


def least_squares(x, y, ridge=0.0, scale=None):
    """
    θ minimising |X θ - Y|² + ridge |diag(scale) θ|² (32), the one linear solve of the project.

    ridge = 0 (identification): plain least squares by `numpy.linalg.lstsq` (SVD, no explicit
    inverse; the minimum-norm θ if X is rank deficient). ridge > 0 (the doctor): the MAP estimate
    for a Gaussian prior on the scaled coefficients, by Cholesky of the scaled normal equations
    (a dozen unknowns, called hundreds of times per diagnosis). `scale` (one per column, default 1)
    is the size each column is measured in; the doctor passes each column's RMS over the rows the
    model will predict (see `bellows_ros.doctor.segment_causes.build_model` for why).
    """
    if not ridge > 0.0:
        return np.linalg.lstsq(x, y, rcond=None)[0]
    scale = np.ones(x.shape[1]) if scale is None else scale
    xs = x / scale
    gram = xs.T @ xs
    gram[np.diag_indices_from(gram)] += ridge
    return cho_solve(cho_factor(gram), xs.T @ y) / scale


def solve_linear(blocks, y):
    """θ = argmin |Y - X θ| (32) with X = [X_a X_s X_f] (31); returns (θ, residual)."""
    x = np.hstack([blocks['X_a'], blocks['X_s'], blocks['X_f']])
    theta = least_squares(x, y)
    return theta, y - x @ theta


def with_linear(params, theta):
    """Return `params` with θ = [θ_a(8), k_s, k_s,p, c_f, c_f,p] set."""
    theta = [float(v) for v in theta]
    return params.replace(actuator_theta=tuple(theta[:8]), restoring_k_s=theta[8],
                          restoring_k_sp=theta[9], friction_c_f=theta[10], friction_c_fp=theta[11])


def linear_of(params):
    return np.array(list(params.actuator_theta) + [params.restoring_k_s, params.restoring_k_sp,
                                                   params.friction_c_f, params.friction_c_fp])


def restoring_and_friction(params, blocks, rows=slice(None)):
    """
    Compute τ_s + τ_f (3, 5), N·m, on `rows` of the regressor blocks.

    With k_s, k_s,p, c_f, c_f,p of `params`.
    """
    theta = linear_of(params)
    return blocks['X_s'][rows] @ theta[8:10] + blocks['X_f'][rows] @ theta[10:12]


def fit_previous(params, blocks, y):
    """θ_prev of (34) by lstsq on Y - τ_s - τ_f, with τ_s, τ_f of `params`."""
    rest = y - restoring_and_friction(params, blocks)
    return least_squares(blocks['X_prev'], rest)


def errors(residual):
    """(RMSE, MAE) in N·m."""
    residual = np.asarray(residual, float)
    return float(np.sqrt(np.mean(residual ** 2))), float(np.mean(np.abs(residual)))


def _to_vector(params):
    mu, gamma = params.ogden_mu, params.ogden_gamma
    return np.array([math.log(mu[0]), math.log(mu[1]), gamma[0], gamma[1],
                     params.restoring_c_psi0, params.restoring_c_psi0_p])


def _from_vector(params, z):
    return params.replace(ogden_mu=(math.exp(z[0]), math.exp(z[1])), ogden_gamma=(z[2], z[3]),
                          restoring_c_psi0=z[4], restoring_c_psi0_p=z[5])


def _bounds():
    lows, highs = [], []
    for name, (low, high) in NONLINEAR:
        if name.startswith('mu'):
            low, high = math.log(low), math.log(high)
        lows.append(low)
        highs.append(high)
    return optimize.Bounds(lows, highs)


def fit_segment(params, record, input_cutoff, holdout=0.3, starts=3, seed=0, max_evaluations=150,
                screen=32, progress=True, search_rows=SEARCH_ROWS, refine_rows=REFINE_ROWS,
                polish_evaluations=POLISH_EVALUATIONS):
    """
    Fit paper A's model to `record` (arrays, columns of docs/interfaces.md); returns a `Fit`.

    `params` gives the fixed geometry and one candidate start. Search, on at most `search_rows`
    evenly strided rows of the training part:
    1. screening: `screen` points of a scrambled Sobol design over the material bounds (plus the
       given material), each scored by the residual of (32);
    2. bounded Nelder-Mead (derivative-free: the ceil() of Algorithm 1 makes the residual piecewise
       constant at fine scale) over (ln μ1, ln μ2, γ1, γ2) from the `starts` best points;
    3. on at most `refine_rows` rows (a finer stride: Algorithm 1 run with coarse steps biases the
       residual, enough to move its minimum on 1 kHz data — see docs/segment.md): (c_Ψ0, c_Ψ0,p),
       which only enter X_s, by least squares for the best material — no forward runs — and a
       shorter Nelder-Mead polish of the material with them, twice;
    4. on every training row (full rate: any stride shifts the optimum, docs/segment.md): a bounded
       trust-region Gauss-Newton (`scipy.optimize.least_squares`) on all six, θ re-solved by (32)
       in each residual, of
       at most ~`polish_evaluations` forward runs (0: skip the step).
    The two Ogden terms are interchangeable, so (μ1, γ1) and (μ2, γ2) may come out swapped.
    Before all of it the inputs are low-pass filtered (`filter_inputs`) at `input_cutoff` Hz
    (`segment.identify.input_cutoff`; 0: off); `Fit.input_cutoff` says what was applied.
    """
    from tqdm import tqdm

    record, applied_cutoff, rate = filter_inputs(record, input_cutoff)
    y_all = target(params, record)
    n = len(y_all)
    n_train = max(2, int(round(n * (1.0 - holdout))))
    train = slice(0, n_train)
    searched = slice(0, n_train, max(1, math.ceil(n_train / search_rows)))
    y_search = y_all[searched]
    bounds = _bounds()
    material_bounds = optimize.Bounds(bounds.lb[:4], bounds.ub[:4])
    curvature = np.clip(_to_vector(params), bounds.lb, bounds.ub)[4:]
    evaluations = 0
    polish = max_evaluations // 2
    bar = tqdm(total=screen + 1 + starts * max_evaluations + 2 * polish + 2
               + polish_evaluations, desc='identify segment',
               unit='run', disable=not progress, file=sys.stderr, leave=False)

    def blocks_for(z_material):
        nonlocal evaluations
        evaluations += 1
        bar.update(1)
        trial = _from_vector(params, np.concatenate([z_material, curvature]))
        return regressors(trial, record, searched)

    def cost(z_material):
        return float(np.sum(solve_linear(blocks_for(z_material), y_search)[1] ** 2))

    def local(z0, budget):
        result = optimize.minimize(cost, z0, method='Nelder-Mead', bounds=material_bounds,
                                   options={'maxfev': budget, 'xatol': 1e-3, 'fatol': 1e-9})
        return result.x, result.fun

    with bar:
        first = np.clip(_to_vector(params), bounds.lb, bounds.ub)[:4]
        design = stats.qmc.scale(stats.qmc.Sobol(4, scramble=True, seed=seed).random(screen),
                                 material_bounds.lb, material_bounds.ub)
        candidates = [first] + list(design)
        scores = [cost(z) for z in candidates]
        best_z, best_cost = first, math.inf
        for k in np.argsort(scores)[:starts]:
            z, value = local(candidates[k], max_evaluations)
            if value < best_cost:
                best_z, best_cost = z, value
        searched = slice(0, n_train, max(1, math.ceil(n_train / max(refine_rows, search_rows))))
        y_search = y_all[searched]
        psi_s = np.asarray(record['psi'], float)[searched]
        q1_s = scaled_pressure(params, np.asarray(record['p1'], float)[searched])
        q2_s = scaled_pressure(params, np.asarray(record['p2'], float)[searched])

        def fit_curvature(z_material):
            # (c_Ψ0, c_Ψ0,p) only enter X_s: one forward run, then least squares without any
            blocks = blocks_for(z_material)

            def curvature_residual(c):
                blocks['X_s'] = restoring_regressor(psi_s, q1_s, q2_s, c[0], c[1])
                return solve_linear(blocks, y_search)[1]
            return optimize.least_squares(curvature_residual, curvature,
                                          bounds=(bounds.lb[4:], bounds.ub[4:]), diff_step=1e-4).x

        def full_rate_polish(z0):
            # Gauss-Newton (trust region) on all six nonlinear parameters over every training row,
            # θ re-solved by (32) in each residual; forward runs cached per material, so the
            # curvature columns of the finite-difference Jacobian cost none. About 1 + 4 runs per
            # iteration.
            psi, y = np.asarray(record['psi'], float)[train], y_all[train]
            q1 = scaled_pressure(params, np.asarray(record['p1'], float)[train])
            q2 = scaled_pressure(params, np.asarray(record['p2'], float)[train])
            cache = {}

            def residual(z):
                key = tuple(z[:4])
                if key not in cache:
                    if len(cache) > 5:
                        cache.clear()
                    cache[key] = _full_blocks(z[:4])
                blocks = dict(cache[key], X_s=restoring_regressor(psi, q1, q2, z[4], z[5]))
                return solve_linear(blocks, y)[1]

            def _full_blocks(z_material):
                nonlocal evaluations
                evaluations += 1
                bar.update(1)
                return regressors(_from_vector(params, np.concatenate([z_material, [0.0, 0.0]])),
                                  record, train)

            result = optimize.least_squares(residual, np.clip(z0, bounds.lb, bounds.ub),
                                            bounds=(bounds.lb, bounds.ub), diff_step=POLISH_STEP,
                                            max_nfev=max(1, polish_evaluations // 5))
            return result.x, 2.0 * result.cost

        for _ in range(2):  # alternate: curvature constants for this material, then re-polish
            curvature = fit_curvature(best_z)
            best_z, best_cost = local(best_z, polish)
        if polish_evaluations > 0:
            best_z, best_cost = full_rate_polish(np.concatenate([best_z, curvature]))
            best_z, curvature = best_z[:4], best_z[4:]
        bar.set_postfix(rms=f'{math.sqrt(best_cost / len(y_search)):.4g} N·m')
    best_z = np.concatenate([best_z, curvature])
    fitted = _from_vector(params, best_z)
    blocks = regressors(fitted, record)
    train_blocks = {k: v[train] for k, v in blocks.items()}
    theta, residual_train = solve_linear(train_blocks, y_all[train])
    fitted = with_linear(fitted, theta)
    fitted = fitted.replace(previous_theta=tuple(
        float(v) for v in fit_previous(fitted, train_blocks, y_all[train])))
    held = slice(n_train, n)
    heldout = {'model': errors(y_all[held] - _predict(fitted, blocks, held)),
               'previous': errors(y_all[held] - _predict_previous(fitted, blocks, held))}
    return Fit(fitted, heldout, n_train, n - n_train, errors(residual_train)[0], evaluations,
               applied_cutoff, rate)


def predict(params, record, input_cutoff):
    """
    Run the fitted model's prediction pipeline on a measured record.

    The same input filter as the fit (`filter_inputs` at `input_cutoff` Hz, the file's
    `segment.identify.input_cutoff`), then the regressors (31) with θ of `params`. Returns (Ŷ of
    paper A's model, Ŷ of the previous model (34), Y measured) in N·m, Y = τ_motion - τ_ext (30)
    with the raw measured τ_ext.
    """
    filtered = filter_inputs(record, input_cutoff)[0]
    blocks = regressors(params, filtered)
    rows = slice(None)
    return _predict(params, blocks,
                    rows), _predict_previous(params, blocks, rows), target(params, filtered)


def prediction_errors(params, record, input_cutoff):
    """
    Return (RMSE, MAE) in N·m of `predict` against the raw measured torque.

    As {'model': ..., 'previous': ...}.
    """
    model, previous, y = predict(params, record, input_cutoff)
    return {'model': errors(y - model), 'previous': errors(y - previous)}


def _predict(params, blocks, rows):
    theta = linear_of(params)
    x = np.hstack([blocks['X_a'], blocks['X_s'], blocks['X_f']])[rows]
    return x @ theta


def _predict_previous(params, blocks, rows):
    return (blocks['X_prev'][rows] @ np.array(params.previous_theta)
            + restoring_and_friction(params, blocks, rows))


# --- Fig. 10 calibration of config/segment.yaml
# ------------------------------------------------------

FIG10_BEFORE, FIG10_AFTER = 6.7, 9.1  # |τ_ext| measured by paper A before/after the excursion, N·m


def calibrate_fig10(params, plant, before=FIG10_BEFORE, after=FIG10_AFTER, free=(0, 1), seed=0):
    """
    Choose θ_a so paper A's Fig. 10 scenario gives |τ_ext| = before/after; refit θ_prev.

    Geometry, material, restoring and friction parameters are taken from `params` (chosen by hand,
    see docs/segment.md). s̃_a does not depend on θ_a, so one noise-free run of the scenario gives
    the regressor rows at the two instants, and the two entries `free` of θ_a (the others kept)
    follow from a 2x2 linear solve. τ_ext = -τ_drive at rest (τ_motion = 0 there). θ_prev is then
    the least-squares fit of (34) to a noise-free quasi-static record of the calibrated physics, as
    paper A refitted its previous model on the same data. `plant`: the simulated segment's
    SegmentPlantParams (valves, dynamics). Returns the calibrated SegmentParams.
    """
    from bellows_ros.papers.segment_experiments import fig10_record, quasi_static_record
    from bellows_ros.models.segment_plant import FULL_MODEL, NO_NOISE

    record, i_before, i_after = fig10_record(params, plant, FULL_MODEL, NO_NOISE)
    blocks = regressors(params, record)
    rows = [i_before, i_after]
    theta_a = np.array(params.actuator_theta, float)
    free, others = list(free), [k for k in range(8) if k not in free]
    x = blocks['X_a'][rows]
    # τ_drive = -τ_ext = +|τ_ext| at both instants: chain 1 drives the segment towards larger Ψ
    rhs = (np.array([before, after]) - restoring_and_friction(params, blocks, rows)
           - x[:, others] @ theta_a[others])
    theta_a[free] = np.linalg.solve(x[:, free], rhs)
    calibrated = params.replace(actuator_theta=tuple(float(v) for v in theta_a))
    quasi = quasi_static_record(calibrated, plant, FULL_MODEL, NO_NOISE, seed=seed,
                                duration=300.0, dt=5e-3)
    qblocks = regressors(calibrated, quasi)
    theta_prev = fit_previous(calibrated, qblocks, target(calibrated, quasi))
    return calibrated.replace(previous_theta=tuple(float(v) for v in theta_prev))


def fig10_torques(params, plant, effects=None, noise=None, seed=None):
    """
    Return |τ_ext| of the Fig. 10 scenario before and after the excursion, with the old model's.

    The previous model's prediction -τ_prev at the same two instants (N·m): (before, after,
    prev_before, prev_after).
    """
    from bellows_ros.models.segment import simulate_model
    from bellows_ros.papers.segment_experiments import fig10_record
    from bellows_ros.models.segment_plant import FULL_MODEL, NO_NOISE

    record, i_before, i_after = fig10_record(params, plant,
                                             FULL_MODEL if effects is None else effects,
                                             NO_NOISE if noise is None else noise, seed)
    out = simulate_model(params, record['psi'], record['p1'], record['p2'], record['psi_dot'])
    return (-record['tau_ext'][i_before], -record['tau_ext'][i_after],
            out['tau_prev'][i_before], out['tau_prev'][i_after])


def main(argv=None):
    """
    Run `python -m bellows_ros.identify.segment --calibrate`: redo the Fig. 10 calibration.

    Prints the θ values of config/segment.yaml to paste there, with the resulting torques.
    """
    import argparse

    from bellows_ros.config.segment import load_segment
    parser = argparse.ArgumentParser(description=main.__doc__)
    parser.add_argument('--calibrate', action='store_true', required=True)
    parser.add_argument('--params', help='start from this parameter file instead of the defaults')
    args = parser.parse_args(argv)
    config = load_segment(args.params)
    calibrated = calibrate_fig10(config.model, config.plant)
    print('actuator.theta:', [round(v, 6) for v in calibrated.actuator_theta])
    print('previous.theta:', [round(v, 6) for v in calibrated.previous_theta])
    before, after, prev_before, prev_after = fig10_torques(calibrated, config.plant)
    print(f'Fig. 10: |tau_ext| before {before:.3f} N·m, after {after:.3f} N·m; '
          f'previous model {prev_before:.3f} / {prev_after:.3f} N·m')
    return 0


if __name__ == '__main__':
    sys.exit(main())
