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
The diagnostics updater (nodes/diagnostics.py) against diagnostic_updater's conventions.

Unit tests on a stand-in node (the bellows Node interface: publisher, timer, name, clock, logger,
message classes), then one node process read back from /diagnostics by a plain rclpy probe.
"""
import subprocess
import sys
import textwrap
import time
import types

from builtin_interfaces.msg import Time
from node_processes import node_env
import probe
import pytest

from bellows_ros import interfaces
from bellows_ros.nodes import diagnostics as d
from bellows_ros.runtime.messages import msg as ros_msg

pytestmark = pytest.mark.realtime  # runs alone, after the others (scripts/test.sh)

# The ROS packages' classes the nodes use, and Time for the stand-in node's clock.
NODE_MSG = types.SimpleNamespace(Time=Time, **vars(ros_msg))


class FakeNode:
    """The part of the bellows Node the updater uses; records what it publishes."""

    def __init__(self, name='probe_node', msg=NODE_MSG):
        self.msg, self.name = msg, name
        self.published, self.timers, self.topics, self.logged = [], [], [], []

    def publisher(self, topic):
        self.topics.append(topic)
        return types.SimpleNamespace(publish=self.published.append)

    def create_timer(self, period, callback):
        self.timers.append((period, callback))

    def get_name(self):
        return self.name

    def get_clock(self):
        stamp = types.SimpleNamespace(to_msg=lambda: self.msg.Time(sec=7, nanosec=0))
        return types.SimpleNamespace(now=lambda: stamp)

    def get_logger(self):
        return types.SimpleNamespace(error=self.logged.append, warn=self.logged.append)


def statuses(node):
    """{name: (level, message, hardware_id, {key: value})} of the last array published."""
    return {s.name: (d.level_of(s.level), s.message, s.hardware_id,
                     {kv.key: kv.value for kv in s.values})
            for s in node.published[-1].status}


def test_the_updater_publishes_on_the_contracts_topic_once_a_period():
    node = FakeNode()
    updater = d.Updater(node)
    assert node.topics == [interfaces.DIAGNOSTICS]
    assert interfaces.DIAGNOSTICS.name == '/diagnostics'  # absolute, as diagnostic_updater's
    assert [period for period, _ in node.timers] == [d.PERIOD] == [1.0]
    updater.add('task', lambda stat: stat.summary(d.OK, 'fine'))
    node.timers[0][1]()  # the timer fires
    assert len(node.published) == 1
    assert node.published[0].header.stamp.sec == 7


def test_status_names_hardware_id_levels_and_key_values():
    node = FakeNode('driver_node')
    updater = d.Updater(node)
    updater.setHardwareID('/dev/ttyACM0')

    def board(stat):
        stat.summary(d.WARN, '3 samples missed')
        stat.add('published', 1000)
        stat.add('rate_hz', '999.5')
        return stat

    def bus(stat):
        stat.hardware_id = 'socketcan:can0'  # a task with a device of its own names it
        stat.summary(d.ERROR, 'no data from socketcan:can0')

    updater.add('actuator', board)
    updater.add(d.FunctionDiagnosticTask('arm', bus))
    updater.force_update()
    got = statuses(node)
    assert got == {
        'driver_node: actuator': (d.WARN, '3 samples missed', '/dev/ttyACM0',
                                  {'published': '1000', 'rate_hz': '999.5'}),
        'driver_node: arm': (d.ERROR, 'no data from socketcan:can0', 'socketcan:can0', {})}
    assert [s.name for s in node.published[-1].status] == ['driver_node: actuator',
                                                           'driver_node: arm']  # as added
    assert (d.OK, d.WARN, d.ERROR, d.STALE) == (0, 1, 2, 3)


def test_a_task_that_sets_nothing_is_an_error_as_in_diagnostic_updater():
    node = FakeNode()
    updater = d.Updater(node)
    updater.add('silent', lambda stat: None)
    updater.force_update()
    assert statuses(node)['probe_node: silent'][:2] == (d.ERROR, 'No message was set')


def test_a_task_that_raises_is_stale_and_the_others_still_report():
    node = FakeNode()
    updater = d.Updater(node)

    def broken(stat):
        raise KeyError('rate_hz')
    updater.add('broken', broken)
    updater.add('fine', lambda stat: stat.summary(d.OK, 'OK'))
    updater.force_update()
    updater.force_update()
    got = statuses(node)
    assert got['probe_node: broken'][0] == d.STALE
    assert "KeyError: 'rate_hz'" in got['probe_node: broken'][1]
    assert got['probe_node: fine'][:2] == (d.OK, 'OK')
    assert len(node.logged) == 1  # logged once, not once a second


def test_remove_by_name_and_broadcast():
    node = FakeNode()
    updater = d.Updater(node)
    updater.add('a', lambda stat: stat.summary(d.OK, 'a'))
    updater.add('b', lambda stat: stat.summary(d.OK, 'b'))
    assert updater.removeByName('a') and not updater.removeByName('a')
    updater.broadcast(d.STALE, 'driver stopped')
    assert statuses(node) == {'probe_node: b': (d.STALE, 'driver stopped', '', {})}


def test_a_group_reports_one_status_per_concern():
    node = FakeNode('arm_controller_node')
    updater = d.Updater(node)

    class Segments(d.DiagnosticTaskGroup):
        def statuses(self):
            return [d.DiagnosticStatusWrapper(d.OK, f'segment_{i}', 'tracking') for i in (1, 2)]
    updater.setHardwareID('none')
    updater.add(Segments('segments'))
    updater.force_update()
    assert statuses(node) == {f'arm_controller_node: segment_{i}': (d.OK, 'tracking', 'none', {})
                              for i in (1, 2)}


def test_a_group_that_raises_is_one_stale_status():
    node = FakeNode('arm_controller_node')
    updater = d.Updater(node)

    class Broken(d.DiagnosticTaskGroup):
        def statuses(self):
            raise RuntimeError('no loops')
    updater.add(Broken('segments'))
    updater.force_update()
    level, message, _, _ = statuses(node)['arm_controller_node: segments']
    assert level == d.STALE and 'RuntimeError: no loops' in message


def test_merge_summary_follows_diagnostic_updater():
    stat = d.DiagnosticStatusWrapper()
    stat.summary(d.OK, 'running at 1000 Hz')
    stat.mergeSummary(d.OK, 'inactive')              # same kind: joined
    assert (stat.level, stat.message) == (d.OK, 'running at 1000 Hz; inactive')
    stat.mergeSummary(d.WARN, '3 samples missed')    # worse: replaces an OK message
    assert (stat.level, stat.message) == (d.WARN, '3 samples missed')
    stat.mergeSummary(d.ERROR, 'link down')          # both not OK: joined, the worse level
    assert (stat.level, stat.message) == (d.ERROR, '3 samples missed; link down')
    stat.mergeSummary(d.OK, 'ignored')               # better: neither level nor message
    assert (stat.level, stat.message) == (d.ERROR, '3 samples missed; link down')
    other = d.DiagnosticStatusWrapper(d.STALE, message='stopped')
    stat.mergeSummary(other)
    assert stat.level == d.STALE
    stat.summary(other)
    assert (stat.level, stat.message) == (d.STALE, 'stopped')
    stat.clearSummary()
    assert (stat.level, stat.message) == (d.OK, '')


def test_levels_as_the_message_classes_want_them():
    """A `byte` field: bytes in rclpy's generated classes; `level_of` reads it back."""
    stat = d.DiagnosticStatusWrapper(d.WARN, 'x', 'late', 'can0')
    stat.add('k', 1.5)
    out = stat.to_msg(ros_msg)
    assert out.level == b'\x01' and d.level_of(out.level) == d.WARN
    assert out.values[0].value == '1.5' and out.hardware_id == 'can0'
    assert d.level_of(b'\x03') == d.STALE
    assert d.level_of(ros_msg.DiagnosticStatus.STALE) == d.STALE


class Clock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


def test_frequency_status_levels_messages_and_keys():
    clock = Clock()
    freq = d.FrequencyStatus(1000.0, 1000.0, tolerance=0.1, window_size=5, clock=clock)

    def report(ticks, seconds=1.0):
        for _ in range(ticks):
            freq.tick()
        clock.t += seconds
        stat = freq.run(d.DiagnosticStatusWrapper())
        return stat.level, stat.message, dict(stat.values)
    level, message, values = report(1000)
    assert (level, message) == (d.OK, 'Desired frequency met')
    assert float(values['Actual frequency (Hz)']) == pytest.approx(1000.0)
    assert float(values['Target frequency (Hz)']) == 1000.0
    assert float(values['Minimum acceptable frequency (Hz)']) == pytest.approx(900.0)
    assert float(values['Maximum acceptable frequency (Hz)']) == pytest.approx(1100.0)
    assert values['Events since startup'] == '1000'
    # The window is the last 5 reports: 3 s at 100 Hz pull the rate of 4 s below 900 Hz.
    for _ in range(3):
        level, message, values = report(100)
    assert (level, message) == (d.WARN, 'Frequency too low.')
    assert float(values['Actual frequency (Hz)']) == pytest.approx(1300 / 4)
    for _ in range(5):
        level, message, _ = report(0)
    assert (level, message) == (d.ERROR, 'No events recorded.')
    for _ in range(5):
        level, message, _ = report(2000)
    assert (level, message) == (d.WARN, 'Frequency too high.')


def test_time_stamp_status_levels_messages_and_keys():
    clock = Clock()
    status = d.TimeStampStatus(clock, min_acceptable=-0.001, max_acceptable=0.002)

    def report():
        stat = status.run(d.DiagnosticStatusWrapper())
        return stat.level, stat.message, dict(stat.values)
    assert report()[:2] == (d.WARN, 'No data since last update.')
    assert status.tick(clock.t - 0.001) == pytest.approx(0.001)
    level, message, values = report()
    assert (level, message) == (d.OK, 'Timestamps are reasonable.')
    assert float(values['Latest timestamp delay:']) == pytest.approx(0.001)
    status.tick(99.0, now=100.0)  # 1 s late, `now` given by the caller
    level, message, values = report()
    assert (level, message) == (d.ERROR, 'Timestamps too far in past seen.')
    assert values['Late diagnostic update count:'] == '1'
    status.tick(clock.t + 0.5)
    assert report()[:2] == (d.ERROR, 'Timestamps too far in future seen.')
    assert report()[2]['Zero seen diagnostic update count:'] == '2'


def test_loop_summary_says_what_is_wrong():
    def summary(rate, misses):
        stat = d.loop_summary(d.DiagnosticStatusWrapper(), rate, misses)
        return stat.level, stat.message
    assert summary(0.0, 0) == (d.ERROR, 'loop not running (no tick since the last report)')
    assert summary(990.0, 4)[0] == d.WARN and '4 ticks missed' in summary(990.0, 4)[1]
    assert summary(1000.0, 0) == (d.OK, 'running at 1000 Hz')


# A node with an updater, as the bellows nodes build theirs.
NODE = textwrap.dedent("""
    import sys
    from bellows_ros.nodes import diagnostics as d
    from bellows_ros.runtime import Node, run

    class Probe(Node):
        def __init__(self, **kwargs):
            super().__init__('diag_probe', **kwargs)
            self.diagnostics = d.Updater(self, period=0.2)
            self.diagnostics.setHardwareID('none')
            self.diagnostics.add('fine', self.fine)
            self.diagnostics.add('broken', lambda stat: 1 / 0)

        def fine(self, stat):
            stat.hardware_id = '/dev/ttyACM0'
            stat.summary(d.WARN, '2 samples missed')
            stat.add('rate_hz', '998.0')
            return stat

    sys.exit(run(Probe))
""")


@pytest.mark.slow  # a node process
def test_a_node_reports_on_diagnostics(tmp_path, monkeypatch):
    domain = '193'
    monkeypatch.setenv('ROS_DOMAIN_ID', domain)
    script = tmp_path / 'probe.py'
    script.write_text(NODE)
    process = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True,
                               env=node_env(ROS_DOMAIN_ID=domain))
    seen = {}
    probe.init()
    try:
        reader = probe.Node('diag_reader')
        reader.create_subscription(
            ros_msg.DiagnosticArray, '/diagnostics',
            lambda a: seen.update({s.name: (d.level_of(s.level), s.message, s.hardware_id,
                                            {kv.key: kv.value for kv in s.values})
                                   for s in a.status}), 10)
        end = time.monotonic() + 60
        while len(seen) < 2 and time.monotonic() < end and process.poll() is None:
            probe.spin_once(reader, timeout_sec=0.1)
        reader.destroy_node()
    finally:
        probe.shutdown()
        process.terminate()
        output = process.communicate(timeout=20)[0]
    assert seen.get('diag_probe: fine') == (d.WARN, '2 samples missed', '/dev/ttyACM0',
                                            {'rate_hz': '998.0'}), (seen, output)
    level, message, hardware_id, _ = seen['diag_probe: broken']
    assert (level, hardware_id) == (d.STALE, 'none') and 'ZeroDivisionError' in message
