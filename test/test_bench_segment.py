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
The paper A segment bench (bench/segment.py): its inputs, its cycling and what it reports.

A quick run takes under a second; only names, references, ratios and targets are checked,
never a time. That `previous_step` is the previous model (34) is held in test_models_segment.py.
"""
import math

import numpy as np
import pytest

from bellows_ros.bench import segment as bench
from bellows_ros.config.segment import load_segment_params
from bellows_ros.models.segment import SegmentModel

REFERENCE = 'segment: previous model (34) step'
FULL = 'segment: paper A model step (both chains)'
NEWTON = 'segment: paper A model step, Newton solve per chain (exact=True)'
OVERHEAD = 'segment: loop overhead (empty step)'


def test_the_inputs_are_one_closed_cycle_at_the_documented_pressures():
    rows = np.array(bench._inputs(400))
    psi, psi_dot, p1, p2 = rows.T
    assert rows.shape == (400, 4)
    assert max(abs(psi)) == pytest.approx(1.3, rel=1e-3)           # Ψ swings ±1.3 rad
    assert np.all(abs(p1 - 4.0e5) <= 2e4) and np.all(p2 == 1.5e5)  # Pa: 4 bar, 1.5 bar
    # Ψ̇ is Ψ's rate over a cycle of 1 s: central differences, the cycle closing on itself
    rate = (np.roll(psi, -1) - np.roll(psi, 1)) / (2.0 / 400)
    np.testing.assert_allclose(psi_dot, rate, atol=1.3 * (2.0 * math.pi) ** 3 / 400 ** 2)


def test_the_cycle_fills_and_releases_both_strain_memories():
    model = SegmentModel(load_segment_params())
    contact = np.array([model.step(*row)[:2] for row in bench._inputs() * 2])
    for chain in contact.T:           # s̃_a of chain 1 and chain 2, m
        change = np.diff(chain)
        assert np.ptp(chain) > 0.01 and np.sum(change > 0) > 100 and np.sum(change < 0) > 100


def test_cycling_calls_the_step_with_each_row_in_turn_and_wraps():
    rows = [(k, 0.0, 0.0, 0.0) for k in range(3)]
    call = bench._cycling(lambda psi, *rest: psi, rows)
    assert [call() for _ in range(7)] == [0, 1, 2, 0, 1, 2, 0]


@pytest.fixture(scope='module')
def results():
    return bench.run(quick=True)


def test_the_quick_run_reports_the_model_against_the_previous_model(results):
    assert [r.name for r in results] == [REFERENCE, FULL, NEWTON, OVERHEAD]
    assert all(r.unit == 's' and r.samples == 20_000 and r.value > 0.0 for r in results)
    reference, full, newton, overhead = results
    for result in (full, newton):
        assert result.reference == REFERENCE
        assert result.ratio == pytest.approx(result.value / reference.value, rel=1e-12)
    assert full.target == bench.TARGET == 20e-6 and newton.target is None
    for result in (reference, overhead):
        assert result.reference is None and result.ratio is None and result.target is None


def test_the_loop_overhead_is_subtracted_from_the_models_figure_only(results):
    _, full, newton, overhead = results
    assert full.extra['minus_loop_overhead'] == pytest.approx(full.value - overhead.value,
                                                              abs=1e-15)
    assert 'minus_loop_overhead' not in newton.extra
    assert overhead.extra == {}              # a plain figure: no p99 of an empty call
