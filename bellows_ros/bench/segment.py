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
Cost of one full segment step of paper A's model against the previous model (34) alone.

Both chains: contact update, τ_a, τ_s, τ_f, and τ_prev; the reference is measured in the same
run.

The inputs cycle through a recorded quasi-static excursion (pressurised chain, angle reversals), so
the strain memories really fill and release as in use. Target: ≤ 20 µs per step (issue 2); issue
22 point 4 aims at ≤ 3× the reference. Also measured in the same run: the same model with the
Newton solve of (22) at every sample, per chain (`SegmentModel(params, exact=True)`, the step
before the Ogden table and the fused chains), against the same reference.
"""
import math

from bellows_ros.bench import Result, timing
from bellows_ros.config.segment import load_segment_params
from bellows_ros.models.segment import previous_torques, SegmentModel

TARGET = 20e-6


def _inputs(count=4000):
    """
    Return one cycle of (psi, psi_dot, p1, p2).

    Chain 1 at 4 bar, chain 2 at 1.5 bar, Ψ swinging ±1.3 rad.
    """
    rows = []
    for k in range(count):
        phase = 2.0 * math.pi * k / count
        rows.append((1.3 * math.sin(phase), 1.3 * math.cos(phase) * 2.0 * math.pi,
                     4.0e5 + 2e4 * math.sin(3 * phase),
                     1.5e5))
    return rows


def previous_step(params):
    """Step the previous model (34) alone (the reference cost): the 1 kHz step's own terms."""
    p0, span = params.p0, 1.0 / (params.p_max - params.p0)
    terms = previous_torques(params)

    def step(psi, psi_dot, p1, p2):
        return terms(psi, psi_dot, (p1 - p0) * span, (p2 - p0) * span)[2]
    return step


def _cycling(step, rows):
    index = [0]
    count = len(rows)

    def call():
        i = index[0]
        index[0] = i + 1 if i + 1 < count else 0
        return step(*rows[i])
    return call


def run(quick=False):
    params = load_segment_params()
    rows = _inputs()
    calls = 20_000 if quick else 200_000
    model = SegmentModel(params)
    reference = timing('segment: previous model (34) step', _cycling(previous_step(params), rows),
                       calls)
    full = timing('segment: paper A model step (both chains)', _cycling(model.step, rows), calls,
                  reference=reference, target=TARGET)
    newton = timing('segment: paper A model step, Newton solve per chain (exact=True)',
                    _cycling(SegmentModel(params, exact=True).step, rows), calls,
                    reference=reference)
    overhead = timing('segment: loop overhead (empty step)', _cycling(lambda *a: None, rows),
                      calls)
    full.extra['minus_loop_overhead'] = full.value - overhead.value
    return [reference, full, newton, Result(overhead.name, overhead.value, 's', calls)]
