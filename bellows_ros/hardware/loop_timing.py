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
Absolute-deadline periodic loops and their timing statistics (no ROS).

Used by the simulated devices, drivers and nodes for every 1 kHz loop (docs/nodes.md, "Timing")::

    stats = LoopStats()
    loop = PeriodicLoop(period=1e-3, stats=stats)
    for dt in loop.ticks(stop_event):      # dt: time this tick stands for, s (period x ticks
    advanced)
        work(dt)
    stats.summary()   # {'count', 'misses', 'period_p50', 'period_p99', 'lateness_p50', ...} in s

API
---
- ``PeriodicLoop(period, stats=None)``; ``.ticks(stop_event) -> Iterator[float]``.
- ``LoopStats(window=10000)``; ``.record(period, lateness, compute)``, ``.add_misses(n)``,
  ``.summary() -> dict[str, float]``.
- ``LoopThread(loop, name, log, what)``: ``loop(stop_event)`` on a daemon thread from
  ``.start()`` to ``.stop()`` (restartable); a loop that raises is logged, not lost.
- ``device_steps(dt, period) -> list[float]``: the samples a simulated device takes for a tick.

Deadlines are ``t0 + k * period`` on ``time.perf_counter`` (absolute, so sleep jitter never
accumulates into drift). The loop only sleeps: ``time.sleep`` overshoots by 50-150 us (timer slack;
measured here 110 us median at normal scheduling, 70 us under SCHED_FIFO), and a busy-wait before
each deadline would cost ~10 % of a core per 1 kHz loop, CPU the driver and model nodes need on a
shared 2-core machine; the loops here are the simulated devices, whose samples are stamped on
arrival at the driver. When a tick starts more than one period late, the slots it lost are
*skipped*, not replayed in a burst, and counted as deadline misses; the returned ``dt`` then covers
the skipped slots so that simulated time keeps pace with wall time. A simulated device then takes
every sample it missed (`device_steps`), as a board with its own processor does while its host is
busy: the host reads a burst instead of a record with a hole.
"""
from collections import deque
import threading
import time

import numpy as np


# s of missed periods a simulated device catches up sample by sample; a longer stall (a stopped
# process) is one step. CI on a loaded shared machine stalled the simulated boards for 0.26-0.68 s.
CATCH_UP_S = 5.0


def device_steps(dt, period):
    """
    Return the plant steps, s, that a device sampling every `period` s takes for a tick of `dt`.

    One step per period the tick stands for (`PeriodicLoop.ticks`), so that every sample is taken
    and stamped on the device's clock; one step of `dt` when that is more than CATCH_UP_S.
    """
    steps = max(1, int(round(dt / period)))
    return [dt / steps] * steps if steps * period <= CATCH_UP_S else [dt]


class LoopStats:
    """
    Rolling timing statistics of a periodic loop (the last `window` ticks), all in seconds.

    Thread-safe: the loop thread records, a diagnostics thread reads `summary()`.
    """

    def __init__(self, window=10000):
        self._lock = threading.Lock()
        self._period = deque(maxlen=window)
        self._lateness = deque(maxlen=window)
        self._compute = deque(maxlen=window)
        self.count = 0
        self.misses = 0

    def record(self, period, lateness, compute):
        """One tick: interval since the previous tick start, start minus deadline, work time."""
        with self._lock:
            self._period.append(period)
            self._lateness.append(lateness)
            self._compute.append(compute)
            self.count += 1

    def add_misses(self, n):
        """`n` deadlines that passed without their tick running."""
        with self._lock:
            self.misses += n

    def summary(self):
        """Count and take p50/p99/max of period, lateness and compute time over the window."""
        with self._lock:
            series = {'period': np.array(self._period), 'lateness': np.array(self._lateness),
                      'compute': np.array(self._compute)}
            out = {'count': float(self.count), 'misses': float(self.misses)}
        for name, values in series.items():
            if values.size:
                p50, p99 = np.percentile(values, [50, 99])
                out.update({f'{name}_p50': float(p50), f'{name}_p99': float(p99),
                            f'{name}_max': float(values.max())})
            else:
                out.update({f'{name}_p50': float('nan'), f'{name}_p99': float('nan'),
                            f'{name}_max': float('nan')})
        return out


class PeriodicLoop:
    """
    Run a body every `period` seconds against absolute deadlines.

    Parameters
    ----------
    period : float
        Loop period, s.
    stats : LoopStats, optional
        Where each tick's timing is recorded.

    """

    def __init__(self, period, stats=None):
        if not period > 0:
            raise ValueError(f'period must be positive, got {period}')
        self.period = float(period)
        self.stats = stats if stats is not None else LoopStats()

    @staticmethod
    def _sleep_until(deadline):
        remaining = deadline - time.perf_counter()
        if remaining > 0:
            time.sleep(remaining)
        while time.perf_counter() < deadline:  # never start early: lateness stays >= 0
            pass

    def ticks(self, stop_event):
        """Yield once per period until `stop_event` is set; yields the time step dt, s."""
        period = self.period
        start = time.perf_counter()
        k = 0
        previous_start = start
        while not stop_event.is_set():
            deadline = start + k * period
            self._sleep_until(deadline)
            tick_start = time.perf_counter()
            lateness = tick_start - deadline
            skipped = int(lateness // period)
            if skipped:
                self.stats.add_misses(skipped)
                k += skipped
            k += 1
            dt = period * (1 + skipped)
            yield dt
            compute = time.perf_counter() - tick_start
            self.stats.record(tick_start - previous_start, lateness, compute)
            previous_start = tick_start


class LoopThread:
    """
    Run `loop(stop_event)` on a daemon thread named `name` from `start()` until `stop()`.

    Restartable (the simulated devices are stopped and started again in tests). A loop that raises
    (e.g. a simulated device's plant callback) is logged on `log` as "`what`: loop stopped"
    instead of its thread dying silently.
    """

    def __init__(self, loop, name, log, what):
        self._loop, self._name, self._log, self._what = loop, name, log, what
        self._stop = threading.Event()
        self._thread = None

    def start(self):
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name=self._name, daemon=True)
        self._thread.start()

    def stop(self):
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None

    def _run(self):
        try:
            self._loop(self._stop)
        except Exception:
            self._log.exception('%s: loop stopped', self._what)
            raise
