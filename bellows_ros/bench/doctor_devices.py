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
The doctor on drawn actuators: does it name what is there, and only that (issue 21).

Per device (`devices.draw_actuator`, seeded: geometry, material, gas, tube, friction, sensors,
sample rate, record length and programme, and the effect's strength and shape all drawn): a record
with one hidden effect, or none (null devices), then `doctor.diagnosis.diagnose` on it with
config/actuator.yaml and the device's geometry (geometry is measured, the rest is the doctor's to
find). The doctor gets only the record.

The effect's size on a device is the RMS change it makes in the noise-free record (the same
device and programme without it) beyond what the doctor's baseline absorbs with its own
parameters (`effect_size`), over the sensor's noise, the larger of pressure and force: a cause is
*due* on a device where that exceeds DUE (3 noise floors). The raw change (without the baseline's
share taken out) is reported beside it. Per cause:
- naming rate on the devices where it is due (target >= 90 %);
- false-name rate: how often it is named on the null devices, and on the devices of the other
  causes (target <= 5 % each);
- median held-out gain of the diagnoses where it was named;
- every miss with its reason: the candidate's "not identifiable" reason, its note, its gain
  against the rule, and whether the doctor said `unexplained`.

Beside one kind of device per cause (`KINDS`), devices whose buckling onset lies at an edge of
its physical range (`buckling@ambient`, `buckling@travel_end`: `devices.ONSETS`) and devices
with two causes (`buckling+air_leak`, `sensor_lag+air_leak`). On a two-cause device each cause's
size is the change it makes beside the other (`effect_size`), and each is judged on its own:
named where due, and no name outside the device's causes. `bellows bench --only doctor_devices
--devices N --kinds KIND[:COUNT],...` runs a subset (`run`).
"""
import dataclasses
import sys
import time

import numpy as np

from bellows_ros.bench import devices, Result
from bellows_ros.identify.blas import one_blas_thread
from bellows_ros.models.actuator_effects import EFFECTS

CAUSES = tuple(devices.EFFECT_RANGES)
# Kinds of device: {kind: (its causes, buckling onset)}; None is the null device.
KINDS = {None: ((), None), **{cause: ((cause,), None) for cause in CAUSES},
         'buckling@ambient': (('buckling',), 'ambient'),
         'buckling@travel_end': (('buckling',), 'travel_end'),
         'buckling+air_leak': (('buckling', 'air_leak'), 'ambient'),
         'sensor_lag+air_leak': (('sensor_lag', 'air_leak'), None)}
# Each kind's block of seeds (`draw`), never reused: an effect's is 1 + its rank, which never
# changes; the kinds of two effects or an onset have theirs. A new effect leaves every other
# kind's devices as they were.
SEED_BLOCKS = {None: 0, **{e.name: 1 + e.rank for e in EFFECTS},
               'buckling@ambient': 7, 'buckling@travel_end': 8, 'buckling+air_leak': 9,
               'sensor_lag+air_leak': 10}
DEVICES, QUICK_DEVICES = 20, 1   # per kind
WORKERS = 2        # processes (the project machine has 2 cores); each device is independent
SEED = 2100
DUE = 3.0          # effect size (noise floors) above which a cause must be named
TARGET_NAMED = 0.90
TARGET_FALSE = 0.05


def doctor_config(device):
    """config/actuator.yaml with the device's (measured) geometry: what its user would give."""
    from bellows_ros.config.actuator import load_actuator
    config = load_actuator()
    model = dataclasses.replace(config.model, chamber=device.params.chamber,
                                spring=device.params.spring)
    return config._replace(model=model)


def effect_size(device, cause=None):
    """
    Return (size, raw): the change the device's effect (`cause` of several) makes in its record.

    Both are RMS over the sensor's noise floor, the larger of pressure and force; (0, 0) for a
    device without an effect. `raw` is the change itself (the same device and programme without
    the effect). `size` is what is left of it beyond what the doctor's baseline takes up with its
    own parameters: the force's linear terms refitted as the doctor refits them, then the
    baseline's directions in p_ref, V_tube and the encoder's zero projected out
    (`actuator_causes.baseline_directions`, linearised at the baseline's start). A play in a
    chamber that never reverses is a constant offset, which the encoder's zero is: no record can
    tell the two apart, and `size` is then small while `raw` is not. With `cause`, the change is
    that of `cause` beside the device's other effects (the record without it keeps them).
    """
    if not device.effects:
        return 0.0, 0.0
    others = {k: v for k, v in device.effects.items() if k != cause} if cause else {}
    from bellows_ros.doctor import actuator_causes, checks
    sensors = device.plant.sensors
    scales = {'p': sensors.pressure_noise, 'f': sensors.force_noise}
    params = doctor_config(device).model
    clean, without = (checks.checked_record(checks.as_table(
        devices.actuator_device_record(device, effects=effects, noise=False), 'actuator',
        f'device {device.seed}'), 'actuator') for effects in (None, others))
    rows = len(without)
    everything = np.ones(rows, bool)
    with_base = actuator_causes.build_model(clean, params, (), scales=scales)
    base = actuator_causes.build_model(without, params, (), scales=scales)
    y0, jacobian = actuator_causes.baseline_directions(base, rows)
    change = np.vstack([(clean[name] - without[name]) / scales[name] for name in ('p', 'f')])
    raw = float(np.max(np.sqrt(np.mean(change ** 2, axis=1))))
    # At the same parameters the baseline's predictions on the two records differ by what it
    # takes up without moving them: the force's linear terms, refitted to each record's force,
    # and its response to the records' inputs (the encoder's x_c differs by micrometres where
    # the effect loads the motor).
    change = change.ravel() - (with_base.predict(base.x0, everything)[0].ravel() - y0)
    left = actuator_causes.beyond_baseline(change, jacobian).reshape(2, rows)
    return float(np.max(np.sqrt(np.mean(left ** 2, axis=1)))), raw


def diagnose_device(device, kind=None):
    """
    Diagnose `device`'s record: a dict of what the bench reports of it.

    'causes' the device's, 'sizes' {cause: (size, raw)}, 'whys' {missed cause: reason}; 'cause',
    'size', 'raw_size' and 'why' those of its first cause.
    """
    from bellows_ros.doctor.diagnosis import diagnose
    started = time.perf_counter()
    record = devices.actuator_device_record(device)
    found = diagnose('actuator', record, doctor_config(device),
                     source=f'device {device.seed}')
    causes = list(device.effects)
    cause = causes[0] if causes else None
    out = {'seed': device.seed, 'kind': kind or cause, 'cause': cause, 'causes': causes,
           'named': list(found.causes), 'gain': found.gain, 'unexplained': found.unexplained,
           'rate': device.rate, 'duration': device.duration,
           'seconds': time.perf_counter() - started}
    # What was drawn of each effect (buckling: its onset) and the bounds its fit pinned.
    out['drawn'] = device.drawn
    out['edges'] = {c: [f"{e['parameter']} {e['side']} ({e['kind']})"
                        for e in found.candidates[c].edges] for c in causes if c in found.causes}
    out['sizes'] = {c: effect_size(device, c if len(causes) > 1 else None) for c in causes}
    out['size'], out['raw_size'] = out['sizes'][cause] if causes else (0.0, 0.0)
    out['whys'] = {c: miss_reason(found, c) for c in causes if c not in found.causes}
    if cause in out['whys']:
        out['why'] = out['whys'][cause]
    return out


def miss_reason(found, cause):
    """Why `cause` was not named in the diagnosis `found`, in numbers."""
    from bellows_ros.doctor.scoring import MIN_GAIN
    candidate = found.candidates[cause]
    if not candidate.identifiable:
        reason = f'not identifiable: {candidate.reason}'
    elif candidate.score is None:
        reason = f'not tried: the baseline, {found.failure}' if found.failure else 'not tried'
    elif candidate.note:
        reason = candidate.note
    else:
        reason = (f'held-out gain {100 * candidate.gain:.1f} % over '
                  f'{" + ".join(("baseline",) + candidate.extends)} (rule: >= '
                  f'{100 * MIN_GAIN:.0f} % and BIC falls)')
    return reason + ('; unexplained structure reported' if found.unexplained else '')


def draw(index, kind):
    """Return the `index`-th device of `kind` (a key of `KINDS`; None: a null device)."""
    causes, onset = KINDS[kind]
    return devices.draw_actuator(SEED + 1000 * SEED_BLOCKS[kind] + index, causes, onset)


def _diagnose_drawn(job):
    return diagnose_device(draw(*job), job[1])


def parse_kinds(text, count):
    """
    Return [(kind, count)] of `--kinds KIND[:COUNT],...` ('none' the null devices), or all kinds.

    A kind without a count gets `count`. An unknown kind is a BellowsError naming the known ones.
    """
    from bellows_ros.errors import BellowsError
    if not text:
        return [(kind, count) for kind in KINDS]
    chosen = []
    for item in text.split(','):
        name, _, number = item.strip().partition(':')
        kind = None if name == 'none' else name
        if kind not in KINDS or (number and not number.isdigit()):
            raise BellowsError(f'--kinds {text!r}: {item.strip()!r} is not KIND[:COUNT] (kinds: '
                               + ', '.join(k or 'none' for k in KINDS) + ')')
        chosen.append((kind, int(number) if number else count))
    return chosen


def run_devices(count, causes=CAUSES, progress=True, workers=1, null=True, kinds=None):
    """
    Diagnose `count` devices per kind: a list of dicts.

    `kinds`: [(kind, count)] (`parse_kinds`); default the single-cause kinds of `causes` and
    (`null`) the null devices, `count` each. Device by device across the kinds (every device is
    seeded on its own, so the order changes no result): a run stopped early has covered every
    kind alike.
    """
    from multiprocessing import get_context
    if kinds is None:
        kinds = [(kind, count) for kind in ((None,) if null else ()) + tuple(causes)]
    jobs = [(index, kind) for index in range(max((n for _, n in kinds), default=0))
            for kind, n in kinds if index < n]
    rows = []
    # Workers side by side, each on one BLAS thread (identify/blas.py): at OpenBLAS's default
    # threads they take the cores from one another.
    with get_context('spawn').Pool(workers, initializer=one_blas_thread) as pool:
        for (index, kind), row in zip(jobs, pool.imap(_diagnose_drawn, jobs)):
            rows.append(row)
            if progress:
                sizes = ', '.join(f'{c} {size:.1f} (raw {raw:.1f})'
                                  for c, (size, raw) in row['sizes'].items()) or 'size 0'
                whys = '; '.join(f'{c}: {why}' for c, why in row['whys'].items())
                print(f"  {kind or 'none'} #{index} seed {row['seed']} ({row['rate']:.0f} Hz, "
                      f"{row['duration']:.0f} s, {sizes}): named "
                      f"{'+'.join(row['named']) or 'none'}, gain {100 * row['gain']:.0f} %"
                      f"{', ' + whys if whys else ''} "
                      f"[{row['seconds']:.0f} s]", file=sys.stderr, flush=True)
    return rows


def _kind(row):
    return row.get('kind', row['cause'])


def _causes(row):
    return row.get('causes', [] if row['cause'] is None else [row['cause']])


def _size(row, cause):
    return row['sizes'][cause] if 'sizes' in row else (row['size'], row['raw_size'])


def _why(row, cause):
    return row['whys'][cause] if 'whys' in row else row['why']


def summarise(rows, causes=CAUSES):
    """
    Per kind and cause: a `Result` with its naming rate (value), false-name rates, gain, misses.

    A single-cause kind is `doctor_devices.KIND.named`; a cause of a two-cause kind
    `doctor_devices.KIND.CAUSE.named`. False names of a cause: on the null devices, and on the
    devices that do not have it.
    """
    results = []
    null = [r for r in rows if not _causes(r)]
    kinds = [k for k in KINDS if k is not None and (k in causes or k not in CAUSES)
             and any(_kind(r) == k for r in rows)]
    for kind in kinds:
        own = [r for r in rows if _kind(r) == kind]
        for cause in KINDS[kind][0]:
            results.append(_summarise_cause(rows, null, own, kind, cause))
    named_on_null = sum(bool(r['named']) for r in null) / max(len(null), 1)
    result = Result('doctor_devices.none.false_names', named_on_null, '', len(null),
                    target=TARGET_FALSE)
    result.extra['named'] = '; '.join(f"seed {r['seed']}: {'+'.join(r['named'])}"
                                      for r in null if r['named']) or 'none'
    result.extra['unexplained'] = f"{sum(r['unexplained'] for r in null)} of {len(null)}"
    wrong = [r for r in rows if set(r['named']) - set(_causes(r))]
    result.extra['false_names_all_devices'] = (
        f'{len(wrong)} of {len(rows)}: ' + '; '.join(
            f"seed {r['seed']} ({_kind(r) or 'none'}): "
            f"{'+'.join(sorted(set(r['named']) - set(_causes(r))))}" for r in wrong)
        if wrong else f'0 of {len(rows)}')
    result.extra['median_seconds_per_device'] = float(np.median([r['seconds'] for r in rows]))
    results.append(result)
    return results


def _summarise_cause(rows, null, own, kind, cause):
    """Return the `Result` of `cause` on the devices `own` of `kind` (`summarise`)."""
    due = [r for r in own if _size(r, cause)[0] > DUE]
    raw_due = [r for r in own if _size(r, cause)[1] > DUE]
    named = [r for r in due if cause in r['named']]
    others = [r for r in rows if _causes(r) and cause not in _causes(r)]
    false_null = sum(cause in r['named'] for r in null) / max(len(null), 1)
    false_other = sum(cause in r['named'] for r in others) / max(len(others), 1)
    gains = [r['gain'] for r in own if cause in r['named']]
    # A single-cause kind by its causes, not its name: buckling@ambient is single-cause too.
    name = kind if len(KINDS[kind][0]) == 1 else f'{kind}.{cause}'
    result = Result(f'doctor_devices.{name}.named', len(named) / max(len(due), 1), '',
                    len(due), target=TARGET_NAMED)
    result.extra.update({
        'devices': len(own), 'due': len(due),
        'named_where_due': f'{len(named)} of {len(due)}',
        'named_below_due': f'{sum(cause in r["named"] for r in own if r not in due)} '
                           f'of {len(own) - len(due)}',
        # What the rate would be with the raw change as the size (the baseline's share in).
        'named_where_raw_size_due': f'{sum(cause in r["named"] for r in raw_due)} of '
                                    f'{len(raw_due)}',
        'false_name_rate_null': false_null, 'false_name_rate_other_causes': false_other,
        'median_heldout_gain': float(np.median(gains)) if gains else float('nan'),
        'misses': '; '.join(f"seed {r['seed']} (size {_size(r, cause)[0]:.1f}): "
                            f'{_why(r, cause)}'
                            for r in due if cause not in r['named']) or 'none',
    })
    result.extra_units.update(false_name_rate_null='', false_name_rate_other_causes='',
                              median_heldout_gain='')
    return result


def run(quick=False, devices=None, kinds=None, workers=None):
    """
    Run the bench: a list of `Result` (`summarise`).

    `devices` (default 20, `quick` 1) devices of every kind, or `kinds` ('KIND[:COUNT],...',
    `parse_kinds`) only; `workers` processes (default `WORKERS`).
    """
    count = devices or (QUICK_DEVICES if quick else DEVICES)
    return summarise(run_devices(count, workers=workers or WORKERS,
                                 kinds=parse_kinds(kinds, count)))
