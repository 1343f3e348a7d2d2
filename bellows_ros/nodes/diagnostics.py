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
/diagnostics for every node, built once, after ROS's diagnostic_updater.

The same names and rules as `diagnostic_updater` (ros/diagnostics), on rclpy: diagnostic_updater
is not among the `ros-jazzy-*` wheels on PyPI (pip finds no `ros-jazzy-diagnostic-updater`; the
messages, `ros-jazzy-diagnostic-msgs`, are there), so a laptop with only Python would lack it:

- `Updater(node, period)` publishes a `diagnostic_msgs/DiagnosticArray` on the contract's
  `/diagnostics` (interfaces.DIAGNOSTICS) every `period` s, one `DiagnosticStatus` per task
  added with `add(name, fn)`, named "<node name>: <task name>" (what rqt_robot_monitor and the
  aggregator group by), with the updater's `setHardwareID` unless the task sets its own (a node
  with several devices names each one's port or CAN channel);
- a task `fn(stat)` fills a `DiagnosticStatusWrapper`: `summary(level, message)`, `add(key,
  value)`, `mergeSummary` (the worse level wins; messages of the same kind are joined with "; ");
- levels are those of diagnostic_msgs: OK=0, WARN=1, ERROR=2, STALE=3 (a `byte` field, bytes in
  rclpy's messages; `to_msg` converts). A task that raises is reported STALE with the
  error as message, so one faulty task neither stops the others nor goes silent;
- `FrequencyStatus` and `TimeStampStatus` are diagnostic_updater's rate and delay checks, with
  its messages and keys.

Bellows' own numbers of a loop (`LoopReport`): achieved rate, loop compute time p50/p99, period
p99, lateness p99, deadline misses (from `hardware.loop_timing.LoopStats`), the scheduling
policy (SCHED_FIFO when granted) and the CPU latency limit in force (the least of every
process's request; nan where not readable). docs/nodes.md lists each node's statuses.
"""
from collections import deque
import math
import threading
import time

from bellows_ros import interfaces
from bellows_ros.runtime import realtime

# diagnostic_msgs/DiagnosticStatus levels.
OK, WARN, ERROR, STALE = 0, 1, 2, 3
LEVEL_NAMES = {OK: 'OK', WARN: 'WARN', ERROR: 'ERROR', STALE: 'STALE'}
PERIOD = 1.0  # s between reports (diagnostic_updater's default diagnostic_period)


def level_of(value):
    """Return a level as an int, from an int or a `byte` field (bytes in rclpy)."""
    return value[0] if isinstance(value, (bytes, bytearray)) else int(value)


class DiagnosticStatusWrapper:
    """
    A DiagnosticStatus being filled, independent of the message classes.

    As diagnostic_updater's: `level`, `name`, `message`, `hardware_id`, `values` (a list of
    (key, value) strings, in the order added).
    """

    def __init__(self, level=OK, name='', message='', hardware_id=''):
        self.level, self.name, self.message, self.hardware_id = level, name, message, hardware_id
        self.values = []

    def summary(self, *args):
        """Set the level and message (given, or copied from another status)."""
        level, message = self._level_message(args)
        self.level, self.message = level, message

    def clearSummary(self):  # noqa: N802 (diagnostic_updater's name)
        self.summary(OK, '')

    def mergeSummary(self, *args):  # noqa: N802 (diagnostic_updater's name)
        """
        Merge a level and message into the summary: the worse level wins.

        Messages of the same kind (both OK, or both not) are joined with "; "; a worse one
        replaces an OK message.
        """
        level, message = self._level_message(args)
        if (level > OK) == (self.level > OK):
            if message:
                self.message = f'{self.message}; {message}' if self.message else message
        elif level > self.level:
            self.message = message
        self.level = max(self.level, level)

    def add(self, key, value):
        """Add a key-value; the value as its string (floats as given: format them before)."""
        self.values.append((str(key), str(value)))

    def addf(self, key, fmt, *args):
        self.add(key, fmt % args)

    def update(self, values):
        """Add every item of a dict, in order."""
        for key, value in values.items():
            self.add(key, value)

    def get(self, key, default=None):
        """Return the value added last under `key`."""
        found = [v for k, v in self.values if k == key]
        return found[-1] if found else default

    def to_msg(self, msg):
        """Return a `msg.DiagnosticStatus` (`msg`: the diagnostic_msgs.msg classes)."""
        return msg.DiagnosticStatus(
            level=bytes([self.level]), name=self.name,
            message=self.message, hardware_id=self.hardware_id,
            values=[msg.KeyValue(key=k, value=v) for k, v in self.values])

    @staticmethod
    def _level_message(args):
        if len(args) == 1:
            return args[0].level, args[0].message
        level, message = args
        return level_of(level), str(message)


class DiagnosticTask:
    """A named check: `run(stat)` fills the status (diagnostic_updater's DiagnosticTask)."""

    def __init__(self, name):
        self.name = name

    def getName(self):  # noqa: N802 (diagnostic_updater's name)
        return self.name

    def run(self, stat):
        return stat


class FunctionDiagnosticTask(DiagnosticTask):
    """A task whose `run` is a function `fn(stat)`."""

    def __init__(self, name, fn):
        super().__init__(name)
        self.fn = fn

    def run(self, stat):
        return self.fn(stat)


class DiagnosticTaskGroup(DiagnosticTask):
    """
    A task that reports several statuses at once: `statuses()` returns their wrappers.

    Not in diagnostic_updater: for a node whose concerns share numbers taken once per report
    (a controller's segment loops share its rate window). Each status is named and published as
    a task's (with the updater's hardware_id unless it has its own); should `statuses()` raise,
    one STALE status named after the group says so.
    """

    def statuses(self):
        return []


class Updater:
    """
    Run the tasks every `period` s and publish their statuses on /diagnostics.

    Parameters
    ----------
    node : bellows_ros.runtime.Node
        The node reporting: its name prefixes each status, its clock stamps the array.
    period : float
        s between two reports (a timer of the node).

    """

    def __init__(self, node, period=PERIOD):
        self.node = node
        self.period = period
        self.tasks = []
        self.hwid = ''
        self.verbose = False
        self._failed = set()  # tasks whose exception was logged (once each)
        self._lock = threading.Lock()
        self.publisher = node.publisher(interfaces.DIAGNOSTICS)
        self.timer = node.create_timer(period, self.update)

    def setHardwareID(self, hwid):  # noqa: N802 (diagnostic_updater's name)
        """Set the `hardware_id` of every status, unless a task sets its own."""
        self.hwid = hwid

    def add(self, *args):
        """Add a task: a name and a function `fn(stat)` filling the status, or a DiagnosticTask."""
        task = args[0] if len(args) == 1 else FunctionDiagnosticTask(*args)
        with self._lock:
            self.tasks.append(task)
        return task

    def removeByName(self, name):  # noqa: N802 (diagnostic_updater's name)
        """Remove the first task named `name`; True if there was one."""
        with self._lock:
            for i, task in enumerate(self.tasks):
                if task.name == name:
                    del self.tasks[i]
                    return True
        return False

    def update(self):
        """Run every task and publish (the timer calls it every `period`)."""
        self.force_update()

    def force_update(self):
        """Run every task and publish now: on a change that should not wait for the timer."""
        with self._lock:
            tasks = list(self.tasks)
        statuses = [stat for task in tasks for stat in self._run(task)]
        if statuses:
            self.publish(statuses)
        return statuses

    def broadcast(self, level, message):
        """Publish `level` and `message` as the status of every task (e.g. at shutdown)."""
        with self._lock:
            tasks = list(self.tasks)
        self.publish([DiagnosticStatusWrapper(level, task.name, message, self.hwid)
                      for task in tasks])

    def publish(self, statuses):
        """Publish wrappers as one DiagnosticArray; names get the node's "<name>: " prefix."""
        msg = self.node.msg
        prefix = f'{self.node.get_name()}: '
        out = []
        for stat in statuses:
            m = stat.to_msg(msg)
            m.name = prefix + stat.name
            out.append(m)
        array = msg.DiagnosticArray(status=out)
        array.header.stamp = self.node.get_clock().now().to_msg()
        self.publisher.publish(array)

    def _run(self, task):
        """Run one task: its statuses (a list: a group gives several)."""
        # As diagnostic_updater: ERROR with 'No message was set' until the task says otherwise.
        stat = DiagnosticStatusWrapper(ERROR, task.name, 'No message was set', self.hwid)
        try:
            if isinstance(task, DiagnosticTaskGroup):
                stats = task.statuses()
                for each in stats:
                    each.hardware_id = each.hardware_id or self.hwid
            else:
                stat = task.run(stat) or stat
                stat.name = task.name
                stats = [stat]
        except Exception as exc:  # one faulty check must not silence the others
            stat.summary(STALE, f'diagnostic task failed: {type(exc).__name__}: {exc}')
            stats = [stat]
            if task.name not in self._failed:
                self._failed.add(task.name)
                self.node.get_logger().error(f'diagnostics: task {task.name!r} raised '
                                             f'{type(exc).__name__}: {exc}')
        for stat in stats:
            if self.verbose and stat.level:
                self.node.get_logger().warn(f'{stat.name}: {LEVEL_NAMES[stat.level]}: '
                                            f'{stat.message}')
        return stats


class FrequencyStatus(DiagnosticTask):
    """
    Whether events (`tick()`) come at the expected rate (diagnostic_updater's FrequencyStatus).

    The rate is taken over the last `window_size` reports. ERROR "No events recorded." when none
    came, WARN "Frequency too low." below `min_freq * (1 - tolerance)`, WARN "Frequency too
    high." above `max_freq * (1 + tolerance)`, else OK "Desired frequency met".
    """

    def __init__(self, min_freq=0.0, max_freq=math.inf, tolerance=0.1, window_size=5,
                 name='Frequency Status', clock=time.monotonic):
        super().__init__(name)
        self.min_freq, self.max_freq = min_freq, max_freq
        self.tolerance, self.window_size = tolerance, window_size
        self._clock = clock
        self._lock = threading.Lock()
        self.count = 0
        now = clock()
        self._history = deque([(0, now)], maxlen=window_size)

    def clear(self):
        with self._lock:
            self.count = 0
            self._history = deque([(0, self._clock())], maxlen=self.window_size)

    def tick(self):
        """One event."""
        with self._lock:
            self.count += 1

    def run(self, stat):
        with self._lock:
            now, count = self._clock(), self.count
            first_count, first_time = self._history[0]
            self._history.append((count, now))
        events = count - first_count
        window = now - first_time
        freq = events / window if window > 0 else 0.0
        if events == 0:
            stat.summary(ERROR, 'No events recorded.')
        elif freq < self.min_freq * (1 - self.tolerance):
            stat.summary(WARN, 'Frequency too low.')
        elif freq > self.max_freq * (1 + self.tolerance):
            stat.summary(WARN, 'Frequency too high.')
        else:
            stat.summary(OK, 'Desired frequency met')
        stat.add('Events in window', events)
        stat.add('Events since startup', count)
        stat.add('Duration of window (s)', f'{window:f}')
        stat.add('Actual frequency (Hz)', f'{freq:f}')
        if self.min_freq == self.max_freq:
            stat.add('Target frequency (Hz)', f'{self.min_freq:f}')
        if self.min_freq > 0:
            stat.add('Minimum acceptable frequency (Hz)',
                     f'{self.min_freq * (1 - self.tolerance):f}')
        if math.isfinite(self.max_freq):
            stat.add('Maximum acceptable frequency (Hz)',
                     f'{self.max_freq * (1 + self.tolerance):f}')
        return stat


class TimeStampStatus(DiagnosticTask):
    """
    Whether stamps arrive with an acceptable delay (diagnostic_updater's TimeStampStatus).

    `tick(stamp)` with the stamp in s of the same clock as `now()`: the delay is `now() - stamp`.
    Per report: WARN "No data since last update." when nothing came, ERROR "Timestamps too far
    in future seen." for a delay below `min_acceptable`, ERROR "Timestamps too far in past seen."
    above `max_acceptable`, else OK "Timestamps are reasonable.".
    """

    def __init__(self, now, min_acceptable=-1.0, max_acceptable=5.0, name='Timestamp Status'):
        super().__init__(name)
        self.now = now
        self.min_acceptable, self.max_acceptable = min_acceptable, max_acceptable
        self._lock = threading.Lock()
        self.early_count = self.late_count = self.zero_seen_count = 0
        self._reset()

    def _reset(self):
        self.min_delta, self.max_delta, self.seen = math.inf, -math.inf, False
        self.early, self.late = False, False

    def tick(self, stamp, now=None):
        """Record a stamp, s (`now`: the time, s, if the caller has it); returns its delay, s."""
        delta = (self.now() if now is None else now) - stamp
        with self._lock:
            self.seen = True
            self.min_delta, self.max_delta = min(self.min_delta, delta), max(self.max_delta, delta)
            self.early |= delta < self.min_acceptable
            self.late |= delta > self.max_acceptable
        return delta

    def run(self, stat):
        with self._lock:
            seen, early, late = self.seen, self.early, self.late
            low, high = self.min_delta, self.max_delta
            self._reset()
        stat.summary(OK, 'Timestamps are reasonable.')
        if not seen:
            stat.summary(WARN, 'No data since last update.')
            self.zero_seen_count += 1
        else:
            if early:
                stat.summary(ERROR, 'Timestamps too far in future seen.')
                self.early_count += 1
            if late:
                stat.summary(ERROR, 'Timestamps too far in past seen.')
                self.late_count += 1
        stat.add('Earliest timestamp delay:', f'{low:f}' if seen else 'nan')
        stat.add('Latest timestamp delay:', f'{high:f}' if seen else 'nan')
        stat.add('Earliest acceptable timestamp delay:', f'{self.min_acceptable:f}')
        stat.add('Latest acceptable timestamp delay:', f'{self.max_acceptable:f}')
        stat.add('Late diagnostic update count:', self.late_count)
        stat.add('Early diagnostic update count:', self.early_count)
        stat.add('Zero seen diagnostic update count:', self.zero_seen_count)
        return stat


class LoopReport:
    """Turns a LoopStats into rate/timing key-values, remembering the previous report for rates."""

    def __init__(self, stats):
        self.stats = stats
        self._count, self._misses, self._time = 0, 0, time.monotonic()

    def values(self):
        """Return (key-values, rate since the last call in Hz, deadline misses since then)."""
        summary = self.stats.summary()
        now = time.monotonic()
        count, misses = int(summary['count']), int(summary['misses'])
        rate = (count - self._count) / max(now - self._time, 1e-9)
        new_misses = misses - self._misses
        self._count, self._misses, self._time = count, misses, now
        values = {'rate_hz': f'{rate:.1f}', 'samples': str(count), 'deadline_misses': str(misses),
                  'new_deadline_misses': str(new_misses), 'scheduling': realtime.describe(),
                  'cpu_latency_limit_us': f'{realtime.cpu_latency_in_force() * 1e6:.0f}'}
        for key in ('compute_p50', 'compute_p99', 'period_p99', 'lateness_p99'):
            values[f'{key}_us'] = f'{summary[key] * 1e6:.1f}'
        return values, rate, new_misses


def loop_summary(stat, rate, new_misses):
    """Summarize a simulated device's own loop: ERROR when it stopped, WARN on misses."""
    if rate == 0.0:
        stat.summary(ERROR, 'loop not running (no tick since the last report)')
    elif new_misses:
        stat.summary(WARN, f'{new_misses} ticks missed since the last report (host overloaded?)')
    else:
        stat.summary(OK, f'running at {rate:.0f} Hz')
    return stat


def add_model_health(stat, values, cost_us, update_ms):
    """
    Add a model-health report's numbers to `stat` (the model node's and the controller's).

    `values`: `live.ModelHealth.values()`; `cost_us`: (mean, max) of the sample path's part, µs,
    since the last report; `update_ms`: this report's comparison, ms.
    """
    for key, value in values.items():
        stat.add(key, value if isinstance(value, str) else f'{value:.6g}')
    stat.add('cost_per_sample_us', f'{cost_us[0]:.2f}')
    stat.add('cost_per_sample_max_us', f'{cost_us[1]:.1f}')
    stat.add('update_ms', f'{update_ms:.2f}')
