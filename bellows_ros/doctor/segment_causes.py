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
The segment's baseline and its candidate causes, as physically parameterised extensions.

What is compared: the driving torque the record implies, Y = τ_motion - τ_ext (30), with the
model's driving torque. τ_motion comes from the record's `tau_motion` column, else from the
equation of motion (2) with `segment.dynamics` (quasi-static by default: Y = -τ_ext).

Baseline (docs/doctor.md): paper A's previous model (34) with constant friction (c_f only)
and no natural curvature (Ψ_j0 = 0, no k_s,p): Y = X_prev θ_prev + 2Ψ k_s + tanh(c_vel Ψ̇) c_f, all
linear coefficients solved by least squares (32) on the training rows.

Each cause is an effect of `models.segment_effects` (docs/effects.md): it feeds the model other
pressures (a sensor lag), swaps or extends a block of the regression (the contact torque, c_f,p,
the natural curvature) and may add nonlinear variables of its own.
"""
from types import SimpleNamespace

import numpy as np

from bellows_ros.doctor.scoring import Model, noise_floor
from bellows_ros.identify.segment import filter_inputs, least_squares, target
from bellows_ros.models.derivatives import rates
from bellows_ros.models.segment import (contact_lengths, friction_regressor, previous_regressor,
                                        restoring_regressor, scaled_pressure)
from bellows_ros.models.segment_effects import BY_NAME, EFFECTS, NAMES

CAUSES = NAMES
# Causes the plant has only with `--effect NAME` (the rest are the model's own parameters).
SWITCHED_BY_EFFECT = tuple(effect.name for effect in EFFECTS if effect.switched_by_effect)
# What a record must hold to decide each cause when it came closest but did not pay (report.md).
DECIDING_DATA = {effect.name: effect.deciding_data for effect in EFFECTS}
BASELINE = ('paper A previous model (34), constant friction c_f, no natural curvature '
            '(psi_j0 = 0, k_s,p = 0); coefficients refitted')
# Hz, highest rate the doctor fits at: quasi-static bench records; the sensor lag is ~30 ms
FIT_RATE = 100.0
UNIT = 'N·m'
# Linear columns of the baseline's regression: A(34)'s pressure polynomial (4), k_s, c_f.
BASELINE_COLUMNS = 6


def add_columns(record, params, input_cutoff):
    """
    Add the derived columns the segment causes need: Ψ̇ (if absent) and Y (the target).

    The measured inputs are low-passed as the identification does (`identify.segment.filter_inputs`
    at `input_cutoff` Hz, the file's `segment.identify.input_cutoff`).

    Why filter: the torque is steep in the pressure (~0.05 N·m per kPa), so white pressure-sensor
    noise (1 kPa) would reach the prediction as ~0.05 N·m at 1 kHz — as large as the torque
    sensor's own noise — and Algorithm 1's strain memory would ratchet with it. The signals are
    band-limited (valve/chamber lag, imposed motion), so a 25 Hz zero-phase filter removes that
    noise without delaying anything. Y (the measured output) is never filtered.
    """
    columns = record.columns
    if 'psi_dot' not in columns:
        columns['psi_dot'] = rates(columns['t'], columns['psi'])
    columns['y'] = target(params, columns)  # Y = τ_motion - τ_ext (30), from the raw record
    filtered, _, _ = filter_inputs(columns, input_cutoff)
    columns.update(filtered)
    return record


def measured(record):
    return record['y']


class ContactLengths:
    """
    s̃_a of both chains over the record, computed once (Algorithm 1 is sequential and costly).

    Algorithm 1 makes one fixed-point iteration per time step (appendix B), so its contact state
    follows the angle and pressure at a pace set by the step: run on the 100 Hz fitted copy it lags
    the plant's 1 kHz strain memory and leaves ~0.1 N·m of structure in the residual that is not
    noise. So it runs on the full-rate record (`record`, inputs already low-passed by
    `add_columns`) and its result is block-averaged by `factor` like the fitted copy
    (`checks.Record.decimated`).
    """

    def __init__(self, params, record, factor=1):
        self.params, self.record, self.factor, self.value = params, record, factor, None

    def __call__(self):
        if self.value is None:
            r = self.record
            lengths = contact_lengths(self.params, r['psi'], r['p1'], r['p2'])
            n = len(lengths[0]) // self.factor * self.factor
            self.value = tuple(sa[:n].reshape(-1, self.factor).mean(axis=1) for sa in lengths)
        return self.value


def build_model(record, params, causes, warm=None, contact=None, noise=None):
    """
    Build the baseline plus `causes` on `record` (`add_columns` applied) as a `scoring.Model`.

    `noise`: white-noise standard deviation of Y on `record` (N·m), for the prior of the linear
    solve; default: the noise floor of Y estimated on `record` itself.

    The linear coefficients are `identify.segment.least_squares` (32) with a ridge and a scale:

    `scale` (one per column) is each column's RMS over the whole record — the rows the model will
    predict — not over the training rows: a column the training rows hardly excite (a chain that
    is pressurised only in the held-out blocks: the pressure columns there are filtered sensor
    noise around p0) must look small, not be blown up to unit norm and fitted to the noise. It
    was, with a ridge of 1e-10 relative to the training Gram: on a record pressurised only in its
    last 2 s, the baseline's held-out RMSE was 3981 N·m (in-sample 0.0183; docs/doctor.md).

    `ridge` = (σ/s)², σ the noise of Y, s the spread of Y over the record: the MAP estimate for the
    prior that no single column contributes more than the measured signal varies (each scaled
    coefficient ~ N(0, s²)). A direction the training rows excite so little that the noise cannot
    resolve it (scaled Gram eigenvalue < ridge) goes to zero instead of to ±∞; a well-excited one
    is untouched (its Gram entry is ~ the number of rows, ~1e7 × ridge).
    """
    causes = tuple(causes)
    contact = contact or ContactLengths(params, record)
    psi, psi_dot, dt = record['psi'], record['psi_dot'], record.dt
    y = record['y']
    noise = noise_floor(y) if noise is None else noise
    # Prior of the linear solve; the floor keeps an all-zero column (a chain never
    # pressurised) from making a noise-free record's system singular.
    ridge = max((noise / max(np.std(y), noise, 1e-12)) ** 2, 1e-10)
    effects = [BY_NAME[cause] for cause in causes]
    names, x0, lower, upper = [], [], [], []
    for effect in effects:
        for name, start, lo, hi in effect.fit:
            key = f'{effect.name}.{name}'
            names.append(key)
            x0.append(warm[key] if warm and key in warm else start)
            lower.append(lo)
            upper.append(hi)
    starts = []
    if effects and effects[-1].fit:
        width = len(effects[-1].fit)
        starts = [x0[:-width] + list(alt) for alt in effects[-1].starts]

    def raw(theta):
        """{cause: {fit variable: value}} of `theta`."""
        values, k = {}, 0
        for effect in effects:
            values[effect.name] = {v.name: float(theta[k + i]) for i, v in enumerate(effect.fit)}
            k += len(effect.fit)
        return values

    def columns(theta):
        values = raw(theta)
        p1, p2 = record['p1'], record['p2']
        for effect in effects:
            p1, p2 = effect.pressures(p1, p2, dt, values[effect.name])
        ps1, ps2 = scaled_pressure(params, p1), scaled_pressure(params, p2)
        friction = friction_regressor(psi_dot, ps1, ps2, params.friction_c_vel)
        blocks = {'pressure': (previous_regressor(psi, ps1, ps2),
                               [f'previous.theta[{k}]' for k in range(4)]),
                  'restoring': (restoring_regressor(psi, ps1, ps2, 0.0, 0.0)[:, :1],
                                ['restoring.k_s']),
                  'friction': (friction[:, :1], ['friction.c_f'])}
        data = SimpleNamespace(psi=psi, psi_dot=psi_dot, ps1=ps1, ps2=ps2, params=params,
                               contact=contact)
        for effect in effects:
            blocks = effect.regressors(blocks, data, values[effect.name])
        parts = [blocks[name] for name in ('pressure', 'restoring', 'friction')]
        return np.column_stack([x for x, _ in parts]), [label for _, ls in parts for label in ls]

    cache = {}

    def run(theta, train):
        key = tuple(np.round(theta, 12))
        if key not in cache:
            cache.clear()
            x, labels = columns(theta)
            scale = np.sqrt(np.mean(x * x, axis=0))
            scale[scale == 0] = 1.0
            cache[key] = x, labels, scale
        x, labels, scale = cache[key]
        coefficients = least_squares(x[train], y[train], ridge, scale)
        return x @ coefficients, dict(zip(labels, coefficients))

    n_linear = BASELINE_COLUMNS + sum(effect.extra_columns for effect in effects)

    def physical(theta, linear):
        out = {'baseline': {}, **{cause: {} for cause in causes}}
        for label, value in linear.items():
            part = next((e.name for e in effects if e.owned and label.startswith(e.owned)),
                        'baseline')
            out[part][label] = float(value)
        for effect, values in zip(effects, raw(theta).values()):
            out[effect.name].update(effect.to_si(values))
        return out

    return Model(causes, names, x0, lower, upper, run, physical, n_linear=n_linear, starts=starts)


def extended_flat(config, causes, values):
    """
    Return the flat ROS 2 parameters of the extended model for `params.write_file`.

    `config`: the `SegmentConfig` diagnosed. All names of config/segment.yaml, loadable by
    `bellows_ros.config.segment.load_segment`.

    The fitted coefficients go to their YAML names; physics a cause did not find is written as
    switched off (each effect's `off`: c_f,p = 0, c_Ψ0,p = k_s,p = 0), so the file describes
    exactly the extended model. A fitted sensor lag goes to `segment.plant.sensor_lag_tau` (the
    plant's `sensor_lag` effect: its `label`).
    """
    params = config.model
    flat = config.flat()
    vector = {'actuator.theta': list(params.actuator_theta),
              'previous.theta': list(params.previous_theta)}
    scalars = {}
    for effect in EFFECTS:
        if effect.name not in causes:
            scalars.update({field.replace('_', '.', 1): value
                            for field, value in effect.off.items()})
    for part, fitted in values.items():
        label_of = BY_NAME[part].label if part in BY_NAME else str
        for label, value in fitted.items():
            if '[' in label:
                name, index = label[:-1].split('[')
                vector[name][int(index)] = value
            else:
                scalars[label_of(label)] = value
    for name, value in vector.items():
        flat[f'segment.{name}'] = [float(v) for v in value]
    for name, value in scalars.items():
        flat[f'segment.{name}'] = float(value)
    return flat
