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
Synthetic actuator records shaped like paper B's experiments (for the doctor and the tests).

`actuator_record` drives `ActuatorPlant` through a seeded random programme:
- air chamber, position-controlled by a PD loop on the encoder (as in the paper, section II-A):
  steps at full speed, ramps at several speeds, holds, frequent direction reversals;
- spring, moved like the paper's MTS test machine: triangle compression cycles 0 -> 8..20 mm at
  several rates, holds, and fast 50 ms compressions held for a few seconds (these show heating).
Columns `t, x_c, x_s, p, f` (docs/interfaces.md), x_c read from the motor encoder (the nut, not the
plate: with backlash they differ).
"""
import numpy as np

from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator_plant import ActuatorPlant

# PD gains of the chamber loop on the encoder position: full duty at 0.25 mm error.
_KP = 4000.0      # 1/m
_KD = 40.0        # s/m


def chamber_programme(rng, n, dt, x0, low, high, max_speed, monotone=False):
    """
    Build a reference compression (m) of the air chamber, n samples.

    Steps, ramps, holds, reversals.

    `monotone`: only ramps at several speeds and holds, each ramp compressing further (a record in
    which the chamber never reverses, e.g. a slow compression sweep), ending in a hold at `high`.
    """
    if monotone:
        return _monotone_programme(rng, n, dt, x0, high, max_speed)
    ref = np.empty(n)
    i, x = 0, x0
    while i < n:
        kind = rng.choice(('step', 'ramp', 'ramp', 'hold'))
        if kind == 'hold':
            length = int(rng.uniform(0.5, 3.0) / dt)
            ref[i:i + length] = x
            i += length
            continue
        # Reverse more often than not, so backlash and rate effects are well excited.
        target = rng.uniform(low, high)
        if kind == 'step':
            settle = abs(target - x) / max_speed + rng.uniform(1.0, 3.0)
            length = int(settle / dt)
            ref[i:i + length] = target
        else:
            speed = rng.choice((0.2, 0.4, 0.8)) * max_speed
            ramp = max(1, int(abs(target - x) / speed / dt))
            ref[i:i + ramp] = np.linspace(x, target, ramp, endpoint=False)[:n - i]
            hold = int(rng.uniform(0.3, 2.0) / dt)
            ref[i + ramp:i + ramp + hold] = target
            length = ramp + hold
        i += length
        x = target
    return ref[:n]


def _monotone_programme(rng, n, dt, x0, high, max_speed):
    ref = np.full(n, float(high))
    i, x = 0, x0
    while i < n and x < high:
        target = min(high, x + rng.uniform(0.002, 0.008))
        speed = rng.choice((0.2, 0.4, 0.8)) * max_speed
        ramp = max(1, int((target - x) / speed / dt))
        ref[i:i + ramp] = np.linspace(x, target, ramp, endpoint=False)[:n - i]
        hold = int(rng.uniform(0.5, 2.0) / dt)
        ref[i + ramp:i + ramp + hold] = target
        i, x = i + ramp + hold, target
    return ref


def spring_programme(rng, n, dt, amplitude=(0.008, 0.020)):
    """
    Spring compression (m), n samples: triangle cycles, holds and fast compressions.

    `amplitude`: (low, high) m, the range the cycles' peak compressions are drawn from.
    """
    x_s = np.zeros(n)
    i = 0
    while i < n:
        kind = rng.choice(('cycle', 'cycle', 'hold', 'fast'))
        if kind == 'cycle':
            peak = rng.uniform(*amplitude)
            period = rng.uniform(1.0, 6.0)
            cycles = int(rng.integers(1, 4))
            t = np.arange(int(cycles * period / dt)) * dt
            phase = (t / period) % 1.0
            segment = peak * (1.0 - np.abs(2.0 * phase - 1.0))
        elif kind == 'hold':
            segment = np.zeros(int(rng.uniform(0.5, 2.5) / dt))
        else:
            peak = rng.uniform(amplitude[0], min(0.015, amplitude[1]))
            rise = int(0.05 / dt)
            hold = int(rng.uniform(2.0, 4.0) / dt)
            segment = np.concatenate([np.linspace(0.0, peak, rise), np.full(hold, peak),
                                      np.linspace(peak, 0.0, rise), np.zeros(hold // 2)])
        take = min(len(segment), n - i)
        x_s[i:i + take] = segment[:take]
        i += take
    return x_s


def actuator_record(params, plant_params, effects=None, noise=None, seed=None, duration=60.0,
                    dt=1e-3, x_c_range=(-0.020, 0.040), gas=None, x_c0=None, monotone=False,
                    spring_range=(0.008, 0.020)):
    """
    Simulate a measurement: dict of arrays `t, x_c, x_s, p, f` (docs/interfaces.md).

    params: ActuatorParams; plant_params: ActuatorPlantParams; effects/noise: as `ActuatorPlant`;
    seed: for the programme and noise; duration s; dt s; x_c_range: the span of chamber targets,
    m; gas: the sealed gas amount as p_ref, Pa (default the YAML's); x_c0: initial chamber
    compression, m (default the design point); monotone: the chamber only compresses (ramps and
    holds, `chamber_programme`); spring_range: (low, high) m of the spring's peak compressions
    (`spring_programme`). 60 s at 1 kHz takes a second or two.
    """
    if not (duration > 0.0 and dt > 0.0):
        raise ParameterError(f'duration and dt must be > 0, got {duration}, {dt}')
    rng = np.random.default_rng(seed)
    n = int(round(duration / dt))
    x_c0 = params.x_c_ref if x_c0 is None else x_c0
    plant = ActuatorPlant(params, plant_params, effects, noise,
                          seed=None if seed is None else seed + 1, gas=gas, x_c0=x_c0)
    low = max(x_c_range[0], plant.x_c_min)
    high = min(x_c_range[1], plant.x_c_max)
    ref = chamber_programme(rng, n, dt, x_c0, low, high, plant.max_speed, monotone)
    x_s = spring_programme(rng, n, dt, spring_range)
    out = {name: np.empty(n) for name in ('t', 'x_c', 'x_s', 'p', 'f')}
    t_col, xc_col, xs_col, p_col, f_col = (out[k] for k in ('t', 'x_c', 'x_s', 'p', 'f'))
    step, to_x = plant.step, plant.x_from_counts
    x_last = x_before = plant.x_nut
    for i in range(n):
        duty = _KP * (ref[i] - x_last) - _KD * (x_last - x_before) / dt
        sample = step(dt, duty, x_s_imposed=x_s[i])
        x_before, x_last = x_last, to_x(sample.encoder_counts)
        t_col[i], xc_col[i], xs_col[i], p_col[i], f_col[i] = (
            sample.t, x_last, sample.x_s, sample.p, sample.f)
    out['t'] -= out['t'][0]
    return out


def volume_test_series(params, plant_params, gases=(0.92, 0.96, 1.0, 1.04, 1.08),
                       effects=('wall_bulging', 'buckling'),
                       noise=None, seed=0, duration=12.0, dt=1e-3):
    """
    Paper B's volume test (Fig. 4, 8): sealed runs at several gas amounts, concatenated.

    Each run seals a different amount of gas (`gases`, as fractions of the YAML's p_ref: the
    paper set them with a syringe), starts at its own chamber compression (spread over -20..40 mm,
    since the lead screw is slow) and runs `actuator_record`'s programme. Returns the record dict
    plus a `run` column (0, 1, ...): identification needs it, because from a single sealed run the
    pressure-dependent volume E_V cannot be told from a larger tube volume.
    """
    parts = []
    starts = np.linspace(-0.020, 0.040, len(gases))
    order = np.random.default_rng(seed).permutation(len(gases))
    for index, fraction in enumerate(gases):
        record = actuator_record(params, plant_params, effects, noise,
                                 None if seed is None else seed + 7 * index,
                                 duration, dt, gas=fraction * params.p_ref,
                                 x_c0=starts[order[index]])
        record['run'] = np.full(len(record['t']), float(index))
        parts.append(record)
    out = {name: np.concatenate([part[name] for part in parts]) for name in parts[0]}
    out['t'] = np.arange(len(out['t'])) * dt
    return out
