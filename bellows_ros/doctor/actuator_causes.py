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
The actuator's baseline and its candidate causes, as physically parameterised extensions.

Baseline (docs/doctor.md): paper B's gas law (17) with the purely geometric volume (2-4, no
E_V), isothermal sealed gas; the gas amount (as `p_ref`), `v_tube` and the zero of the motor
encoder (`x_c_offset`, within ±1 mm: on a rig the encoder's zero is set by homing and is as unknown
as the tube volume) are refitted to the data. For the force, paper B's (7)-(12) on the predicted
(not the measured) pressure: F = (P - P_atm) A(x_s) + F_mat with the material force a cubic
polynomial of x_s (F_MTS, plus the load cell's zero) and E_F (11) with the YAML's C2, C3 and its
amplitude C1, all linear and solved by least squares on the training rows; no buckling.

Two measured outputs are compared, the system pressure p (Pa) and the spring force f (N), each
divided by its own noise floor (`OUTPUTS`, `noise_floors`): the model is fitted to both at once and
every cause is judged on both (a leak changes the pressure and through it the force; a sensor lag
only the pressure reading; buckling only the force).

Each cause is an effect of `models.actuator_effects` (`EFFECTS`): it adds the missing physics
with its own parameters (its module's docstring, docs/doctor.md), its fit variables, starts,
bounds and what a fit pinned at each bound means (`edges`: a limit of the physics is a finding,
the others say why it is not named), and how a record shows it (`judged_by`).

Every bound is derived (docs/doctor.md, "Where every range comes from").

Standing physics (`standing`, `standing_physics`): the live doctor asks what changed from the
model its monitor compares the measurement with (`live.actuator_residuals`: the whole model, its
own E_V and buckling included), so its baseline keeps them at the model's values. The offline
doctor (`bellows diagnose`) keeps none: it asks what a device holds beyond paper B. A cause that
is also standing (buckling) replaces the standing term by its own fit, started at the model's
values: it pays only where the spring buckles otherwise than the model says.
"""
import dataclasses

import numpy as np

from bellows_ros.config.actuator import params_to_flat
from bellows_ros.doctor.scoring import guarded_floor, Model, noise_floor, noise_floor_ramps
from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator import (air_force, force_error, gas_amount,
                                         material_terms, pressure_of_amount, total_volume,
                                         without_bulging)
from bellows_ros.models.actuator_effects import BY_NAME, EFFECTS, NAMES
from bellows_ros.models.actuator_effects.base import FitVariable
from bellows_ros.models.actuator_geometry import P_ATM, volume_geo

CAUSES = NAMES
# What a record must hold to decide each cause when it came closest but did not pay (report.md).
DECIDING_DATA = {effect.name: effect.deciding_data for effect in EFFECTS}
BASELINE = ('paper B (17): geometric volume (no E_V), isothermal sealed gas, '
            'p_ref and v_tube refitted; force (7)-(12) on the predicted pressure, F_MTS a cubic '
            'in x_s and E_F amplitude refitted, no buckling')
# Physics of the model that a baseline may keep at the model's own values (module docstring).
STANDING = tuple(effect.name for effect in EFFECTS if effect.standing)
# Causes the plant has only with `--effect NAME` (the rest are the model's own parameters).
SWITCHED_BY_EFFECT = tuple(effect.name for effect in EFFECTS if effect.switched_by_effect)
# Measured outputs: (column, unit, name). The first is the legacy single output.
OUTPUTS = (('p', 'Pa', 'pressure'), ('f', 'N', 'force'))
F_MTS_DEGREE = 3
# Hz, highest rate the doctor fits at: sensor lag and heating act within tens of ms
FIT_RATE = 200.0
UNIT = 'Pa'
SIGNAL = 'p'
ML = 1e-6  # m³ per mL: volumes are fitted in mL so that all parameters are O(1)

# x_c_offset: the plate sits at x_c + offset. Without it a constant nut-plate offset (backlash in
# a record whose chamber never reverses) is taken up by the most flexible candidate (E_V).
BASELINE_FIT = (FitVariable('p_ref_kpa', 101.325, 20.0, 500.0),
                FitVariable('v_tube_ml', 20.0, 0.0, 400.0),
                FitVariable('x_c_offset_mm', 0.0, -1.0, 1.0))
# An effect judged by its onset (`judged_by == 'onset'`: buckling, `buckling_profile`): onsets on
# a grid over its bounds, kept where the record's rows reach them; the best PROFILE_STARTS of
# them start the fit. Four decades each: about 2.3 onsets per octave of x_cr, 1.5 of p_cr.
PROFILE_COMPRESSIONS = 28
PROFILE_PRESSURES = 18
PROFILE_STARTS = 3
# The strongest effect the bounds allow must change the outputs by at least this many (averaged)
# noise floors, in the least-squares sense and beyond what the baseline absorbs, at some onset
# the record reaches; else the record cannot show it (a chi-square of 25 on one added parameter:
# far beyond chance, yet any real effect the held-out rule would name clears it).
DETECTABLE = 5.0
# Values of each parameter across its bounds at which `_detectable` profiles a cause.
PROFILE_POINTS = 5


def fit_variables(part, params):
    """Return the `FitVariable`s of `part` ('baseline' or a cause) on `params` (ActuatorParams)."""
    return list(BASELINE_FIT) if part == 'baseline' else BY_NAME[part].fit_variables(params)


def edge_kind(cause, name, side):
    """(kind, meaning) of `cause`'s fit variable `name` pinned at its `side` bound (its edges)."""
    return BY_NAME[cause].edges.get((name, side), ('range', 'a bound of the fit, not of physics'))


def standing_physics(params):
    """Return the part of `STANDING` that `params` holds (E_V not zero, a spring that buckles)."""
    return tuple(e.name for e in EFFECTS if e.standing and e.held_by(params))


def baseline_name(standing=()):
    """`BASELINE`, with the model's own physics that it keeps (`standing`) said."""
    name = BASELINE
    for effect in EFFECTS:
        if effect.name in standing:
            name = name.replace(*effect.baseline_text)
    return name


@dataclasses.dataclass
class Onset:
    """One onset of the buckling profile: where it lies and what the record can show of it."""

    critical_compression: float   # x_cr, m
    critical_pressure: float      # p_cr, Pa
    detectable: float             # the strongest k_b's force change beyond F_mat, noise floors
    stiffness_loss: float         # k_b, N/m, that fits the record best at this onset (>= 0)
    improvement: float            # the fall of the force's squared error (noise floors²)


def buckling_profile(record, params, force_scale, standing, effect):
    """
    Profile buckling over its onset across the record's range: a list of `Onset`, best first.

    For every onset (x_cr, p_cr) on a grid over `actuator.buckling.bounds` that the record's rows
    reach on one side and not on another, the buckling force per unit stiffness loss on the
    measured pressure and compression, minus what the baseline's linear material force (F_MTS,
    load-cell zero, E_F) can absorb of it. Its norm with the largest k_b of the bounds, over the
    averaged force noise floor `force_scale` (N), is how far the record can show buckling there
    (`detectable`); the k_b >= 0 fitted to the baseline's force residual gives the improvement.
    No nonlinear fit: a few least-squares projections, cheap at any onset. With `standing` E_V,
    the force the model knows keeps it; a standing buckling is left out (the cause replaces it).
    `effect`: the effect judged by its onset (`judged_by == 'onset'`).
    """
    variables = effect.fit_variables(params)
    upper = {v.name: v.upper for v in variables}
    k_max = effect.to_si(upper)['stiffness_loss']
    _, pressure, compression = variables   # the fit's (k_b, p_cr, x_cr), in its own scale
    x_s, p, f = record['x_s'], record['p'], record['f']
    kept = tuple(name for name in standing if name != effect.name)
    known, columns = force_columns(params, (), {}, x_s, p, kept)
    basis, _ = np.linalg.qr(columns / np.sqrt(np.mean(columns ** 2, axis=0) + 1e-300))
    residual = f - known
    residual = residual - basis @ (basis.T @ residual)
    gauge = p - P_ATM
    onsets = []
    # The grid spans each onset variable's range evenly in the fit's own scale (decades).
    for x_value in np.linspace(compression.lower, compression.upper, PROFILE_COMPRESSIONS):
        for p_value in np.linspace(pressure.lower, pressure.upper, PROFILE_PRESSURES):
            unit = dict(effect.to_si({**upper, pressure.name: p_value,
                                      compression.name: x_value}), stiffness_loss=1.0)
            x_cr, p_cr = unit['critical_compression'], unit['critical_pressure']
            load = x_s / x_cr + gauge / p_cr
            if not (load.max() > 1.0 and load.min() < 1.0):
                continue    # buckled everywhere or nowhere: no onset in this record
            shape = effect.force(np.zeros_like(x_s), params, x_s, p, unit)
            shape = shape - basis @ (basis.T @ shape)
            norm2 = float(shape @ shape)
            if norm2 <= 0.0:
                continue
            k_b = min(max(float(shape @ residual) / norm2, 0.0), k_max)
            improvement = (2.0 * k_b * float(shape @ residual) - k_b ** 2 * norm2)
            onsets.append(Onset(x_cr, p_cr, k_max * np.sqrt(norm2) / force_scale, k_b,
                                improvement / force_scale ** 2))
    onsets.sort(key=lambda o: -o.improvement)
    return onsets


def identifiability(record, params, scales, standing=()):
    """
    Why this record cannot show each cause: {cause: reason or None}, as its effect is judged.

    No span of pressure, compression or time is assumed; the question is what the strongest
    effect the physical bounds allow would change in this record beyond what the baseline's own
    parameters absorb, in (averaged) noise floors, against `DETECTABLE`:
    - 'onset' (buckling): at every onset the record reaches (`buckling_profile`);
    - 'profile': each parameter profiled across its range (`PROFILE_POINTS` values, the others
      at their start), the baseline's Jacobian (p_ref, V_tube, the encoder's zero; the force's
      linear terms are refitted inside every prediction) projected out (`_detectable`);
    - 'structure': the effect's own condition (backlash: a chamber that never reverses turns a
      play into a constant offset, which the encoder's zero is).
    `standing`: the model's own physics the baseline keeps (module docstring).
    """
    reasons = {}
    for effect in EFFECTS:
        if effect.judged_by == 'structure':
            reasons[effect.name] = effect.structural_reason(record)
        elif effect.judged_by == 'onset':
            reasons[effect.name] = _onset_reason(record, params, scales, standing, effect)
        else:
            size, where = _detectable(record, params, scales, effect.name, standing)
            reasons[effect.name] = None if size >= DETECTABLE else (
                f'the strongest {effect.name.replace("_", " ")} within its physical range '
                f'({where}) would change pressure and force by at most {size:.1f} noise floors '
                f"beyond what the baseline's p_ref, V_tube and encoder zero absorb (needs "
                f'{DETECTABLE:g})')
    return reasons


def _onset_reason(record, params, scales, standing, effect):
    """Why `record` cannot show `effect` at any onset it reaches (`buckling_profile`), or None."""
    onsets = buckling_profile(record, params, scales['f'], standing, effect)
    best = max((o.detectable for o in onsets), default=0.0)
    if best >= DETECTABLE:
        return None
    k_max = 10.0 ** effect.fit_variables(params)[0].upper
    x_s, gauge = 1e3 * record['x_s'], (record['p'] - P_ATM) / 1e3
    return ('at every onset within the bounds that the record reaches (spring '
            f'{x_s.min():.1f}-{x_s.max():.1f} mm, {gauge.min():.1f}-{gauge.max():.1f} kPa gauge; '
            f'{len(onsets)} of {PROFILE_COMPRESSIONS * PROFILE_PRESSURES} onsets), the strongest '
            f'buckling (k_b {k_max:.0f} kN/m) would change the force by at most {best:.1f} '
            f'noise floors beyond what the material force absorbs (needs {DETECTABLE:g})')


def _detectable(record, params, scales, cause, standing=()):
    """
    Largest change `cause` can make beyond the baseline's parameters: (noise floors, where).

    Each of the cause's parameters is set to `PROFILE_POINTS` values across its bounds (the others
    at their start); the baseline's prediction at its initial guess and its Jacobian in its own
    parameters are projected out of the change. Outputs are in noise floors, so the norm of what
    is left is the chi-square an ideal fit would gain: the Fisher information of the strongest
    effect, not a rule drawn around one device.
    """
    everything = np.ones(len(record), bool)
    base = build_model(record, params, (), scales=scales, standing=standing)
    extended = build_model(record, params, (cause,), scales=scales, standing=standing)
    theta = np.asarray(base.x0, float)
    y0, jacobian = baseline_directions(base, len(record))
    best, where = 0.0, ''
    variables = fit_variables(cause, params)
    start = [v.start for v in variables]
    for k, (name, _, low, high) in enumerate(variables):
        for value in np.linspace(low, high, PROFILE_POINTS):
            trial = list(start)
            trial[k] = value
            prediction = extended.predict(np.concatenate([theta, trial]), everything)[0].ravel()
            if not np.all(np.abs(prediction) < 1e8):
                continue    # no pressure root at this extreme: says nothing about the record
            size = float(np.linalg.norm(beyond_baseline(prediction - y0, jacobian)))
            if size > best:
                best, where = size, f'{name} {value:.3g}'
    return best, where


def baseline_directions(base, rows):
    """
    Return the baseline's prediction at its start and its Jacobian in its own parameters.

    `base`: `build_model(record, params, ())` on a record of `rows` rows (the force's linear
    terms refitted on all of them). Returns (y0, jacobian): y0 the flattened outputs
    (noise floors), one Jacobian column per baseline parameter (p_ref, V_tube, the encoder's
    zero; the force's linear terms are refitted inside every prediction), by forward differences
    of 1e-3 of each parameter's range.
    """
    everything = np.ones(rows, bool)
    theta = np.asarray(base.x0, float)
    y0 = base.predict(theta, everything)[0].ravel()
    columns = []
    for k, (low, high) in enumerate(zip(base.lower, base.upper)):
        step = 1e-3 * (high - low)
        shifted = theta.copy()
        shifted[k] += step
        columns.append((base.predict(shifted, everything)[0].ravel() - y0) / step)
    return y0, np.column_stack(columns)


def beyond_baseline(change, jacobian):
    """Return what is left of `change` (flattened outputs) beyond the baseline's `jacobian`."""
    coef, *_ = np.linalg.lstsq(jacobian, change, rcond=None)
    return change - jacobian @ coef


def noise_floors(record):
    """
    Return the white-noise floor of each output at the record's rate: {column: sigma}.

    The force is ramped fast by the test machine, so its floor comes from second differences. A
    noise-free column (simulated) gets a floor of 1e-6 of its span (`scoring.guarded_floor`).
    """
    floors = {'p': noise_floor(record['p']), 'f': noise_floor_ramps(record['f'])}
    return {name: guarded_floor(value, record[name]) for name, value in floors.items()}


def measured(record, scales):
    """Return the measured outputs, a row each, over their (averaged) noise floors `scales`."""
    return np.vstack([record[name] / scales[name] for name, *_ in OUTPUTS])


def initial_guess(record, params):
    """Start of the baseline fit: p_ref from the mean measured P·V at the nominal v_tube."""
    base = without_bulging(params)   # geometric volumes (4): the pressure argument is unused
    v = total_volume(base, record['x_c'], record['x_s'], P_ATM)
    v_ref = total_volume(base, base.x_c_ref, 0.0, P_ATM)
    return {'p_ref_kpa': float(np.mean(record['p'] * v) / v_ref / 1e3),
            'v_tube_ml': base.v_tube / ML,
            'x_c_offset_mm': 0.0}


def geometric_volumes(params, x_c, x_s):
    """
    Compute V_geo,c(x_c), V_geo,s(x_s) (arrays) (4), m³.

    Everything of the volume that the fitted parameters do not change, computed once per record.
    """
    return volume_geo(params.chamber, x_c), volume_geo(params.spring, x_s)


def predict(params, causes, values, x_c, x_s, dt, geometry=None, standing=()):
    """Pressure the extended model predicts at the sensor (Pa) over a record (`predict_state`)."""
    return predict_state(params, causes, values, x_c, x_s, dt, geometry, standing)[0]


def predict_state(params, causes, values, x_c, x_s, dt, geometry=None, standing=()):
    """
    Pressure at the sensor and in the gas (Pa) the extended model predicts over a record.

    `values`: physical parameters {cause: {name: value}} plus 'baseline': {'p_ref', 'v_tube',
    'x_c_offset' (optional, m)}; `geometry`: `geometric_volumes(params, x_c, x_s)` if already
    computed (for the encoder's x_c; the chamber's volume is recomputed when the offset is not 0).
    Only the inputs x_c, x_s enter: no measured pressure, so nothing of the held-out output leaks
    in. `standing`: the model's own physics kept (module docstring; E_V here).
    """
    model = _gas_model(params, causes, values, standing)
    effects = [BY_NAME[cause] for cause in causes]
    v_c, v_s = geometry or geometric_volumes(params, x_c, x_s)
    offset = values['baseline'].get('x_c_offset', 0.0)
    plate = x_c + offset if offset else x_c
    for effect in effects:
        plate = effect.plate(plate, values[effect.name])
    if plate is not x_c:
        v_c = volume_geo(params.chamber, plate)
    volume = v_c + v_s + model.v_tube
    n0 = gas_amount(model, model.p_ref)   # N = P V of the sealed gas (17)
    temperature = np.ones(len(x_c))   # over ambient
    for effect in effects:
        temperature = effect.temperature(temperature, volume, dt, values[effect.name])
    amount = np.ones(len(x_c))        # over the sealed amount
    for effect in effects:
        amount = effect.amount(amount, temperature, volume, dt, values[effect.name], n0)
    p = p_gas = pressure_of_amount(model, plate, x_s, n0 * temperature * amount, v_geo=volume)
    for effect in effects:
        p = effect.sensor(p, dt, values[effect.name])
    return p, p_gas


def _kept(params, standing):
    """Return `params` without the standing physics that is not kept (`standing`)."""
    for effect in EFFECTS:
        if effect.standing and effect.name not in standing:
            params = effect.model_params(params, None)
    return params


def _volume_model(params, causes, values, standing=()):
    """
    Return `params` with the volumes of the causes (E_V).

    The model's own physics where it is `standing` and not a cause; else none.
    """
    model = _kept(params, standing)
    for cause in causes:
        model = BY_NAME[cause].volumes(model, values[cause])
    return model


def _gas_model(params, causes, values, standing=()):
    """Return `_volume_model` with the baseline's gas and tube."""
    base = values['baseline']
    return dataclasses.replace(_volume_model(params, causes, values, standing),
                               p_ref=base['p_ref'], v_tube=base['v_tube'])


def force_columns(params, causes, values, x_s, p_gas, standing=()):
    """
    Return the force the model knows, (7)-(10) (+ buckling), and the material force's columns.

    The columns of the linear material force: 1 (load cell zero), x_s .. x_s^3 (F_MTS), E_F's
    shape exp(C2 (P - P_atm) + C3 Δh) (11), C1 being its coefficient. A `standing` E_V or
    buckling that is not a cause is the model's own.
    """
    model = _volume_model(params, causes, values, standing)
    known = air_force(model, x_s, p_gas)[0]                          # (9), (10)
    for effect in EFFECTS:
        if effect.name in causes:
            known = effect.force(known, params, x_s, p_gas, values[effect.name])
        elif effect.name in standing:
            known = effect.force(known, params, x_s, p_gas, None)
    _, c2, c3, _ = params.e_f
    # A trial step of the fit may predict any pressure: the exponent of E_F stays finite within
    # the range the data checks accept.
    shape = force_error((1.0, c2, c3, -c2 * P_ATM), params.spring.n, x_s,
                        np.clip(p_gas, 0.0, 2e6), np.exp)[0]
    columns = [np.ones_like(x_s)] + material_terms(x_s, F_MTS_DEGREE) + [shape]
    return known, np.column_stack(columns)


def solve_force(known, columns, f, train):
    """Least-squares coefficients of the material force on the `train` rows (columns scaled)."""
    scale = np.sqrt(np.mean(columns ** 2, axis=0))
    scale[scale == 0.0] = 1.0
    coef, *_ = np.linalg.lstsq(columns[train] / scale, (f - known)[train], rcond=None)
    return coef / scale


def physical(causes, theta):
    """Scaled fit variables -> physical parameters {part: {name: SI value}}."""
    values, k = {}, 0
    for part in ('baseline',) + tuple(causes):
        raw = {}
        for name, *_ in fit_variables(part, None):  # the names and order, whatever the bounds
            raw[name] = float(theta[k])
            k += 1
        values[part] = (_baseline_si(raw) if part == 'baseline' else BY_NAME[part].to_si(raw))
    return values


def _baseline_si(raw):
    return {'p_ref': raw['p_ref_kpa'] * 1e3, 'v_tube': raw['v_tube_ml'] * ML,
            'x_c_offset': raw['x_c_offset_mm'] * 1e-3}


def build_model(record, params, causes, warm=None, scales=None, standing=()):
    """
    Build the baseline plus `causes` on `record` as a `scoring.Model`.

    The model is fitted to the measured outputs (`measured(record, scales)`: pressure and force,
    each over its noise floor in `scales`).

    `warm` ({fit variable: value}) starts the fit from an earlier model's solution. `standing`:
    the model's own physics the baseline keeps (module docstring); a standing buckling that is a
    cause starts at the model's values.
    """
    causes = tuple(causes)
    standing = tuple(standing)
    names, x0, lower, upper = [], [], [], []
    guess = initial_guess(record, params)
    for part in ('baseline',) + causes:
        own = BY_NAME[part].own_start(params) if part in standing else {}
        for name, start, lo, hi in fit_variables(part, params):
            key = f'{part}.{name}'
            names.append(key)
            if warm and key in warm:
                start = warm[key]
            elif part == 'baseline':
                start = guess[name]
            elif name in own:
                start = _off_edges(own[name], lo, hi)
            x0.append(start)
            lower.append(lo)
            upper.append(hi)
    starts = []
    if causes:
        last = BY_NAME[causes[-1]]
        width = len(last.fit)
        alternatives = last.starts
        if last.judged_by == 'onset':
            alternatives = _profile_starts(record, params, scales, standing, last)
        for alternative in alternatives:
            starts.append(x0[:-width] + list(alternative))
        if warm:
            # A cold start too: an earlier model may have bent v_tube to mimic the missing effect.
            cold = [guess[name] for name, *_ in BASELINE_FIT]
            starts.append(cold + x0[len(cold):])
    x_c, x_s, dt, f = record['x_c'], record['x_s'], record.dt, record['f']
    geometry = geometric_volumes(params, x_c, x_s)
    scales = scales or {name: 1.0 for name, *_ in OUTPUTS}

    def run(theta, train):
        values = physical(causes, theta)
        try:
            p, p_gas = predict_state(params, causes, values, x_c, x_s, dt, geometry, standing)
        except ParameterError:
            # E_V so large that (17) has no positive root: a trial step of the fit, far off.
            return np.full((2, len(x_s)), 1e9), {'force': np.zeros(F_MTS_DEGREE + 2)}
        known, columns = force_columns(params, causes, values, x_s, p_gas, standing)
        coef = solve_force(known, columns, f, train)
        force = known + columns @ coef
        return np.vstack([p / scales['p'], force / scales['f']]), {'force': coef}

    def report(theta, linear):
        values = physical(causes, theta)
        coef = linear.get('force')
        if coef is not None:
            values['baseline'].update(force_zero=float(coef[0]), e_f_c1=float(coef[-1]),
                                      f_mts=[float(c) for c in coef[1:-1]])
        return values

    return Model(causes, names, x0, lower, upper, run, report,
                 n_linear=F_MTS_DEGREE + 2, starts=starts)


def _profile_starts(record, params, scales, standing, effect):
    """Return the onset fit's starts: the best onsets of `buckling_profile` (scaled)."""
    variables = effect.fit_variables(params)
    k_max = effect.to_si({v.name: v.upper for v in variables})['stiffness_loss']
    force_scale = (scales or {}).get('f') or noise_floors(record)['f']
    starts = []
    for onset in buckling_profile(record, params, force_scale, standing,
                                  effect)[:PROFILE_STARTS]:
        start = effect.from_si({'stiffness_loss': onset.stiffness_loss or 0.25 * k_max,
                                'critical_pressure': onset.critical_pressure,
                                'critical_compression': onset.critical_compression})
        starts.append([_off_edges(start[name], low, high) for name, _, low, high in variables])
    return starts


def _off_edges(value, low, high):
    """Return `value` inside [low, high], 1 % of the range off its edges (trf keeps an edge)."""
    return min(max(value, low + 0.01 * (high - low)), high - 0.01 * (high - low))


def extended_flat(config, causes, values, standing=()):
    """
    Return the flat ROS 2 parameters of the extended model (for `params.write_file`).

    `config`: the `ActuatorConfig` diagnosed (model and plant: the file is complete).

    The refitted gas and tube, E_V if wall bulging pays, and the fitted effect parameters under
    `actuator.effects.*` (read by `bellows simulate actuator --effect NAME` and the plant).
    """
    params = config.model
    base = values['baseline']
    model = dataclasses.replace(params, p_ref=base['p_ref'], v_tube=base['v_tube'])
    # The model's own E_V and buckling stay where they are standing physics (`standing`).
    model = _kept(model, standing)
    if 'f_mts' in base:
        model = dataclasses.replace(model, f_mts=tuple(base['f_mts']),
                                    e_f=(base['e_f_c1'], params.e_f[1], params.e_f[2],
                                         -params.e_f[1] * P_ATM))
    for cause in causes:
        model = BY_NAME[cause].extended(model, params, values[cause])
    flat = params_to_flat(model, config.plant)
    for cause in causes:
        for key, value in BY_NAME[cause].flat(values[cause]).items():
            flat[f'actuator.effects.{cause}.{key}'] = value
    return flat
