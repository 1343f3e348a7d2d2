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
The `bellows diagnose` bench (bench/doctor.py): its file, its median and what it reports.

Even the quick run diagnoses a 60 s record for most of a minute, so `run` is driven here with a
short record, a stand-in for `diagnose` that says what it was given, and a clock of its own: the
Result fields are checked exactly, and no time is measured. The doctor itself is tested in the
doctor's own test modules.
"""
import types

import numpy as np
import pytest

from bellows_ros.bench import doctor as bench
from bellows_ros.config.actuator import load_actuator
from bellows_ros.io.data import read_table
from bellows_ros.papers.actuator_experiments import actuator_record


def clock(*ticks):
    """Stand in for the module's `time`: perf_counter returns `ticks` in turn (s)."""
    return types.SimpleNamespace(perf_counter=iter(ticks).__next__)


def test_the_written_record_is_what_the_doctor_reads_back(tmp_path):
    config = load_actuator()
    record = actuator_record(*config, bench.EFFECTS, seed=1, duration=1.0)
    path = tmp_path / 'record.csv'
    bench._write(path, record)
    table = read_table(path, 'actuator')
    assert len(table) == len(record['t']) == 1000
    for name in ('t', 'x_c', 'x_s', 'p', 'f'):
        # 10 significant digits (`fmt='%.10g'`)
        np.testing.assert_allclose(table[name], record[name], rtol=1e-9, atol=1e-12,
                                   err_msg=name)


def test_median_time_is_the_median_of_the_repeats_and_returns_the_last_result(monkeypatch):
    monkeypatch.setattr(bench, 'time', clock(0.0, 5.0, 10.0, 11.0, 20.0, 23.0))
    calls = []
    median, result = bench._median_time(lambda: calls.append(len(calls)) or len(calls), 3)
    assert (median, result, len(calls)) == (3.0, 3, 3)     # repeats of 5, 1 and 3 s


@pytest.mark.parametrize('quick, duration, repeats', [(True, 60.0, 1), (False, 600.0, 3)])
def test_a_run_times_the_baseline_then_the_full_search_on_the_same_file(
        monkeypatch, quick, duration, repeats):
    asked, given = [], []

    def short_record(params, plant, effects, seed, duration):
        asked.append((effects, seed, duration))
        return actuator_record(params, plant, effects, seed=seed, duration=2.0)

    def diagnose(system, table, config, causes):
        given.append((system, len(table), causes))
        return types.SimpleNamespace(causes=('air_leak', 'sensor_lag'), gain=0.97012,
                                     record=np.zeros(400))
    monkeypatch.setattr(bench, 'actuator_record', short_record)
    monkeypatch.setattr(bench, 'diagnose', diagnose)
    # each baseline repeat takes 2 s, each full diagnosis 8 s
    ticks = [t for k in range(repeats) for t in (10.0 * k, 10.0 * k + 2.0)]
    ticks += [t for k in range(repeats) for t in (100.0 + 10.0 * k, 108.0 + 10.0 * k)]
    monkeypatch.setattr(bench, 'time', clock(*ticks))
    reference, full = bench.run(quick=quick)
    assert asked == [(bench.EFFECTS, 1, duration)]
    # the baseline alone (no candidate causes), then the search over every cause
    assert given == [('actuator', 2000, ())] * repeats + [('actuator', 2000, None)] * repeats
    assert (reference.name, reference.value, reference.unit) == \
        ('doctor: read + baseline only', 2.0, 's')
    assert reference.samples == full.samples == repeats and reference.extra == {'rows': 2000}
    assert reference.reference is None and reference.target is None
    assert full.name == 'doctor: diagnose actuator, 2000 rows at 1 kHz'
    assert (full.value, full.reference, full.ratio, full.target) == \
        (8.0, reference.name, 4.0, 60.0)     # issue 6: under 60 s per diagnosis
    assert full.extra == {'rows': 2000, 'causes': ['air_leak', 'sensor_lag'],
                          'heldout_gain': '97.0 %', 'fitted_samples': 400}
