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
Absolute-deadline loop and its statistics.

Counts and sums only: no wall-clock bounds asserted.
"""
import threading
import time

import numpy as np
import pytest

from bellows_ros.hardware.loop_timing import CATCH_UP_S, device_steps, LoopStats, PeriodicLoop

pytestmark = pytest.mark.realtime  # runs alone, after the others (scripts/test.sh)


def test_stats_percentiles_and_misses():
    stats = LoopStats(window=1000)
    for i in range(1, 101):
        stats.record(period=i * 1e-5, lateness=i * 1e-6, compute=0.5e-3)
    stats.add_misses(3)
    s = stats.summary()
    assert s['count'] == 100 and s['misses'] == 3
    assert s['period_p50'] == pytest.approx(np.percentile(np.arange(1, 101) * 1e-5, 50))
    assert s['lateness_p99'] == pytest.approx(np.percentile(np.arange(1, 101) * 1e-6, 99))
    assert s['compute_max'] == pytest.approx(0.5e-3)


def test_window_keeps_only_the_newest_ticks():
    stats = LoopStats(window=10)
    for i in range(100):
        stats.record(period=float(i), lateness=0.0, compute=0.0)
    assert stats.summary()['period_max'] == 99.0
    assert stats.summary()['period_p50'] == pytest.approx(94.5)


def test_simulated_time_keeps_pace_with_wall_time_without_drift():
    loop = PeriodicLoop(1e-3)
    stop = threading.Event()
    total, ticks = 0.0, 0
    start = time.perf_counter()
    for dt in loop.ticks(stop):
        total += dt
        ticks += 1
        if ticks == 300:
            elapsed = time.perf_counter() - start
            stop.set()
    # The sum of dt is the deadline count: it may lead the wall clock by at most one period and
    # never lag it by more than one (lost slots are skipped and included in dt, not dropped).
    assert elapsed - 1e-3 <= total <= elapsed + 1e-3
    assert loop.stats.summary()['count'] == 300


def test_slow_ticks_are_counted_as_misses_and_skipped_not_replayed():
    loop = PeriodicLoop(1e-3)
    stop = threading.Event()
    dts = []
    for dt in loop.ticks(stop):
        dts.append(dt)
        if len(dts) % 20 == 0:
            time.sleep(0.0035)   # overruns: at least the next two deadlines are gone
        if len(dts) == 100:
            stop.set()
    assert loop.stats.misses >= 2 * 4
    assert sum(round(dt / 1e-3) for dt in dts) == len(dts) + loop.stats.misses


def test_a_device_takes_every_sample_a_late_tick_stands_for():
    assert device_steps(1e-3, 1e-3) == [1e-3]
    steps = device_steps(0.7, 1e-3)  # a 0.7 s stall: 700 samples, each one period
    assert len(steps) == 700 and np.allclose(steps, 1e-3) and sum(steps) == pytest.approx(0.7)
    assert device_steps(2 * CATCH_UP_S, 1e-3) == [2 * CATCH_UP_S]  # a stopped process: one step
