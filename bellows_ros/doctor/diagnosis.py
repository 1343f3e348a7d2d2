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
The model doctor's decision procedure (docs/doctor.md).

It takes data and parameter objects and returns a `Diagnosis`; it reads and writes no file (the
`bellows diagnose` command does: `bellows_ros.cli.diagnose`).

1. Check the record; estimate the white-noise floor of the measured signal at full rate.
2. Fit on a block-averaged copy (at most the system's `FIT_RATE` Hz and `FIT_SAMPLES` samples): the
   dynamics of every cause are slower than that, and averaging also lowers the noise.
3. Score the baseline on held-out blocks of time.
4. Greedy forward selection: try every identifiable cause as an extension of the current model,
   keep the best if it *pays* (`scoring.pays`) and none of its physical parameters is pinned at
   a bound that is not a limiting case of the physics (`edge_report`: a buckling onset at
   ambient pressure is a finding; a lag at the end of an arbitrary range is not), refit, repeat
   with the remaining causes until none pays (a second cause beside the first: a leak and a
   buckling spring).
5. Look at what is left: if the final held-out residual is still well above the noise floor and
   correlated in time, the record holds structure that no candidate explains (`unexplained`).

A system with several measured outputs (the actuator: pressure p and force f, `module.OUTPUTS`) is
fitted and scored on all of them at once, each divided by its own noise floor; the decision rule
then works on that combined residual (in noise floors), and `outputs` holds the figures of each
output in its own unit.
"""
from dataclasses import dataclass, field
import sys
import time

import numpy as np

from bellows_ros.doctor import checks, scoring

# most samples of the fitted copy (the highest rate is the system's FIT_RATE)
FIT_SAMPLES = 20000
# Unexplained structure: final held-out RMSE above this multiple of the (averaged) noise floor ...
UNEXPLAINED_RATIO = 2.0
# ... and a Ljung-Box statistic over LB_LAGS lags of the residual with p below LB_P.
LB_LAGS = 20
LB_P = 1e-3


@dataclass
class Candidate:
    cause: str
    identifiable: bool
    reason: str = None
    score: scoring.Score = None
    extends: tuple = ()
    gain: float = None
    pays: bool = False
    note: str = None
    # Fit variables of the scored model at a bound of their range (`edge_report`): [{parameter,
    # side, kind, meaning}]; kind 'limit' is a finding, the others say why it is not named.
    edges: list = field(default_factory=list)


@dataclass
class OutputView:
    """One measured output of a diagnosis in its own unit: held-out residuals, RMSEs, evidence."""

    name: str
    unit: str
    label: str
    scale: float                   # noise floor on the fitted copy: the output's unit of the fit
    noise: float                   # noise floor at full rate
    signal: np.ndarray
    baseline_heldout: np.ndarray
    final_heldout: np.ndarray
    candidate_rmse: dict
    evidence: dict

    @property
    def baseline_rmse(self):
        return float(np.sqrt(np.mean(self.baseline_heldout ** 2)))

    @property
    def final_rmse(self):
        return float(np.sqrt(np.mean(self.final_heldout ** 2)))

    @property
    def gain(self):
        return scoring.gain(self.final_rmse, self.baseline_rmse)


@dataclass
class Diagnosis:
    system: str
    source: str                    # the data's name: the file it was read from, or the caller's
    record: checks.Record          # the fitted (block-averaged) copy
    signal: np.ndarray             # the measured signal compared with the model, on `record`
    unit: str
    baseline_name: str
    baseline: scoring.Score
    final: scoring.Score
    causes: list
    candidates: dict
    noise: float                   # noise floor at full rate
    evidence: dict
    unexplained: bool
    values: dict                   # physical parameters of the final model {part: {name: value}}
    extended_flat: dict            # ROS 2 parameters of the extended model
    timings: dict = field(default_factory=dict)
    # why the baseline's held-out score is broken (then no cause is tried)
    failure: str = None
    outputs: list = field(default_factory=list)   # OutputView per measured output (multi-output)
    primary: int = 0               # the output where the first cause pays most

    @property
    def baseline_rmse(self):
        """Held-out RMSE of the baseline, in `unit` (the primary output's for several outputs)."""
        return self.outputs[self.primary].baseline_rmse if self.outputs else self.baseline.rmse

    @property
    def final_rmse(self):
        return self.outputs[self.primary].final_rmse if self.outputs else self.final.rmse

    @property
    def gain(self):
        return scoring.gain(self.final_rmse, self.baseline_rmse)

    def candidate_rmse(self, cause):
        """Held-out RMSE of `cause`'s scored model in `unit`, or None if it was not scored."""
        candidate = self.candidates[cause]
        if candidate.score is None:
            return None
        if self.outputs:
            return self.outputs[self.primary].candidate_rmse[cause]
        return candidate.score.rmse

    @property
    def cause(self):
        return self.causes[0] if self.causes else 'none'


def system_module(system):
    if system == 'actuator':
        from bellows_ros.doctor import actuator_causes as module
    else:
        from bellows_ros.doctor import segment_causes as module
    return module


def decimation_factor(record, rate):
    """Block length that brings `record` to at most `rate` Hz and `FIT_SAMPLES` samples."""
    by_rate = int(np.floor(1.0 / (record.dt * rate) + 1e-6)) or 1
    by_size = int(np.ceil(len(record) / FIT_SAMPLES))
    return max(1, by_rate, by_size)


def raw_noise(system, table, params):
    """
    Return the white-noise floor(s) the doctor compares residuals with, on raw rows `table`.

    {column: sigma} of the actuator's outputs, {'y': sigma} of the segment's Y (30). For a long
    record read as block means (`data.read_record`): its raw chunks' floors, of which `diagnose`
    takes the median (`raw_noise` argument), as block means would hide the noise.
    """
    module = system_module(system)
    if system == 'actuator':
        return module.noise_floors(table)
    from bellows_ros.identify.segment import target
    from bellows_ros.models.derivatives import rates
    columns = {name: np.asarray(table[name], float) for name in table.values}
    if 'psi_dot' not in columns:
        columns['psi_dot'] = rates(columns['t'], columns['psi'])
    return {'y': scoring.noise_floor(target(params, columns))}


def diagnose(system, data, config, progress=False, causes=None, source='<arrays>',
             raw_noise=None, factor=1, standing=()):
    """
    Diagnose one record of `system` ('segment' or 'actuator'). Returns a `Diagnosis`.

    `data`: a `table.Table` (as `data.read_table` gives it) or a mapping column -> array (SI
    units, the columns of the system's files); `config`: the system's parameter objects
    (`config.segment.SegmentConfig` or `config.actuator.ActuatorConfig`): `config.model` is the
    nominal model the doctor extends. `source` names
    in-memory data in error messages (a table carries its own). `causes` restricts the candidates
    (default: the whole vocabulary of the system; `()` fits and scores the baseline only, the
    benchmark's reference). `factor` > 1: the rows of `data` are block means of that many raw rows
    (`data.read_record`), and `raw_noise` gives the raw rows' noise floors as `raw_noise` does
    (the floors of the averaged rows follow, divided by √factor). `standing` (actuator only): the
    model's own physics the baseline keeps at the model's values (`actuator_causes.STANDING`; the
    live doctor's, which asks what changed from the model its monitor compares with).
    """
    started = time.perf_counter()
    standing = tuple(standing)
    if standing and system != 'actuator':
        raise ValueError(f"standing physics {standing} is the actuator's, not the {system}'s")
    module = system_module(system)
    params = config.model
    full = checks.checked_record(checks.as_table(data, system, source), system, factor)
    if system == 'segment':
        module.add_columns(full, params, config.identify.input_cutoff)
    record = full.decimated(decimation_factor(full, module.FIT_RATE))
    extra = {}
    outputs = getattr(module, 'OUTPUTS', None)
    if outputs:
        floors = module.noise_floors(full) if raw_noise is None else dict(raw_noise)
        scales = {name: floors[name] / np.sqrt(record.factor) for name, *_ in outputs}
        extra['scales'] = scales
        extra['standing'] = standing
        y = module.measured(record, scales)
        noise = floors[outputs[0][0]]
        reasons = checks.identifiability(record)
        reasons.update(module.identifiability(record, params, scales, standing))
    else:
        noise = (scoring.noise_floor(module.measured(full)) if raw_noise is None
                 else raw_noise['y'])
        y = module.measured(record)
        reasons = checks.identifiability(record, params.p0)
    timings = {'load': time.perf_counter() - started}   # checks (the caller reads the data)
    bar = _progress(progress, total=1 + len(module.CAUSES if causes is None else causes))
    if system == 'segment':
        # Algorithm 1 over the record does not depend on any fitted parameter: run it once, at
        # the record's full rate (see `segment_causes.ContactLengths`).
        extra['contact'] = module.ContactLengths(params, full, record.factor // full.factor)
        extra['noise'] = noise / np.sqrt(record.factor)

    def score(switched_on, warm=None):
        model = module.build_model(record, params, switched_on, warm=warm, **extra)
        result = scoring.score(model, y)
        bar.update(1)
        return result

    baseline = score(())
    timings['baseline'] = time.perf_counter() - started
    floor = 1.0 if outputs else noise / np.sqrt(record.factor)   # outputs are in noise floors
    # A baseline whose held-out score is broken leaves nothing to compare causes against.
    failure = scoring.heldout_failure(baseline, floor)
    candidates = {cause: Candidate(cause, reason is None, reason)
                  for cause, reason in reasons.items()}
    current, chosen = baseline, []
    vocabulary = module.CAUSES if causes is None else tuple(causes)
    remaining = [c for c in vocabulary if candidates[c].identifiable and failure is None]
    while remaining:
        warm = dict(zip(current.model.names, current.full.theta))
        round_scores = {}
        for cause in remaining:
            result = score(tuple(chosen) + (cause,), warm)
            round_scores[cause] = result
            candidate = candidates[cause]
            candidate.score, candidate.extends = result, tuple(chosen)
            candidate.gain = scoring.gain(result.rmse, current.rmse)
        polished = _polished(current, round_scores, y, lambda warm: score(tuple(chosen), warm))
        if polished is not None:
            current = polished
            for cause, result in round_scores.items():
                candidates[cause].gain = scoring.gain(result.rmse, current.rmse)
        for cause, result in round_scores.items():
            candidates[cause].edges = edge_report(result, cause, module)
            candidates[cause].note = (_doubt(candidates[cause].edges, result, floor)
                                      or _worsens(result, current, outputs))
        credible = [c for c in round_scores if candidates[c].note is None]
        if not credible:
            break
        best = min(credible, key=lambda c: round_scores[c].rmse)
        if not scoring.pays(round_scores[best], current):
            break
        candidates[best].pays = True
        chosen.append(best)
        remaining.remove(best)
        current = round_scores[best]
        bar.total += len(remaining)  # the next round's fits
        bar.refresh()
    bar.close()
    timings['fit'] = time.perf_counter() - started
    values = current.params()
    if not outputs:
        evidence = residual_evidence(record, current.heldout, floor, system)
        unexplained = _structured(evidence)
        return Diagnosis(system, full.path, record, y, module.UNIT, module.BASELINE, baseline,
                         current, chosen, candidates, noise, evidence, bool(unexplained), values,
                         module.extended_flat(config, chosen, values), timings, failure)
    views = []
    for i, (name, unit, label) in enumerate(outputs):
        scale = scales[name]
        final_heldout = current.heldout[i] * scale
        views.append(OutputView(
            name, unit, label, scale, floors[name], record[name], baseline.heldout[i] * scale,
            final_heldout, {c: cand.score.output_rmse(i) * scale
                            for c, cand in candidates.items() if cand.score is not None},
            residual_evidence(record, final_heldout, scale, system)))
    primary = 0
    if chosen:
        first = candidates[chosen[0]].score
        primary = max(range(len(views)), key=lambda i: scoring.gain(
            first.output_rmse(i), baseline.output_rmse(i)))
    unexplained = any(_structured(v.evidence) for v in views)
    worst = max(views, key=lambda v: v.evidence['rmse_over_noise'])
    view = views[primary]
    return Diagnosis(system, full.path, record, view.signal, view.unit,
                     module.baseline_name(standing), baseline,
                     current, chosen, candidates, view.noise, worst.evidence, bool(unexplained),
                     values, module.extended_flat(config, chosen, values, standing), timings,
                     failure, views, primary)


# The current model at a candidate's values of their shared parameters must fit all the data
# better than its own fit by this fraction of the cost before it is refitted from there.
POLISH = 1e-3


def _polished(current, round_scores, y, rescore):
    """
    Return the current model refitted from where a candidate's fit left their shared parameters.

    Every candidate's fit starts where the current model's ended and runs on. When the current
    fit had not converged (a large effect just named), a candidate whose own effect is nil (a
    sensor lag of 0.3 ms) would take the credit for those extra iterations. So the current model
    is evaluated at the shared parameters of the candidate that fits all the data best; if that
    is better than its own fit by more than `POLISH`, it is refitted from there (`rescore(warm)`)
    and every candidate is judged against the better of the two. Returns None when nothing is
    gained.
    """
    if not round_scores or not current.model.names:
        return None
    names = current.model.names
    best = min(round_scores.values(), key=lambda r: r.full.cost)
    shared = np.asarray(best.full.theta[:len(names)], float)
    everything = np.ones(np.shape(y)[-1], bool)
    prediction = current.model.predict(shared, everything)[0]
    if not np.mean((prediction - y) ** 2) < (1.0 - POLISH) * current.full.cost:
        return None
    refitted = rescore(dict(zip(names, shared)))
    return refitted if refitted.full.cost < current.full.cost else None


def _structured(evidence):
    return evidence['rmse_over_noise'] > UNEXPLAINED_RATIO and evidence['ljung_box_p'] < LB_P


# What a fit pinned at a bound of each kind (`edge_report`) says, when the cause is not named.
EDGE_VERDICTS = {
    'absent': 'the effect vanishes there',
    'bound': 'a physical bound no such effect passes: the cause absorbs some other error',
    'range': 'not a physical limit: the range is wrong',
}


def edge_report(result, cause, module):
    """
    Return the fit variables of `cause` at a bound of their range, with what that means.

    [{'parameter', 'side' ('lower'/'upper'), 'kind', 'meaning'}]; the kind and meaning come from
    the system's causes module (`edge_kind`: 'limit', 'absent', 'bound' or 'range'); a module
    without them has only ranges of the fit ('range').
    """
    kind_of = getattr(module, 'edge_kind', None)
    out = []
    for name, side in scoring.edges(result, cause):
        kind, meaning = (kind_of(cause, name, side) if kind_of
                         else ('range', 'a bound of the fit, not of physics'))
        out.append({'parameter': name, 'side': side, 'kind': kind, 'meaning': meaning})
    return out


def _doubt(edges, result, floor):
    """
    Tell why a scored candidate cannot be named whatever its gain, or return None.

    A physical parameter at a bound of its range (`edge_report`) that is not a limiting case of
    the physics: the effect vanishes there, or the cause absorbs some other error, or the range
    is wrong. At a limit ('limit': an onset at ambient pressure) the fit is a finding and the
    cause is named when it pays. Or a broken held-out score.
    """
    doubtful = [e for e in edges if e['kind'] != 'limit']
    if doubtful:
        return '; '.join(f"fitted {e['parameter']} at the {e['side']} bound of its range "
                         f"({e['meaning']}; {EDGE_VERDICTS.get(e['kind'], e['kind'])})"
                         for e in doubtful)
    return scoring.heldout_failure(result, floor)


def _worsens(result, current, outputs):
    """
    Name the output `result` makes worse than `current` by more than `scoring.MIN_GAIN`, or None.

    A cause must not buy a better fit of one output with a worse one of another (the combined
    residual is dominated by whichever output is furthest above its noise floor).
    """
    for i, (name, unit, label) in enumerate(outputs or ()):
        loss = -scoring.gain(result.output_rmse(i), current.output_rmse(i))
        if loss > scoring.MIN_GAIN:
            return f'makes the {label} ({name}) held-out RMSE {100 * loss:.0f} % worse'
    return None


def residual_evidence(record, residual, noise, system):
    """Numbers that say whether structure is left in a held-out residual."""
    q, p_value = scoring.ljung_box(residual, LB_LAGS)
    position = record['x_c'] if system == 'actuator' else record['psi']
    rate = np.gradient(position, record.dt)
    pressure = record['p'] if system == 'actuator' else record['p1'] - record['p2']
    rmse = float(np.sqrt(np.mean(residual ** 2)))
    return {
        'rmse': rmse,
        'noise_floor': float(noise),
        'rmse_over_noise': rmse / noise if noise > 0 else float('inf'),
        'ljung_box_q': q,
        'ljung_box_lags': LB_LAGS,
        'ljung_box_p': p_value,
        'autocorrelation_lag1': float(scoring.autocorrelation(residual, 1)[1]),
        'correlation_with_rate': _correlation(residual, rate),
        'correlation_with_position': _correlation(residual, position),
        'correlation_with_pressure': _correlation(residual, pressure),
        'correlation_with_direction': _correlation(residual, np.sign(rate)),
    }


def _correlation(a, b):
    if np.std(a) == 0 or np.std(b) == 0:
        return 0.0
    return float(np.corrcoef(a, b)[0, 1])


def _progress(enabled, total):
    from tqdm import tqdm
    return tqdm(total=total, desc='diagnose', unit='fit', file=sys.stderr, disable=not enabled,
                leave=False)
