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
A recording has one writer (issue #30, class 2, the readers' side).

A process holding the bag's writer lock (bag_lock: an exclusive flock on
<bag>/.bellows-writer.lock, as the recorder holds it) makes every reader refuse the bag in one
line naming it, exit 2, and reindex leave it as it is; released, the same bag reads. The holder is
a child process taking the flock itself, so the test holds the protocol, not this module's code.
"""
import os
import subprocess
import sys
import threading
import time

from bag_messages import write_actuator_bag
import numpy as np
import pytest
from rosbags.rosbag2.enums import StoragePlugin

from bellows_ros.cli import main

LOCK = '.bellows-writer.lock'


def write_bag(path, n=400, wrench_rows=None, layout='sample'):
    """Write an actuator bag of `n` samples at 1 kHz; the force only in the rows `wrench_rows`."""
    start = 5 * 10 ** 9
    wrench_rows = range(n) if wrench_rows is None else wrench_rows
    rows = [(start + k * 1_000_000, 0.01 + 1e-5 * np.sin(k / 30), 0.002 + 1e-3 * np.sin(k / 50),
             1.2e5 + 100.0 * np.sin(k / 40), 3.0 + np.sin(k / 50) if k in wrench_rows else None)
            for k in range(n)]
    return write_actuator_bag(path, rows, StoragePlugin.MCAP, layout=layout, version=9)


def kill_bag(bag):
    """Leave what a SIGKILL leaves: no metadata.yaml, the MCAP cut inside its last records."""
    (bag / 'metadata.yaml').unlink()
    mcap = next(bag.glob('*.mcap'))
    os.truncate(mcap, int(mcap.stat().st_size * 0.7))


class Holder:
    """A child process holding the bag's writer lock (flock LOCK_EX), as a recorder does."""

    CODE = ('import fcntl, os, sys\n'
            'fd = os.open(sys.argv[1], os.O_RDWR | os.O_CREAT, 0o644)\n'
            'fcntl.flock(fd, fcntl.LOCK_EX)\n'
            'os.write(fd, b"pid %d, bellows record\\n" % os.getpid())\n'
            'print("held", flush=True)\n'
            'sys.stdin.read()\n')

    def __init__(self, bag):
        self.process = subprocess.Popen([sys.executable, '-c', self.CODE, str(bag / LOCK)],
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        assert self.process.stdout.readline().strip() == 'held'

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait(timeout=30)


def one_line(capsys, *fragments):
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and 'Traceback' not in err, err
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


def tree(directory):
    return {str(p.relative_to(directory)): p.read_bytes() for p in sorted(directory.rglob('*'))
            if p.is_file() and p.name != LOCK}


READERS = {
    'export': 'export actuator {bag} --output {tmp}/o.csv',
    'identify': 'identify actuator {bag} --output {tmp}/p.yaml --quiet',
    'diagnose': 'diagnose actuator {bag} --report {tmp}/report --quiet',
    'stiffness': 'stiffness {bag}',
}


@pytest.mark.parametrize('command', sorted(READERS))
def test_a_bag_being_written_is_refused_by_every_reader(tmp_path, capsys, command):
    bag = write_bag(tmp_path / 'bag')
    before = tree(bag)
    with Holder(bag):
        argv = READERS[command].format(bag=bag, tmp=tmp_path).split()
        assert main(argv) == 2
        one_line(capsys, str(bag), 'being written', 'pid ')
    assert tree(bag) == before
    assert not (tmp_path / 'o.csv').exists() and not (tmp_path / 'report').exists()


def test_reindex_leaves_a_bag_being_written_as_it_is(tmp_path, capsys):
    bag = write_bag(tmp_path / 'bag')
    kill_bag(bag)
    before = tree(bag)
    with Holder(bag) as holder:
        assert main(['reindex', str(bag)]) == 2
        one_line(capsys, str(bag), 'being written')
        assert tree(bag) == before
        holder.process.stdin.close()
        holder.process.wait(timeout=30)
    assert main(['reindex', str(bag)]) == 0  # the writer gone: repaired
    assert (bag / 'metadata.yaml').exists() and not (bag / LOCK).exists()


def test_a_released_bag_reads_and_the_lock_file_goes_with_its_holder(tmp_path, capsys):
    from bellows_ros.io.bag_lock import hold
    bag = write_bag(tmp_path / 'bag')
    with hold(bag):
        assert (bag / LOCK).read_text().startswith(f'pid {os.getpid()}, bellows record')
        assert main(['export', 'actuator', str(bag), '--output', str(tmp_path / 'o.csv')]) == 2
    assert not (bag / LOCK).exists()
    assert main(['export', 'actuator', str(bag), '--output', str(tmp_path / 'o.csv')]) == 0
    assert len((tmp_path / 'o.csv').read_text().splitlines()) == 401


def test_a_second_writer_is_refused(tmp_path):
    from bellows_ros.io.bag_lock import BagBeingWritten, hold
    bag = write_bag(tmp_path / 'bag')
    with Holder(bag):
        with pytest.raises(BagBeingWritten, match='being written'):
            with hold(bag):
                pass


def test_reindex_refuses_a_storage_file_that_grows_without_a_lock(tmp_path, capsys):
    """A recorder that takes no lock (ros2 bag record, an older bellows record): its file grows."""
    bag = write_bag(tmp_path / 'bag')
    kill_bag(bag)
    mcap = next(bag.glob('*.mcap'))
    stop = threading.Event()

    def grow():
        with open(mcap, 'ab') as stream:
            while not stop.wait(0.2):
                stream.write(b'\0' * 100)
                stream.flush()
    writer = threading.Thread(target=grow)
    writer.start()
    try:
        time.sleep(0.3)
        assert main(['reindex', str(bag)]) == 2
    finally:
        stop.set()
        writer.join()
    one_line(capsys, str(bag), 'still being written')
    assert not (bag / 'metadata.yaml').exists()
    assert not list(bag.glob('*.damaged'))


def test_metadata_after_reindex_counts_what_the_bag_holds(tmp_path, capsys):
    from rosbags.rosbag2 import Reader
    bag = write_bag(tmp_path / 'bag')
    kill_bag(bag)
    assert main(['reindex', str(bag)]) == 0
    with Reader(bag) as reader:
        claimed = {c.topic: c.msgcount for c in reader.connections}
        held = {}
        for connection, _, _ in reader.messages():
            held[connection.topic] = held.get(connection.topic, 0) + 1
    assert claimed == held


def test_a_killed_bag_points_to_reindex(tmp_path, capsys):
    bag = write_bag(tmp_path / 'bag')
    kill_bag(bag)
    assert main(['export', 'actuator', str(bag), '--output', str(tmp_path / 'o.csv')]) == 2
    one_line(capsys, 'no metadata.yaml', f'bellows reindex {bag}')


def test_the_lock_protocol_is_one_name():
    from bellows_ros.io import bag_lock
    assert bag_lock.LOCK_NAME == LOCK
