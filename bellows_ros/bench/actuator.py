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
Paper B actuator: cost of the forward model, the inverse stiffness map and a plant step.

References measured in the same run: a plain `math.sqrt` call and one geometric volume (4) of a
bellows. Every timed call draws its inputs from a fixed pseudo-random cycle, so no call repeats the
previous one's arguments. Targets (issue 3): forward <= 10 µs, inverse <= 50 µs, plant step well
under 100 µs (it runs at 1 kHz).
"""
import itertools
import math
import random
import time

import numpy as np

from bellows_ros.bench import Result, timing
from bellows_ros.config.actuator import load_actuator
from bellows_ros.models.actuator import estimate_gas, evaluate, evaluate_array
from bellows_ros.models.actuator_effects import NAMES as EFFECT_NAMES
from bellows_ros.models.actuator_geometry import P_ATM, volume_geo
from bellows_ros.models.actuator_plant import ActuatorPlant
from bellows_ros.models.stiffness_map import (compression_for_stiffness, stiffness_map,
                                              stiffness_range)


def run(quick=False):
    calls = 2000 if quick else 20000
    params, plant_params = load_actuator()
    rng = random.Random(1)
    c = params.chamber
    points = itertools.cycle([(rng.uniform(c.x_min, c.x_max),
                               rng.uniform(0.0, 0.02)) for _ in range(997)])
    values = itertools.cycle([rng.uniform(1.0, 2.0) for _ in range(997)])
    stiffness_map(params)                      # build the table outside the timing
    targets = []
    for _ in range(997):        # gas amounts as a slow leak or a temperature change would leave
        g = rng.uniform(0.97, 1.03) * params.p_ref
        k_min, k_max = stiffness_range(params, g)
        targets.append((rng.uniform(k_min, k_max), g))
    targets = itertools.cycle(targets)

    sqrt = math.sqrt
    reference = timing('reference: math.sqrt call', lambda: sqrt(next(values)), calls)
    geometry = timing('reference: V_geo (4) of one bellows',
                      lambda: volume_geo(c, next(points)[0]),
                      calls, reference=reference)

    def forward():
        x_c, x_s = next(points)
        return evaluate(params, x_c, x_s)

    def inverse():
        k, g = next(targets)
        return compression_for_stiffness(params, k, g)

    def gas_estimate():
        x_c, x_s = next(points)
        return estimate_gas(params, P_ATM, x_c, x_s)

    results = [reference, geometry,
               timing('actuator forward: evaluate -> (P, F, K)', forward, calls,
                      reference=reference,
                      target=10e-6),
               timing('actuator inverse: compression_for_stiffness', inverse, calls,
                      reference=reference, target=50e-6),
               timing('actuator estimate_gas', gas_estimate, calls, reference=reference)]
    for result in results[2:]:
        result.extra['ratio_to_V_geo'] = f'{result.value / geometry.value:.1f}'

    plant = ActuatorPlant(params, plant_params, seed=0)
    duties = itertools.cycle([rng.uniform(-1.0, 1.0) for _ in range(997)])
    results.append(timing('actuator plant step (dt = 1 ms, no effects)',
                          lambda: plant.step(1e-3, next(duties), x_s_imposed=0.005), calls,
                          reference=reference, target=100e-6))
    every_effect = {name: {} for name in EFFECT_NAMES}  # each at its default parameters
    plant_all = ActuatorPlant(params, plant_params, every_effect, seed=0)
    results.append(timing('actuator plant step (dt = 1 ms, all effects)',
                          lambda: plant_all.step(1e-3, next(duties), x_s_imposed=0.005), calls,
                          reference=reference, target=100e-6))

    rows = 60000 if quick else 600000
    x_c = np.random.default_rng(2).uniform(c.x_min, c.x_max, rows)
    x_s = np.random.default_rng(3).uniform(0.0, 0.02, rows)
    repeats = []
    for _ in range(3):
        start = time.perf_counter()
        evaluate_array(params, x_c, x_s)
        repeats.append(time.perf_counter() - start)
    per_row = sorted(repeats)[1] / rows
    results.append(Result('actuator evaluate_array, per row', per_row, 's', rows,
                          reference=reference.name, ratio=per_row / reference.value,
                          extra={'rows': rows, 'total_s': sorted(repeats)[1]}))
    return results
