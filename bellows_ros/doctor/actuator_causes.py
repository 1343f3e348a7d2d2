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

Each cause adds the missing physics with its own parameters (docs/doctor.md, config/actuator.yaml
`actuator.effects`):
- air_leak: volume flow C (P - P_atm) out of the sealed gas; the gas amount N = P V then follows
  dN/dt = -C P (P - P_atm) (isothermal outflow at the chamber pressure).
- heat_exchange: polytropic compression with heat capacity ratio γ and first-order relaxation of
  the gas temperature to ambient with time constant τ_th ≥ 0.1 s (heat through silicone walls into
  ~0.1 L of air is slow; a faster "relaxation" would only mimic a sensor lag):
  d ln T/dt = -(γ - 1) d ln V/dt - (ln T - ln T_a)/τ_th (linearised in T/T_a - 1).
- wall_bulging: paper B's augmented volume (5, 6), V = V_geo + E_V(Δh, P), with the terms of the
  full cubic that a pressure record can separate: q, d q (both bellows) and d² (both bellows).
- sensor_lag: the pressure sensor as a first-order lag with time constant τ.
- backlash: a dead band of width b between the lead screw (the encoder's x_c) and the chamber.
- buckling: the spring loses force once its load index x_s/x_cr + (P - P_atm)/p_cr passes 1
  (`models.actuator.buckling_force`): stiffness loss k_b, critical pressure p_cr, critical
  compression x_cr, within the physical bounds of `actuator.buckling.bounds` (onset width from the
  YAML): the onset from ambient pressure and the start of the travel to where the other variable
  alone sets it, fitted in decades.

Every bound is derived (docs/doctor.md, "Where every range comes from"), and what a fit pinned at
each means is `EDGES`: a limit of the physics is a finding, the others say why it is not named.

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
from bellows_ros.doctor.filters import lag, play, recurrence, relax
from bellows_ros.doctor.scoring import guarded_floor, Model, noise_floor, noise_floor_ramps
from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator import (air_force, Buckling, buckling_force, force_error,
                                         gas_amount, material_terms, NO_BUCKLING,
                                         pressure_of_amount, total_volume, without_buckling,
                                         without_bulging)
from bellows_ros.models.actuator_geometry import P_ATM, volume_geo

CAUSES = ('air_leak', 'heat_exchange', 'wall_bulging', 'sensor_lag', 'backlash', 'buckling')
# What a record must hold to decide each cause when it came closest but did not pay (report.md).
DECIDING_DATA = {
    'air_leak': 'long holds (tens of s) with the pressure well away from ambient',
    'heat_exchange': 'fast chamber steps followed by holds of several seconds',
    'wall_bulging': 'sealed runs at several gas amounts over a wide pressure range',
    'sensor_lag': 'fast chamber steps sampled at >= 10 x 1/tau',
    'backlash': 'the chamber reversing often by more than the play',
    'buckling': 'the spring cycled past the fitted onset at several pressures (gas amounts)',
}
BASELINE = ('paper B (17): geometric volume (no E_V), isothermal sealed gas, '
            'p_ref and v_tube refitted; force (7)-(12) on the predicted pressure, F_MTS a cubic '
            'in x_s and E_F amplitude refitted, no buckling')
# Physics of the model that a baseline may keep at the model's own values (module docstring).
STANDING = ('wall_bulging', 'buckling')
# Measured outputs: (column, unit, name). The first is the legacy single output.
OUTPUTS = (('p', 'Pa', 'pressure'), ('f', 'N', 'force'))
F_MTS_DEGREE = 3
# Hz, highest rate the doctor fits at: sensor lag and heating act within tens of ms
FIT_RATE = 200.0
UNIT = 'Pa'
SIGNAL = 'p'
ML = 1e-6  # m³ per mL: volumes are fitted in mL so that all parameters are O(1)

# Nonlinear parameters of each part: (name, start, lower, upper), other starts for multi-start.
SPECS = {
    # x_c_offset: the plate sits at x_c + offset. Without it a constant nut-plate offset (backlash
    # in a record whose chamber never reverses) is taken up by the most flexible candidate (E_V).
    'baseline': [('p_ref_kpa', 101.325, 20.0, 500.0), ('v_tube_ml', 20.0, 0.0, 400.0),
                 ('x_c_offset_mm', 0.0, -1.0, 1.0)],
    'air_leak': [('log10_conductance', -11.0, -15.0, -7.0)],
    'heat_exchange': [('log10_time_constant', 0.0, -1.0, 2.5), ('gamma', 1.4, 1.0, 1.67)],
    'wall_bulging': [('e_q_ml', 0.0, -200.0, 200.0), ('e_dq_chamber_ml', 0.0, -200.0, 200.0),
                     ('e_dq_spring_ml', 0.0, -200.0, 200.0),
                     ('e_dd_chamber_ml', 0.0, -200.0, 200.0),
                     ('e_dd_spring_ml', 0.0, -200.0, 200.0)],
    'sensor_lag': [('log10_time_constant', -1.5, -3.5, 0.5)],
    'backlash': [('width_mm', 0.3, 0.0, 3.0)],
    # Bounds from actuator.buckling.bounds (`buckling_specs`); these are the fallbacks, the same
    # physical ranges (docs/doctor.md, "Where every range comes from"). The onset is fitted in
    # decades: its physical range spans four of them, from an onset at ambient pressure (p_cr
    # 0.1 kPa) or at the start of the travel (x_cr 0.1 mm) to one the other variable alone sets.
    # k_b too: at such an onset the loss in the pressure, k_b x_cr / p_cr per Pa, is newtons
    # per kPa with k_b of a few N/m, where a spring that carries tens of newtons ends.
    'buckling': [('log10_stiffness_loss_kn', 0.3, -5.0, 1.23),
                 ('log10_critical_pressure_kpa', 1.4, -1.0, 3.04),
                 ('log10_critical_compression_mm', 1.3, -1.0, 3.0)],
}
# What a fit pinned at each bound means (`edge_kind`): 'limit', the bound is a limiting case of
# the physics that a device can be in (a finding: stated, and the cause named when it pays);
# 'absent', the effect vanishes there (it cannot pay); 'bound', a physical bound that the effect
# cannot pass (pinned there, the cause absorbs some other error); 'range', a bound set for the
# fit, not by physics (pinned there, the range is wrong). (cause, fit variable, side) -> (kind,
# what it means); a bound not listed is 'range'. The numbers' sources: docs/doctor.md.
EDGES = {
    ('air_leak', 'log10_conductance', 'lower'): (
        'absent', 'no leak: the gas would take > 10^5 s to escape a 0.1 L chamber'),
    ('air_leak', 'log10_conductance', 'upper'): (
        'limit', 'the chamber is vented: its gas reaches ambient within ~10 ms, a fit sample'),
    ('heat_exchange', 'log10_time_constant', 'lower'): (
        'range', 'set so that heat exchange is not a second sensor lag, not by the walls'),
    ('heat_exchange', 'log10_time_constant', 'upper'): (
        'limit', 'adiabatic gas: no heat crosses the walls within the record'),
    ('heat_exchange', 'gamma', 'lower'): ('absent', 'isothermal gas (gamma 1)'),
    ('heat_exchange', 'gamma', 'upper'): ('bound', 'a monatomic gas (5/3); air is 1.4'),
    ('sensor_lag', 'log10_time_constant', 'lower'): (
        'absent', 'no lag: 0.3 ms is below the fastest sample (1 ms)'),
    ('sensor_lag', 'log10_time_constant', 'upper'): (
        'bound', 'a 3 s pressure reading: slower than any sensor behind a tube of a rig'),
    ('backlash', 'width_mm', 'lower'): ('absent', 'no play'),
    ('backlash', 'width_mm', 'upper'): (
        'bound', 'a play of more than two turns of the lead screw (1.27 mm lead)'),
    ('buckling', 'log10_stiffness_loss_kn', 'lower'): (
        'absent', 'no buckling: a stiffness loss of 0.01 N/m, 0.4 mN over the whole travel'),
    ('buckling', 'log10_stiffness_loss_kn', 'upper'): (
        'bound', "the axial stiffness of the spring's straight wall tube: no loss is larger"),
    ('buckling', 'log10_critical_pressure_kpa', 'lower'): (
        'limit', 'the onset lies at ambient pressure: the spring buckles as soon as the gas is '
                 'above ambient, compressed or not (buckling from the start of the record '
                 'wherever it is above ambient)'),
    ('buckling', 'log10_critical_pressure_kpa', 'upper'): (
        'limit', 'the pressure does not move the onset: the compression alone sets it'),
    ('buckling', 'log10_critical_compression_mm', 'lower'): (
        'limit', 'the onset lies at the start of the travel: the spring is buckled from the '
                 'start of the record wherever it is compressed'),
    ('buckling', 'log10_critical_compression_mm', 'upper'): (
        'limit', 'the compression does not move the onset: the pressure alone sets it'),
}
for _name in ('e_q_ml', 'e_dq_chamber_ml', 'e_dq_spring_ml', 'e_dd_chamber_ml', 'e_dd_spring_ml'):
    for _side in ('lower', 'upper'):
        EDGES['wall_bulging', _name, _side] = (
            'bound', "a bulge larger than the bellows' own volume over the range of a record")
STARTS = {
    'air_leak': [[-9.5], [-12.5]],
    'heat_exchange': [[-0.7, 1.4], [1.3, 1.4]],
    'sensor_lag': [[-2.5], [-0.5]],
    'backlash': [[1.0], [0.05]],
    'wall_bulging': [],
    'buckling': [],   # from the record: `buckling_profile`
}
# Buckling's onset profile (`buckling_profile`): onsets on a grid over the bounds, kept where the
# record's rows reach them; the best PROFILE_STARTS of them start the fit.
# Four decades each (`SPECS['buckling']`): about 2.3 onsets per octave of x_cr, 1.5 of p_cr.
PROFILE_COMPRESSIONS = 28
PROFILE_PRESSURES = 18
PROFILE_STARTS = 3
# The strongest buckling the bounds allow must change the force by at least this many (averaged)
# noise floors, in the least-squares sense and beyond what the material force absorbs, at some
# onset the record reaches; else the record cannot show buckling (a chi-square of 25 on one added
# parameter: far beyond chance, yet any real effect the held-out rule would name clears it).
DETECTABLE = 5.0
# Values of each parameter across its bounds at which `_detectable` profiles a cause.
PROFILE_POINTS = 5
# SI factor of each scaled buckling variable.
# The onset's variables are fitted as log10 of the scaled value (`_LOG`).
_BUCKLING_SI = {'log10_stiffness_loss_kn': ('stiffness_loss', 1e3),
                'log10_critical_pressure_kpa': ('critical_pressure', 1e3),
                'log10_critical_compression_mm': ('critical_compression', 1e-3)}
_LOG = ('log10_stiffness_loss_kn', 'log10_critical_pressure_kpa', 'log10_critical_compression_mm')
# The smallest stiffness loss fitted, N/m (`SPECS`: 1e-5 kN/m); the YAML's lower bound 0 is no
# buckling, which a fit in decades reaches as this.
K_B_FLOOR = 0.01


def edge_kind(cause, name, side):
    """(kind, meaning) of `cause`'s fit variable `name` pinned at its `side` bound (`EDGES`)."""
    return EDGES.get((cause, name, side), ('range', 'a bound of the fit, not of physics'))


def standing_physics(params):
    """Return the part of `STANDING` that `params` holds (E_V not zero, a spring that buckles)."""
    held = {'wall_bulging': params.chamber.bulging or params.spring.bulging,
            'buckling': params.buckling is not NO_BUCKLING
            and params.buckling.stiffness_loss > 0.0}
    return tuple(name for name in STANDING if held[name])


def baseline_name(standing=()):
    """`BASELINE`, with the model's own physics that it keeps (`standing`) said."""
    name = BASELINE
    if 'wall_bulging' in standing:
        name = name.replace('geometric volume (no E_V)', "the model's own E_V")
    if 'buckling' in standing:
        name = name.replace('no buckling', "the model's own buckling")
    return name


def buckling_specs(params):
    """SPECS['buckling'] with the bounds of `actuator.buckling.bounds` where the YAML has them."""
    specs = []
    bounds = dict(params.buckling.bounds) if params.buckling is not None else {}
    for name, start, low, high in SPECS['buckling']:
        si, factor = _BUCKLING_SI[name]
        if si in bounds:
            if name in _LOG:
                floor = K_B_FLOOR if si == 'stiffness_loss' else 1e-12
                low, high = (float(np.log10(max(v, floor) / factor)) for v in bounds[si])
            else:
                low, high = (max(v / factor, 0.0) for v in bounds[si])
        specs.append((name, min(max(start, low), high), low, high))
    return specs


def _onset_width(params):
    return params.buckling.onset_width if params.buckling is not None else 0.15


@dataclasses.dataclass
class Onset:
    """One onset of the buckling profile: where it lies and what the record can show of it."""

    critical_compression: float   # x_cr, m
    critical_pressure: float      # p_cr, Pa
    detectable: float             # the strongest k_b's force change beyond F_mat, noise floors
    stiffness_loss: float         # k_b, N/m, that fits the record best at this onset (>= 0)
    improvement: float            # the fall of the force's squared error (noise floors²)


def buckling_profile(record, params, force_scale, standing=()):
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
    """
    specs = {name: (low, high) for name, _, low, high in buckling_specs(params)}
    k_max = 10.0 ** specs['log10_stiffness_loss_kn'][1] * 1e3
    x_s, p, f = record['x_s'], record['p'], record['f']
    kept = tuple(name for name in standing if name != 'buckling')
    known, columns = force_columns(params, (), {}, x_s, p, kept)
    basis, _ = np.linalg.qr(columns / np.sqrt(np.mean(columns ** 2, axis=0) + 1e-300))
    residual = f - known
    residual = residual - basis @ (basis.T @ residual)
    width = _onset_width(params)
    gauge = p - P_ATM
    onsets = []
    compressions = np.logspace(*specs['log10_critical_compression_mm'], PROFILE_COMPRESSIONS)
    pressures = np.logspace(*specs['log10_critical_pressure_kpa'], PROFILE_PRESSURES)
    for x_cr in compressions * 1e-3:
        for p_cr in pressures * 1e3:
            load = x_s / x_cr + gauge / p_cr
            if not (load.max() > 1.0 and load.min() < 1.0):
                continue    # buckled everywhere or nowhere: no onset in this record
            shape = buckling_force(Buckling(1.0, p_cr, x_cr, width), x_s, p, np.exp)[0]
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
    Why this record cannot show each model-based cause: {cause: reason or None}.

    No span of pressure, compression or time is assumed; the question is what the strongest
    effect the physical bounds allow would change in this record beyond what the baseline's own
    parameters absorb, in (averaged) noise floors, against `DETECTABLE`:
    - buckling: at every onset the record reaches (`buckling_profile`);
    - the gas and sensor causes: each parameter profiled across its range (`PROFILE_POINTS`
      values, the others at their start), the baseline's Jacobian (p_ref, V_tube, the encoder's
      zero; the force's linear terms are refitted inside every prediction) projected out
      (`_detectable`).
    Backlash keeps its structural condition (`checks.identifiability`): a chamber that never
    reverses turns a play into a constant offset, which the encoder's zero is.
    `standing`: the model's own physics the baseline keeps (module docstring).
    """
    onsets = buckling_profile(record, params, scales['f'], standing)
    best = max((o.detectable for o in onsets), default=0.0)
    reasons = {'buckling': None}
    if best < DETECTABLE:
        k_max = 10.0 ** buckling_specs(params)[0][3]
        x_s, gauge = 1e3 * record['x_s'], (record['p'] - P_ATM) / 1e3
        reasons['buckling'] = (
            'at every onset within the bounds that the record reaches (spring '
            f'{x_s.min():.1f}-{x_s.max():.1f} mm, {gauge.min():.1f}-{gauge.max():.1f} kPa gauge; '
            f'{len(onsets)} of {PROFILE_COMPRESSIONS * PROFILE_PRESSURES} onsets), the strongest '
            f'buckling (k_b {k_max:.0f} kN/m) would change the force by at most {best:.1f} '
            f'noise floors beyond what the material force absorbs (needs {DETECTABLE:g})')
    for cause in ('air_leak', 'heat_exchange', 'wall_bulging', 'sensor_lag'):
        size, where = _detectable(record, params, scales, cause, standing)
        reasons[cause] = None if size >= DETECTABLE else (
            f'the strongest {cause.replace("_", " ")} within its physical range ({where}) would '
            f'change pressure and force by at most {size:.1f} noise floors beyond what the '
            f"baseline's p_ref, V_tube and encoder zero absorb (needs {DETECTABLE:g})")
    return reasons


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
    start = [spec[1] for spec in SPECS[cause]]
    for k, (name, _, low, high) in enumerate(SPECS[cause]):
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


def bulged(params, e):
    """
    `params` with the fitted E_V terms (m³) placed in both bellows' coefficient vectors (5).

    `e`: the physical parameters of `wall_bulging` ({'e_q': ..., 'e_dd_spring': ...}, m³).
    """
    e_q, e_dq_c, e_dq_s, e_dd_c, e_dd_s = (e['e_q'], e['e_dq_chamber'], e['e_dq_spring'],
                                           e['e_dd_chamber'], e['e_dd_spring'])
    chamber = [0.0] * 10
    spring = [0.0] * 10
    chamber[2], chamber[4], chamber[3] = e_q, e_dq_c, e_dd_c   # a01, a11, a20 of (5)
    spring[4], spring[3] = e_dq_s, e_dd_s
    return dataclasses.replace(params,
                               chamber=dataclasses.replace(params.chamber, e_v=tuple(chamber)),
                               spring=dataclasses.replace(params.spring, e_v=tuple(spring)))


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
    v_c, v_s = geometry or geometric_volumes(params, x_c, x_s)
    offset = values['baseline'].get('x_c_offset', 0.0)
    if offset or 'backlash' in causes:
        x_c = x_c + offset
        if 'backlash' in causes:
            x_c = play(x_c, values['backlash']['width'])
        v_c = volume_geo(params.chamber, x_c)
    volume = v_c + v_s + model.v_tube
    n0 = gas_amount(model, model.p_ref)   # N = P V of the sealed gas (17)
    gas = np.ones(len(x_c))  # gas amount (times temperature), relative to the sealed amount
    if 'heat_exchange' in causes or 'air_leak' in causes:
        temperature = np.ones(len(x_c))
        if 'heat_exchange' in causes:
            h = values['heat_exchange']
            temperature = np.exp(relax(-(h['gamma'] - 1.0) * np.log(volume), dt,
                                       h['time_constant']))
        gas = temperature
        if 'air_leak' in causes:
            # N_{k+1} = N_k - dt C P_k (N_k T_k / V_k - P_atm), with N relative to N_0; the flow's
            # pressure factor P_k is taken from the sealed gas (second order in the leak).
            flow = dt * values['air_leak']['conductance'] * n0 * temperature / volume
            amount = recurrence(1.0 - flow * temperature / volume, flow * P_ATM / n0, 1.0)
            gas = temperature * amount
    p = pressure_of_amount(model, x_c, x_s, n0 * gas, v_geo=volume)
    p_gas = p
    if 'sensor_lag' in causes:
        p = lag(p, dt, values['sensor_lag']['time_constant'])
    return p, p_gas


def _kept(params, standing):
    """Return `params` with E_V zero unless it is standing physics (`standing`)."""
    return params if 'wall_bulging' in standing else without_bulging(params)


def _gas_model(params, causes, values, standing=()):
    """
    Return `params` with the baseline's gas and tube, and the fitted E_V if it is a cause.

    The model's own E_V if it is `standing` and not a cause; else the geometric volume.
    """
    base = values['baseline']
    model = dataclasses.replace(_kept(params, standing), p_ref=base['p_ref'],
                                v_tube=base['v_tube'])
    if 'wall_bulging' in causes:
        model = bulged(model, values['wall_bulging'])
    return model


def force_columns(params, causes, values, x_s, p_gas, standing=()):
    """
    Return the force the model knows, (7)-(10) (+ buckling), and the material force's columns.

    The columns of the linear material force: 1 (load cell zero), x_s .. x_s^3 (F_MTS), E_F's
    shape exp(C2 (P - P_atm) + C3 Δh) (11), C1 being its coefficient. A `standing` E_V or
    buckling that is not a cause is the model's own.
    """
    model = (bulged(params, values['wall_bulging']) if 'wall_bulging' in causes
             else _kept(params, standing))
    known = air_force(model, x_s, p_gas)[0]                          # (9), (10)
    if 'buckling' in causes:
        b = values['buckling']
        known = known + buckling_force(Buckling(b['stiffness_loss'], b['critical_pressure'],
                                                b['critical_compression'], _onset_width(params)),
                                       x_s, p_gas, np.exp)[0]
    elif 'buckling' in standing:
        known = known + buckling_force(params.buckling, x_s, p_gas, np.exp)[0]
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
        for name, *_ in SPECS[part]:  # buckling_specs keep these names and order
            raw[name] = float(theta[k])
            k += 1
        values[part] = _to_si(part, raw)
    return values


def _to_si(part, raw):
    if part == 'baseline':
        return {'p_ref': raw['p_ref_kpa'] * 1e3, 'v_tube': raw['v_tube_ml'] * ML,
                'x_c_offset': raw['x_c_offset_mm'] * 1e-3}
    if part == 'air_leak':
        return {'conductance': 10.0 ** raw['log10_conductance']}
    if part in ('heat_exchange', 'sensor_lag'):
        out = {'time_constant': 10.0 ** raw['log10_time_constant']}
        if part == 'heat_exchange':
            out['gamma'] = raw['gamma']
        return out
    if part == 'backlash':
        return {'width': raw['width_mm'] * 1e-3}
    if part == 'buckling':
        return {_BUCKLING_SI[name][0]: (10.0 ** value if name in _LOG else value)
                * _BUCKLING_SI[name][1] for name, value in raw.items()}
    return {name[:-3]: value * ML for name, value in raw.items()}  # wall_bulging, m³


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
    own = _own_buckling(params) if 'buckling' in standing else {}
    names, x0, lower, upper = [], [], [], []
    guess = initial_guess(record, params)
    for part in ('baseline',) + causes:
        for name, start, lo, hi in (buckling_specs(params) if part == 'buckling' else SPECS[part]):
            key = f'{part}.{name}'
            names.append(key)
            if warm and key in warm:
                start = warm[key]
            elif part == 'baseline':
                start = guess[name]
            elif part == 'buckling' and name in own:
                start = min(max(own[name], lo + 0.01 * (hi - lo)), hi - 0.01 * (hi - lo))
            x0.append(start)
            lower.append(lo)
            upper.append(hi)
    starts = []
    if causes:
        width = len(SPECS[causes[-1]])
        alternatives = STARTS[causes[-1]]
        if causes[-1] == 'buckling':
            alternatives = _profile_starts(record, params, scales, standing)
        for alternative in alternatives:
            starts.append(x0[:-width] + list(alternative))
        if warm:
            # A cold start too: an earlier model may have bent v_tube to mimic the missing effect.
            cold = [guess[name] for name, *_ in SPECS['baseline']]
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


def _own_buckling(params):
    """Return the model's own buckling as the fit's scaled variables {name: value}."""
    b = params.buckling
    return {'log10_stiffness_loss_kn': float(np.log10(max(b.stiffness_loss, K_B_FLOOR) / 1e3)),
            'log10_critical_pressure_kpa': float(np.log10(b.critical_pressure / 1e3)),
            'log10_critical_compression_mm': float(np.log10(b.critical_compression * 1e3))}


def _profile_starts(record, params, scales, standing=()):
    """Return the buckling fit's starts: the best onsets of `buckling_profile` (scaled)."""
    specs = buckling_specs(params)
    force_scale = (scales or {}).get('f') or noise_floors(record)['f']
    starts = []
    for onset in buckling_profile(record, params, force_scale, standing)[:PROFILE_STARTS]:
        k_b = onset.stiffness_loss or 0.25 * 10.0 ** specs[0][3] * 1e3
        start = [np.log10(max(k_b, K_B_FLOOR) / 1e3), np.log10(onset.critical_pressure / 1e3),
                 np.log10(onset.critical_compression * 1e3)]
        # inside the bounds, off their edges (a start on an edge stays there under trf)
        starts.append([min(max(v, low + 0.01 * (high - low)), high - 0.01 * (high - low))
                       for v, (_, _, low, high) in zip(start, specs)])
    return starts


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
    if 'buckling' not in standing:
        model = without_buckling(model)
    if 'f_mts' in base:
        model = dataclasses.replace(model, f_mts=tuple(base['f_mts']),
                                    e_f=(base['e_f_c1'], params.e_f[1], params.e_f[2],
                                         -params.e_f[1] * P_ATM))
    if 'buckling' in causes and params.buckling is not None:
        b = values['buckling']
        model = dataclasses.replace(model, buckling=dataclasses.replace(
            params.buckling, stiffness_loss=b['stiffness_loss'],
            critical_pressure=b['critical_pressure'],
            critical_compression=b['critical_compression']))
    if 'wall_bulging' in causes:
        model = bulged(model, values['wall_bulging'])
    flat = params_to_flat(model, config.plant)
    for cause in causes:
        if cause in ('wall_bulging', 'buckling'):
            flat[f'actuator.effects.{cause}.scale'] = 1.0
            continue
        for name, value in values[cause].items():
            key = f'actuator.effects.{cause}.{name}'
            if key in flat:
                flat[key] = value
    return flat
