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
"""
import dataclasses
import sys
import time

import numpy as np

from bellows_ros.bench import devices, Result

CAUSES = tuple(devices.EFFECT_RANGES)
DEVICES, QUICK_DEVICES = 20, 1   # per cause, and null devices
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


def effect_size(device):
    """
    Return (size, raw): the change the device's effect makes in its noise-free record.

    Both are RMS over the sensor's noise floor, the larger of pressure and force; (0, 0) for a
    device without an effect. `raw` is the change itself (the same device and programme without
    the effect). `size` is what is left of it beyond what the doctor's baseline takes up with its
    own parameters: the force's linear terms refitted as the doctor refits them, then the
    baseline's directions in p_ref, V_tube and the encoder's zero projected out
    (`actuator_causes.baseline_directions`, linearised at the baseline's start). A play in a
    chamber that never reverses is a constant offset, which the encoder's zero is: no record can
    tell the two apart, and `size` is then small while `raw` is not.
    """
    if not device.effects:
        return 0.0, 0.0
    from bellows_ros.doctor import actuator_causes, checks
    sensors = device.plant.sensors
    scales = {'p': sensors.pressure_noise, 'f': sensors.force_noise}
    params = doctor_config(device).model
    clean, without = (checks.checked_record(checks.as_table(
        devices.actuator_device_record(device, effects=effects, noise=False), 'actuator',
        f'device {device.seed}'), 'actuator') for effects in (None, {}))
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


def diagnose_device(device):
    """Diagnose `device`'s record: a dict of what the bench reports of it."""
    from bellows_ros.doctor.diagnosis import diagnose
    started = time.perf_counter()
    record = devices.actuator_device_record(device)
    found = diagnose('actuator', record, doctor_config(device),
                     source=f'device {device.seed}')
    cause = next(iter(device.effects), None)
    out = {'seed': device.seed, 'cause': cause, 'named': list(found.causes),
           'gain': found.gain, 'unexplained': found.unexplained,
           'rate': device.rate, 'duration': device.duration,
           'seconds': time.perf_counter() - started}
    out['size'], out['raw_size'] = effect_size(device)
    if cause is not None and cause not in found.causes:
        out['why'] = miss_reason(found, cause)
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


def draw(index, cause):
    """Return the `index`-th device of `cause` (None: a null device)."""
    offset = 0 if cause is None else 1 + CAUSES.index(cause)
    return devices.draw_actuator(SEED + 1000 * offset + index, () if cause is None else (cause,))


def _diagnose_drawn(job):
    return diagnose_device(draw(*job))


def run_devices(count, causes=CAUSES, progress=True, workers=1, null=True):
    """
    Diagnose `count` devices per cause and (`null`) `count` null devices: a list of dicts.

    Device by device across the causes (every device is seeded on its own, so the order changes
    no result): a run stopped early has covered every cause alike.
    """
    from multiprocessing import get_context
    kinds = ((None,) if null else ()) + tuple(causes)
    jobs = [(index, cause) for index in range(count) for cause in kinds]
    rows = []
    with get_context('spawn').Pool(workers) as pool:
        for (index, cause), row in zip(jobs, pool.imap(_diagnose_drawn, jobs)):
            rows.append(row)
            if progress:
                print(f"  {cause or 'none'} #{index} ({row['rate']:.0f} Hz, "
                      f"{row['duration']:.0f} s, size {row['size']:.1f}, "
                      f"raw {row['raw_size']:.1f}): named "
                      f"{'+'.join(row['named']) or 'none'}, gain {100 * row['gain']:.0f} %"
                      f"{', ' + row['why'] if 'why' in row else ''} "
                      f"[{row['seconds']:.0f} s]", file=sys.stderr, flush=True)
    return rows


def summarise(rows, causes=CAUSES):
    """Per cause: a `Result` with its naming rate (value), false-name rates, gain and misses."""
    results = []
    null = [r for r in rows if r['cause'] is None]
    for cause in causes:
        own = [r for r in rows if r['cause'] == cause]
        due = [r for r in own if r['size'] > DUE]
        raw_due = [r for r in own if r['raw_size'] > DUE]
        named = [r for r in due if cause in r['named']]
        others = [r for r in rows if r['cause'] not in (None, cause)]
        false_null = sum(cause in r['named'] for r in null) / max(len(null), 1)
        false_other = sum(cause in r['named'] for r in others) / max(len(others), 1)
        gains = [r['gain'] for r in own if cause in r['named']]
        result = Result(f'doctor_devices.{cause}.named', len(named) / max(len(due), 1), '',
                        len(due), target=TARGET_NAMED)
        result.extra.update({
            'devices': len(own), 'due': len(due),
            'named_where_due': f'{len(named)} of {len(due)}',
            'named_below_due': f'{sum(cause in r["named"] for r in own if r["size"] <= DUE)} '
                               f'of {len(own) - len(due)}',
            # What the rate would be with the raw change as the size (the baseline's share in).
            'named_where_raw_size_due': f'{sum(cause in r["named"] for r in raw_due)} of '
                                        f'{len(raw_due)}',
            'false_name_rate_null': false_null, 'false_name_rate_other_causes': false_other,
            'median_heldout_gain': float(np.median(gains)) if gains else float('nan'),
            'misses': '; '.join(f"seed {r['seed']} (size {r['size']:.1f}): {r['why']}"
                                for r in due if cause not in r['named']) or 'none',
        })
        result.extra_units.update(false_name_rate_null='', false_name_rate_other_causes='',
                                  median_heldout_gain='')
        results.append(result)
    named_on_null = sum(bool(r['named']) for r in null) / max(len(null), 1)
    result = Result('doctor_devices.none.false_names', named_on_null, '', len(null),
                    target=TARGET_FALSE)
    result.extra['named'] = '; '.join(f"seed {r['seed']}: {'+'.join(r['named'])}"
                                      for r in null if r['named']) or 'none'
    result.extra['unexplained'] = f"{sum(r['unexplained'] for r in null)} of {len(null)}"
    result.extra['median_seconds_per_device'] = float(np.median([r['seconds'] for r in rows]))
    results.append(result)
    return results


def run(quick=False):
    return summarise(run_devices(QUICK_DEVICES if quick else DEVICES, workers=WORKERS))
