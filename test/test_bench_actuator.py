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
The paper B actuator bench (bench/actuator.py): what it reports and what it feeds the timed calls.

A quick run takes about a second. Its figures are times on a shared machine, so only their
names, units, references, ratios and targets are checked, never a time.
"""
import types

import pytest

from bellows_ros.bench import actuator as bench
from bellows_ros.config.actuator import load_actuator
from bellows_ros.models.stiffness_map import stiffness_range

REFERENCE = 'reference: math.sqrt call'
GEOMETRY = 'reference: V_geo (4) of one bellows'
# issue 3's targets, s
TARGETS = {'actuator forward: evaluate -> (P, F, K)': 10e-6,
           'actuator inverse: compression_for_stiffness': 50e-6,
           'actuator plant step (dt = 1 ms, no effects)': 100e-6,
           'actuator plant step (dt = 1 ms, all effects)': 100e-6}
MODEL_CALLS = ('actuator forward: evaluate -> (P, F, K)',
               'actuator inverse: compression_for_stiffness', 'actuator estimate_gas')


@pytest.fixture(scope='module')
def results():
    return {r.name: r for r in bench.run(quick=True)}


def test_the_quick_run_reports_each_figure_once_in_seconds(results):
    assert list(results) == [REFERENCE, GEOMETRY, *MODEL_CALLS,
                             'actuator plant step (dt = 1 ms, no effects)',
                             'actuator plant step (dt = 1 ms, all effects)',
                             'actuator evaluate_array, per row']
    assert all(r.unit == 's' and r.value > 0.0 for r in results.values())
    rows = results['actuator evaluate_array, per row']
    # quick: 2000 calls each
    assert {r.samples for r in results.values() if r is not rows} == {2000}
    assert rows.samples == rows.extra['rows'] == 60000


def test_every_ratio_is_against_the_reference_of_the_same_run(results):
    reference = results[REFERENCE]
    assert reference.reference is None and reference.ratio is None
    for name, result in results.items():
        if name != REFERENCE:
            assert result.reference == REFERENCE, name
            assert result.ratio == pytest.approx(result.value / reference.value, rel=1e-12)
    geometry = results[GEOMETRY]
    for name in MODEL_CALLS:
        # a string in `extra`, printed as it is (not a time in µs)
        assert results[name].extra['ratio_to_V_geo'] == \
            f'{results[name].value / geometry.value:.1f}'
    assert all('ratio_to_V_geo' not in r.extra for n, r in results.items()
               if n not in MODEL_CALLS)


def test_the_targets_are_the_issues(results):
    assert {name: r.target for name, r in results.items() if r.target is not None} == TARGETS


def test_the_array_figure_is_per_row_of_the_median_of_three_repeats(monkeypatch):
    # a clock of the bench's own: the three repeats of evaluate_array take 3, 1 and 2 s
    ticks = iter([0.0, 3.0, 10.0, 11.0, 20.0, 22.0])
    monkeypatch.setattr(bench, 'time', types.SimpleNamespace(perf_counter=lambda: next(ticks)))
    results = {r.name: r for r in bench.run(quick=True)}
    rows = results['actuator evaluate_array, per row']
    assert rows.extra == {'rows': 60000, 'total_s': 2.0}
    assert rows.value == pytest.approx(2.0 / 60000, rel=1e-12)
    assert rows.ratio == pytest.approx(rows.value / results[REFERENCE].value, rel=1e-12)
    assert 'p99' not in rows.extra and all('p99' in results[name].extra for name in TARGETS)


def test_no_timed_call_repeats_the_previous_ones_arguments(monkeypatch):
    # the forward and inverse calls record what they are given, then do their work
    calls = {'forward': [], 'inverse': []}
    evaluate, inverse = bench.evaluate, bench.compression_for_stiffness

    def recorded_evaluate(params, x_c, x_s):
        calls['forward'].append((x_c, x_s))
        return evaluate(params, x_c, x_s)

    def recorded_inverse(params, k, gas):
        calls['inverse'].append((k, gas))
        return inverse(params, k, gas)
    monkeypatch.setattr(bench, 'evaluate', recorded_evaluate)
    monkeypatch.setattr(bench, 'compression_for_stiffness', recorded_inverse)
    bench.run(quick=True)
    params = load_actuator().model
    forward, targets = calls['forward'], calls['inverse']
    assert len(forward) == len(targets) == 3000           # 1000 warm-up calls, 2000 timed
    assert all(a != b for a, b in zip(forward, forward[1:]))
    assert all(a != b for a, b in zip(targets, targets[1:]))
    assert all(params.chamber.x_min <= x_c <= params.chamber.x_max and 0.0 <= x_s <= 0.02
               for x_c, x_s in forward)
    # the inverse is timed on stiffnesses the gas can reach (a slow leak, a warmer day)
    for k, gas in targets[:997]:
        assert 0.97 * params.p_ref <= gas <= 1.03 * params.p_ref
        k_min, k_max = stiffness_range(params, gas)
        assert k_min <= k <= k_max
