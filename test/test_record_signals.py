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
A recording survives being stopped: SIGINT, SIGTERM, two quick SIGINTs, and SIGKILL + reindex.

A publisher in this process numbers its messages (std_msgs/Float64 data = 0, 1, 2, ...) at about
500 Hz; `bellows record` runs as a child and is stopped by a signal. Afterwards the bag must open
in rosbags and in the official MCAP reader, and hold every message the recorder received (it
prints its counts) — after SIGKILL, every message published up to the last second before the
kill, once `bellows reindex` has rebuilt the bag. The counts kept are printed for the record.
"""
import os
from pathlib import Path
import signal
import subprocess
import sys
import threading
import time

from mcap.reader import make_reader
from node_processes import free_domain
import probe
import pytest
from rosbags.rosbag2 import Reader
from rosbags.typesys import get_typestore, Stores

from bellows_ros.runtime.messages import msg

# each case records for a few seconds
pytestmark = [pytest.mark.slow, pytest.mark.realtime]

STORE = get_typestore(Stores.ROS2_JAZZY)
BELLOWS = str(Path(sys.executable).with_name('bellows'))
TOPIC = '/actuator/stiffness'


def numbers_in_rosbags(bag):
    with Reader(bag) as reader:
        return [STORE.deserialize_cdr(raw, c.msgtype).data
                for c, _, raw in reader.messages()]


def disorder(bag):
    """
    Where the file's messages (in file order) are out of number order: for a failure's message.

    Each as (index, (log time ns, number) before, at), with the chunks' time ranges.
    """
    (path,) = [p for p in Path(bag).iterdir() if p.suffix == '.mcap']
    with open(path, 'rb') as stream:
        reader = make_reader(stream)
        rows = [(m.log_time, STORE.deserialize_cdr(m.data, 'std_msgs/msg/Float64').data)
                for _, _, m in reader.iter_messages(log_time_order=False)]
        chunks = [(c.message_start_time, c.message_end_time)
                  for c in reader.get_summary().chunk_indexes]
    return ([(i, rows[i - 1], rows[i]) for i in range(1, len(rows))
             if rows[i][1] < rows[i - 1][1]][:5], chunks)


def count_in_mcap(bag):
    """Messages the official MCAP reader finds (it reads the summary the footer points to)."""
    (path,) = [p for p in Path(bag).iterdir() if p.suffix == '.mcap']
    with open(path, 'rb') as stream:
        return sum(1 for _ in make_reader(stream).iter_messages())


class NumberedPublisher:
    """Publish 0, 1, 2, ... on TOPIC at about 500 Hz, noting when each went out."""

    def __init__(self):
        self.node = probe.Node('numbered_publisher')
        self.publisher = self.node.create_publisher(msg.Float64, TOPIC, 1000)
        self.sent = []  # time.monotonic() of each number
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)

    def _run(self):
        while not self.stop.is_set():
            self.publisher.publish(msg.Float64(data=float(len(self.sent))))
            self.sent.append(time.monotonic())
            time.sleep(0.002)


@pytest.fixture
def recording(tmp_path, monkeypatch):
    """Start `bellows record` and a numbered publisher; yield (recorder, publisher, bag)."""
    domain = free_domain()
    monkeypatch.setenv('ROS_DOMAIN_ID', domain)
    bag = tmp_path / 'bag'
    recorder = subprocess.Popen([BELLOWS, 'record', '--output', str(bag), '--topics', TOPIC],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                env=dict(os.environ, ROS_DOMAIN_ID=domain))
    probe.init()
    publisher = NumberedPublisher()
    try:
        end = time.monotonic() + 30
        while publisher.publisher.get_subscription_count() == 0:
            assert time.monotonic() < end and recorder.poll() is None, recorder.stderr.read()
            time.sleep(0.02)
        time.sleep(0.5)  # the recorder's reader has matched ours too
        publisher.thread.start()
        yield recorder, publisher, bag
    finally:
        publisher.stop.set()
        if recorder.poll() is None:
            recorder.kill()
            recorder.wait()
        probe.shutdown()


def recorded_count(stdout):
    for line in stdout.splitlines():
        if line.startswith(f'{TOPIC}:'):
            return int(line.split()[1])
    raise AssertionError(stdout)


# 'SIGINT held': Ctrl-C every 10 ms until the recorder has ended, into its closing and its
# interpreter's exit (where Python restores the default handlers: a recorder killed there, exit
# status -2, was seen once in CI with two SIGINTs).
@pytest.mark.parametrize('signals', [[signal.SIGINT], [signal.SIGTERM],
                                     [signal.SIGINT, signal.SIGINT], [signal.SIGINT] * 300],
                         ids=['SIGINT', 'SIGTERM', 'SIGINT twice', 'SIGINT held'])
def test_a_stopped_recording_opens_with_every_message_received(recording, signals):
    recorder, publisher, bag = recording
    time.sleep(3.0)
    for signum in signals:
        if recorder.poll() is not None:
            break
        recorder.send_signal(signum)
        time.sleep(0.01)
    out, err = recorder.communicate(timeout=30)
    publisher.stop.set()
    assert recorder.returncode == 0, err
    received = recorded_count(out)
    numbers = numbers_in_rosbags(bag)
    assert len(numbers) == received == count_in_mcap(bag)
    assert numbers == sorted(numbers), disorder(bag)  # seen once (08:20 UTC run), not since
    assert received > 500
    print(f'{[signal.Signals(s).name for s in signals]}: published {len(publisher.sent)}, '
          f'received and kept {received}')


def test_a_killed_recording_is_rebuilt_by_reindex_up_to_the_last_second(recording):
    recorder, publisher, bag = recording
    time.sleep(4.0)
    recorder.send_signal(signal.SIGKILL)
    killed = time.monotonic()
    recorder.wait()
    publisher.stop.set()
    assert not (bag / 'metadata.yaml').exists()      # what the kill leaves: no reader opens it
    result = subprocess.run([BELLOWS, 'reindex', str(bag)], capture_output=True, text=True,
                            timeout=60)
    assert result.returncode == 0, result.stderr
    numbers = numbers_in_rosbags(bag)
    assert count_in_mcap(bag) == len(numbers)
    # Every message published more than a second (the flush period) and a margin for delivery
    # before the kill is in the rebuilt bag.
    due = sum(1 for sent in publisher.sent if sent < killed - 1.0 - 0.3)
    assert set(range(due)) <= {int(n) for n in numbers}, (due, len(numbers))
    damaged = [p for p in bag.iterdir() if p.name.endswith('.mcap.damaged')]
    assert len(damaged) == 1                         # the original is kept, not deleted
    print(f'SIGKILL: published {len(publisher.sent)}, due (> 1.3 s before the kill) {due}, '
          f'kept after reindex {len(numbers)}')
    again = subprocess.run([BELLOWS, 'reindex', str(bag)], capture_output=True, text=True,
                           timeout=60)
    assert again.returncode == 0 and 'nothing to do' in again.stdout


@pytest.mark.parametrize('what', ['missing', 'file', 'empty directory', 'two files'])
def test_reindex_of_something_that_is_not_a_bag_is_one_line(tmp_path, what):
    target = tmp_path / 'x'
    if what == 'file':
        target.write_text('not a bag')
    elif what == 'empty directory':
        target.mkdir()
    elif what == 'two files':
        target.mkdir()
        (target / 'a.mcap').write_bytes(b'')
        (target / 'b.mcap').write_bytes(b'')
    result = subprocess.run([BELLOWS, 'reindex', str(target)], capture_output=True, text=True,
                            timeout=60)
    assert result.returncode == 2
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
