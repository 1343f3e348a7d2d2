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
The doctor's report as data: report.json's and details.json's dictionaries and report.md's text.

`bellows diagnose` (`bellows_ros.cli.diagnose`) writes them to DIR/report.json, details.json and
report.md, with extended.yaml and the PNG plots (`bellows_ros.doctor.plots.figures`).

report.json has the keys of docs/interfaces.md; for a system with several measured outputs (the
actuator's pressure p and force f) its baseline/extended/gain and the candidates' held-out RMSE are
those of the output where the first cause pays most (`baseline.unit` says which), and `outputs`
adds the figures of every output. Everything else (per-candidate gains, the decision, the residual
evidence, timings) goes to details.json.
"""
import math

import numpy as np

from bellows_ros.doctor import diagnosis as engine
from bellows_ros.doctor import scoring
from bellows_ros.models.segment_effects import driving_torque

EXTENDED_FILE = 'extended.yaml'


def summary_line(d, report_directory):
    """Return the line `bellows diagnose` prints when it is done."""
    causes = ', '.join(d.causes) or 'none'
    return (f'{d.system}: cause {causes}; held-out RMSE {d.baseline_rmse:.4g} -> '
            f'{d.final_rmse:.4g} {d.unit} (gain {100 * d.gain:.1f} '
            f'%){"; unexplained structure left" if d.unexplained else ""}; report in '
            f'{report_directory}')


def extended_header(d):
    """Return the comment at the top of extended.yaml."""
    return (f'Extended {d.system} model written by `bellows diagnose` from {d.source}\n'
            f'causes: {", ".join(d.causes) or "none"}; held-out gain {100 * d.gain:.1f} %')


def _number(value):
    return None if value is None or not math.isfinite(value) else float(value)


def report_dict(d):
    """report.json (the keys of docs/interfaces.md)."""
    candidates = []
    for cause, candidate in d.candidates.items():
        params = {}
        if candidate.score is not None:
            params = candidate.score.params().get(cause, {})
        rmse = d.candidate_rmse(cause)
        # A fit at a bound of its range: a limiting case of the physics (a finding, kind
        # 'limit') or not (the note says why it is not named), per parameter.
        candidates.append({'cause': cause, 'heldout_rmse': None if rmse is None else _number(rmse),
                           'params': params, 'edges': list(candidate.edges)})
    report = {
        'system': d.system,
        # A broken held-out score is not a number: JSON has null for it, not NaN.
        'baseline': {'model': d.baseline_name, 'rmse': _number(d.baseline_rmse), 'unit': d.unit},
        'cause': d.cause,
        'extended': {'model': extended_name(d), 'rmse': _number(d.final_rmse)},
        'gain': _number(d.gain),
        'causes': list(d.causes),
        'unexplained': d.unexplained,
        'candidates': candidates,
    }
    if d.outputs:
        report['outputs'] = {o.name: {
            'quantity': o.label, 'unit': o.unit, 'noise_floor': o.noise,
            'noise_floor_fitted': o.scale, 'baseline_rmse': _number(o.baseline_rmse),
            'extended_rmse': _number(o.final_rmse), 'gain': _number(o.gain),
            'candidates_heldout_rmse': {c: _number(v) for c, v in o.candidate_rmse.items()}}
            for o in d.outputs}
        report['output'] = d.outputs[d.primary].name
    return report


def limit_findings(d):
    """
    Return a sentence per named cause fitted at a limiting case of its physics (`edges`).

    Such a fit is a finding, not a doubt: a buckling onset at ambient pressure says the spring is
    buckled from the start of the record wherever the gas is above ambient.
    """
    lines = []
    for cause in d.causes:
        limits = [e for e in d.candidates[cause].edges if e['kind'] == 'limit']
        if limits:
            lines.append(f'`{cause}` is fitted at a physical limit, a finding: ' + '; '.join(
                f"{e['parameter']} at its {e['side']} bound: {e['meaning']}" for e in limits)
                + '.')
    return lines


def extended_name(d):
    return 'baseline + ' + ' + '.join(d.causes) if d.causes else 'baseline (no cause pays)'


def details_dict(d):
    candidates = {}
    for cause, c in d.candidates.items():
        candidates[cause] = {'identifiable': c.identifiable, 'reason': c.reason,
                             'extends': list(c.extends), 'gain_over_extended_model': c.gain,
                             'pays': c.pays, 'note': c.note, 'edges': list(c.edges),
                             'heldout_rmse': c.score.rmse if c.score else None,
                             'insample_rmse': c.score.insample_rmse if c.score else None}
    return {
        'data': d.source,
        'samples_fitted': len(d.record),
        'fit_rate_hz': 1.0 / d.record.dt,
        'decimation': d.record.factor,
        'resampled': d.record.resampled,
        'noise_floor_full_rate': d.noise,
        'baseline': {'heldout_rmse': d.baseline.rmse, 'insample_rmse': d.baseline.insample_rmse,
                     'heldout_rmse_per_fold': fold_rmse(d.baseline.heldout)},
        'heldout_units': ('noise floors of each output (combined)' if d.outputs else d.unit),
        'evidence_per_output': {o.name: o.evidence for o in d.outputs},
        'heldout_failure': d.failure,
        'rule': {'min_gain': scoring.MIN_GAIN, 'blocks': scoring.BLOCKS,
                 'penalty': 'BIC on held-out',
                 'unexplained_ratio': engine.UNEXPLAINED_RATIO, 'ljung_box_p': engine.LB_P,
                 'failure_over_noise': scoring.FAILURE_NOISE,
                 'failure_over_insample': scoring.FAILURE_INSAMPLE},
        'candidates': candidates,
        'closest': closest(d),
        'evidence': d.evidence,
        'extended_params': d.values,
        'timings_s': d.timings,
    }


def closest(d):
    """
    Return the candidate that came closest to removing the structure left, or None.

    {'cause', 'gain', 'why_not', 'deciding_data'}: among the causes scored against the final
    model and not named, the one with the largest held-out gain; its note or the rule it missed,
    and the data that would decide it (`DECIDING_DATA` of the system's causes module).
    """
    tried = [c for c in d.candidates.values() if c.score is not None and not c.pays
             and c.gain is not None]
    if not tried:
        return None
    best = max(tried, key=lambda c: c.gain)
    if best.gain < scoring.MIN_GAIN:
        measured = f'held-out gain {100 * best.gain:.1f} % < {100 * scoring.MIN_GAIN:.0f} %'
    else:
        measured = (f'held-out gain {100 * best.gain:.1f} %, but its BIC did not fall (the '
                    'gain does not pay for the parameters it adds)')
    why = best.note or measured
    deciding = engine.system_module(d.system).DECIDING_DATA[best.cause]
    return {'cause': best.cause, 'gain': best.gain, 'why_not': why, 'deciding_data': deciding}


def fold_rmse(heldout):
    """
    Return the held-out RMSE of each fold (`scoring.block_masks`).

    A fold far above the others is one whose refit extrapolates.
    """
    return [float(np.sqrt(np.mean(heldout[..., test] ** 2)))
            for _, test in scoring.block_masks(np.shape(heldout)[-1])]


def _fmt(value):
    if isinstance(value, float):
        return f'{value:.4g}'
    return str(value)


def markdown(d, plots):
    lines = [f'# Model doctor: {d.system}', '',
             f'Data: `{d.source}` — {len(d.record)} samples fitted '
             f'at {1 / d.record.dt:.0f} Hz (block means of {d.record.factor} raw samples).', '']
    if d.causes:
        lines.append(f'**Cause: {", ".join(f"`{c}`" for c in d.causes)}.** Extending the baseline '
                     f'with {"it" if len(d.causes) == 1 else "them"} cuts the held-out RMSE from '
                     f'{d.baseline_rmse:.4g} to {d.final_rmse:.4g} {d.unit} (gain '
                     f'{100 * d.gain:.1f} %).')
        for line in limit_findings(d):
            lines.append(f'\n{line}')
    elif d.failure:
        lines.append(f'**Cause: `none` — the baseline could not be scored.** Its {d.failure} '
                     f'{d.unit}. Causes compared against a broken score would name whichever '
                     'breaks least, so none was tried; this is a failure of the doctor on this '
                     'record, not a finding about the system.')
    else:
        lines.append(f'**Cause: `none`.** No candidate cause improves the held-out RMSE '
                     f'({d.baseline_rmse:.4g} {d.unit}) by at least '
                     f'{100 * scoring.MIN_GAIN:.0f} %.')
    if d.outputs:
        lines += ['', '## Both measured outputs', '',
                  'Fitted and scored together, each over its own noise floor; the decision rule '
                  'works on the combined residual in noise floors.', '',
                  '| output | noise floor (full rate) | baseline held-out RMSE | extended '
                  '| gain |',
                  '|---|---|---|---|---|']
        for o in d.outputs:
            lines.append(f'| {o.label} `{o.name}` ({o.unit}) | {o.noise:.3g} | '
                         f'{o.baseline_rmse:.4g} ({o.baseline_rmse / o.scale:.1f} × floor) | '
                         f'{o.final_rmse:.4g} ({o.final_rmse / o.scale:.1f} × floor) | '
                         f'{100 * o.gain:.1f} % |')
        lines.append(f"\nThe headline figures above are the {d.outputs[d.primary].label}'s, "
                     'where the first cause pays most.')
    lines += ['', '## What is left', '']
    for label, unit, ev in ([(o.label + ': ', o.unit, o.evidence) for o in d.outputs]
                            or [('', d.unit, d.evidence)]):
        lines += [f'{label}Held-out residual RMSE {ev["rmse"]:.4g} {unit} = '
                  f'{ev["rmse_over_noise"]:.2f} × the noise floor ({ev["noise_floor"]:.3g} {unit} '
                  f'after averaging); Ljung-Box Q = {ev["ljung_box_q"]:.4g} over '
                  f'{ev["ljung_box_lags"]} lags (p = {ev["ljung_box_p"]:.2g}); lag-1 '
                  f'autocorrelation {ev["autocorrelation_lag1"]:.2f}; correlation with rate '
                  f'{ev["correlation_with_rate"]:.2f}, '
                  f'position {ev["correlation_with_position"]:.2f}, '
                  f'pressure {ev["correlation_with_pressure"]:.2f}, '
                  f'direction {ev["correlation_with_direction"]:.2f}.', '']
    if d.unexplained:
        lines.append('**Unexplained structure remains**: the residual is more than '
                     f'{engine.UNEXPLAINED_RATIO:g} × the noise floor and correlated in time, and '
                     'no candidate in the vocabulary removes it. Something outside the vocabulary '
                     'is at work; the correlations above say what it moves with.')
        near = closest(d)
        if near:
            lines.append(f"\nClosest candidate: `{near['cause']}`, held-out gain "
                         f"{100 * near['gain']:.1f} %, not named: {near['why_not']}. A record "
                         f"with {near['deciding_data']} would decide it.")
    else:
        lines.append('No structure beyond the noise is left that the doctor can tell apart.')
    lines += ['', '## Candidates (held-out, greedy forward selection)', '',
              '| cause | identifiable | extends | held-out RMSE | gain over that model | pays |',
              '|---|---|---|---|---|---|']
    for cause, c in d.candidates.items():
        if not c.identifiable:
            lines.append(f'| `{cause}` | no: {c.reason} | | | | no |')
            continue
        if c.score is None:
            lines.append(f'| `{cause}` | yes | | | | '
                         "not tried: the baseline's held-out score is broken |")
            continue
        extends = ' + '.join(('baseline',) + c.extends)
        verdict = 'yes' if c.pays else ('no: ' + c.note if c.note else 'no')
        limits = [e for e in c.edges if e['kind'] == 'limit']
        if limits and not c.note:
            verdict += ' (at a physical limit: ' + '; '.join(
                f"{e['parameter']} at its {e['side']} bound, {e['meaning']}" for e in limits) + ')'
        if d.outputs:
            rmse = ', '.join(f'{o.candidate_rmse[cause]:.4g} {o.unit}' for o in d.outputs)
        else:
            rmse = f'{c.score.rmse:.4g} {d.unit}'
        lines.append(f'| `{cause}` | yes | {extends} | {rmse} | '
                     f'{100 * c.gain:.1f} % | {verdict} |')
    lines += ['', '## Fitted parameters of the extended model (SI)', '']
    for part, values in d.values.items():
        if values:
            lines.append(f'- {part}: ' + ', '.join(f'{k} = {_fmt(v)}' for k, v in values.items()))
    lines += ['', '## Using the extended model', '',
              f'`{EXTENDED_FILE}` holds the extended model in ROS 2 parameter format. Lay it over '
              'the defaults wherever parameters are read:', '',
              f'    bellows simulate {d.system} --input IN.csv --output OUT.csv --params '
              f'{EXTENDED_FILE}'
              + ''.join(f' --effect {c}' for c in _plant_effects(d)),
              f'    ros2 run bellows_ros <node> --ros-args --params-file {EXTENDED_FILE}', '']
    if d.system == 'segment':
        output = driving_torque(d.causes)
        name = TORQUES[output]
        lines.append(f"The extended segment model's driving torque is the `{output}` output of "
                     f'`bellows simulate segment` and of the model node ({name}).')
    plant_only = _plant_effects(d)
    if plant_only:
        verb = 'is a dynamic effect' if len(plant_only) == 1 else 'are dynamic effects'
        lines.append(f'{", ".join(plant_only)} {verb} of the plant: the fitted values are its '
                     '`--effect` defaults in the file, so `--effect NAME` switches it on with '
                     'them.')
    lines += ['', '## How the doctor decided', '',
              f'The record was cut into {scoring.BLOCKS} contiguous blocks of time, dealt into '
              f'{scoring.FOLDS} folds; every model was refitted without each fold and scored on '
              'the blocks it did not see. A cause pays when it cuts the held-out RMSE of the '
              f'current model by at least {100 * scoring.MIN_GAIN:.0f} % and its held-out BIC (n '
              'ln MSE + k ln n) decreases; the best paying cause is added and the search repeats '
              '(see docs/doctor.md).', '', '## Plots', '']
    lines += [f'![{name}]({name})' for name in plots]
    return '\n'.join(lines) + '\n'


# The segment model's outputs that can be its driving torque, and what each is.
TORQUES = {'tau_prev': 'previous model (34)', 'tau_drive': 'membrane-contact torque (29)'}


def _plant_effects(d):
    """Return the causes of `d` that are plant effects switched on by `--effect`."""
    return [c for c in d.causes if c in engine.system_module(d.system).SWITCHED_BY_EFFECT]
