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
/diagnostics for every node: one DiagnosticStatus per loop or device group, about once a second.

Reported per loop: achieved rate, loop compute time p50/p99, period p99, lateness p99, deadline
misses (from `hardware.loop_timing.LoopStats`), the scheduling policy (SCHED_FIFO when granted),
the CPU latency limit in force (the least of every process's request; nan where not readable),
plus whatever counters the node passes (link health, stale data, rejected samples). Level: ERROR
when the link is down, WARN on new deadline misses or stale data since the last report, else OK.
"""
import time

from bellows_ros.runtime import realtime

# diagnostic_msgs/DiagnosticStatus levels (a `byte`: bytes in rclpy, int on the DDS runtime).
OK, WARN, ERROR, STALE = 0, 1, 2, 3
PERIOD = 1.0  # s between reports


class LoopReport:
    """Turns a LoopStats into rate/timing key-values, remembering the previous report for rates."""

    def __init__(self, stats):
        self.stats = stats
        self._count, self._misses, self._time = 0, 0, time.monotonic()

    def values(self):
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


def status(node, name, values, level=OK, message='', hardware_id=''):
    """Build a DiagnosticStatus of `node`'s runtime with `values` (dict) as string key-values."""
    msg = node.msg
    return msg.DiagnosticStatus(
        level=bytes([level]) if isinstance(msg.DiagnosticStatus.OK, bytes) else level,
        name=name, message=message or ('OK' if level == OK else ''), hardware_id=hardware_id,
        values=[msg.KeyValue(key=str(k), value=str(v)) for k, v in values.items()])


def publish(node, publisher, statuses):
    array = node.msg.DiagnosticArray(status=list(statuses))
    array.header.stamp = node.get_clock().now().to_msg()
    publisher.publish(array)
