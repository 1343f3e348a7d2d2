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
The doctor on drawn actuators (`bellows bench --only doctor_devices`): a seeded subset.

The devices are drawn as the bench draws them; the doctor gets only each record (and the
device's measured geometry), never the hidden effect.
"""
import re

import pytest

from bellows_ros.bench import devices, doctor_devices as bench
from bellows_ros.errors import BellowsError


def test_drawn_devices_differ_repeat_and_keep_their_physics_with_an_effect():
    first, again, other = (devices.draw_actuator(s) for s in (5, 5, 6))
    assert first == again and first.params != other.params and first.plant != other.plant
    leaky = devices.draw_actuator(5, ('air_leak',))
    assert leaky.params == first.params and leaky.plant == first.plant
    low, high = devices.EFFECT_RANGES['air_leak']['conductance'][1:]
    assert low <= leaky.effects['air_leak']['conductance'] <= high
    record = devices.actuator_device_record(first)
    assert abs(record['t'][1] - record['t'][0] - 1.0 / first.rate) < 1e-9


def test_a_null_device_and_a_buckling_device():
    """The buckling device's onset lies at ambient pressure (p_cr 123 Pa, x_cr 4.6 mm)."""
    rows = [bench.diagnose_device(bench.draw(0, None)),
            bench.diagnose_device(bench.draw(0, 'buckling@ambient'), 'buckling@ambient')]
    null, buckled = rows
    assert null['named'] == [] and null['size'] == null['raw_size'] == 0.0
    assert buckled['size'] > bench.DUE          # this draw's buckling shows in its record
    assert buckled['named'] == ['buckling']
    results = {r.name: r for r in bench.summarise(rows, ('buckling',))}
    assert results['doctor_devices.buckling@ambient.named'].value == 1.0
    assert results['doctor_devices.none.false_names'].value == 0.0


def test_the_drawn_buckling_spans_the_physical_range_beyond_the_old_fit():
    """
    Issue 32: the generator drew inside the fit's own range (p_cr 10-300 kPa, x_cr 5-30 mm).

    Now the physical range, edges included: onsets below 5 kPa and beyond 300 kPa, x_cr below
    5 mm and beyond 80 mm; the 'ambient' kind within 2 kPa of ambient, the 'travel_end' kind at
    the record's top spring peak; k_b never makes the spring lose more than it carries.
    """
    shapes = [devices.draw_actuator(seed, ('buckling',)) for seed in range(60)]
    onsets = [(d.params.buckling.critical_pressure, d.params.buckling.critical_compression)
              for d in shapes]
    assert min(p for p, _ in onsets) < 5e3 and max(p for p, _ in onsets) > 3e5
    assert min(x for _, x in onsets) < 5e-3 and max(x for _, x in onsets) > 0.08
    for seed in range(10):
        ambient = devices.draw_actuator(seed, ('buckling',), 'ambient').params.buckling
        assert 1e2 <= ambient.critical_pressure <= 2e3
        end = devices.draw_actuator(seed, ('buckling',), 'travel_end')
        assert 0.85 <= end.params.buckling.critical_compression / end.spring_range[1] <= 1.0
    for device in shapes[:10]:
        shape = {k: getattr(device.params.buckling, k) for k in
                 ('stiffness_loss', 'critical_pressure', 'critical_compression')}
        assert devices.within_carried(device.params, shape, device.spring_range[1]) == \
            pytest.approx(shape['stiffness_loss'])


def test_two_cause_rows_are_judged_per_cause_and_kinds_parse():
    """A two-cause device: each cause named where due on its own; a third name is false."""
    def row(seed, kind, causes, named, sizes):
        return {'seed': seed, 'kind': kind, 'cause': causes[0] if causes else None,
                'causes': causes, 'named': named, 'gain': 0.9, 'unexplained': False,
                'sizes': {c: (s, s) for c, s in zip(causes, sizes)},
                'whys': {c: 'missed' for c in causes if c not in named}, 'seconds': 1.0}
    both = ['buckling', 'air_leak']
    rows = [row(1, 'buckling+air_leak', both, both, (20.0, 9.0)),
            row(2, 'buckling+air_leak', both, ['air_leak'], (15.0, 9.0)),
            row(3, 'buckling+air_leak', both, ['buckling'], (15.0, 1.0)),   # leak not due
            row(4, 'air_leak', ['air_leak'], ['air_leak', 'sensor_lag'], (9.0,)),
            row(5, None, [], [], ())]
    results = {r.name: r for r in bench.summarise(rows)}
    assert results['doctor_devices.buckling+air_leak.buckling.named'].value == 2 / 3
    assert results['doctor_devices.buckling+air_leak.air_leak.named'].value == 1.0
    assert 'seed 2' in results['doctor_devices.buckling+air_leak.buckling.named'].extra['misses']
    none = results['doctor_devices.none.false_names']
    assert none.value == 0.0 and none.extra['false_names_all_devices'].startswith('1 of 5')
    assert bench.parse_kinds('none:2, buckling@ambient', 3) == [(None, 2), ('buckling@ambient', 3)]
    with pytest.raises(BellowsError, match='buckling@nowhere'):
        bench.parse_kinds('buckling@nowhere', 1)


def test_an_effect_the_baselines_own_parameters_take_up_is_not_due():
    """
    A play whose chamber never reverses is a constant offset, which the encoder's zero is.

    Backlash device 0 (seed 7100): the lead screw travels down the whole record. Its raw change is
    above DUE, but the baseline's encoder zero takes nearly all of it. On device 3 the chamber
    reverses and the play shows at every reversal: the size stays near the raw change.
    """
    monotone, reversing = bench.draw(0, 'backlash'), bench.draw(3, 'backlash')
    size, raw = bench.effect_size(monotone)
    assert raw > bench.DUE and size < 0.3 * raw
    size, raw = bench.effect_size(reversing)
    assert size > bench.DUE and size > 0.8 * raw
    assert bench.effect_size(bench.draw(0, None)) == (0.0, 0.0)


@pytest.mark.slow  # one device per cause and a null device: 7 diagnoses, a few minutes
def test_one_device_per_cause_names_it_or_says_why_in_numbers():
    """
    The CI subset: one drawn device per cause; no false names, and every miss says why.

    The 90 % naming target is the full bench's (20 devices per cause,
    bench_results/0.1.0/notebook.md): on one device a rate is 0 or 1. What holds for every
    device is the contract: no false names, and a due cause that is not named comes with a reason
    in numbers (or `unexplained`).
    """
    rows = bench.run_devices(1, progress=False)
    for row in rows:
        missed = row['cause'] is not None and row['cause'] not in row['named']
        if missed and row['size'] > bench.DUE:
            assert re.search(r'\d', row['why']) or row['unexplained'], row
    for result in bench.summarise(rows):
        if result.name.endswith('.named'):
            assert result.extra['false_name_rate_null'] <= bench.TARGET_FALSE
            assert result.extra['false_name_rate_other_causes'] <= bench.TARGET_FALSE
        else:
            assert result.value <= bench.TARGET_FALSE, result.extra['named']
