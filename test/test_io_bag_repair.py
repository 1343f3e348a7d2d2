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
A killed recording made readable again (io/bag_repair.py, `bellows reindex`).

The bags are written as `bellows record` writes them: rosbags' MCAP writer, one connection per
topic, the chunk closed and flushed every "second" (`runtime.record._flush`); a kill leaves the
chunks flushed before it whole, the one being written cut, and no metadata.yaml. `repair` keeps
every message of the whole chunks, byte for byte, in a new file under the old name, and never
changes its input: the damaged file stays beside it as `<name>.mcap.damaged`, a bag that readers
open is left as it is, and a refusal changes nothing.
"""
import os
import struct

from bag_messages import actuator_messages, STORE
import pytest
from rosbags.rosbag2 import Reader, StoragePlugin, Writer

from bellows_ros.cli import main
from bellows_ros.errors import BellowsError
from bellows_ros.io.bag_lock import LOCK_NAME
from bellows_ros.io.bag_repair import DAMAGED_SUFFIX, repair
from bellows_ros.runtime.record import _flush

CHUNKS, PER_CHUNK = 6, 40   # flushes, samples per flush
TOPICS = ('/actuator/joint_states', '/actuator/chambers', '/bellows/wrench')  # 'split' layout


def record_bag(path):
    """
    Write a bag as the recorder does; return (path, file offset after each flush, messages).

    messages: (topic, log time ns, raw CDR bytes) in the order written.
    """
    offsets, written, connections = [], [], {}
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        for chunk in range(CHUNKS):
            for i in range(PER_CHUNK):
                k = chunk * PER_CHUNK + i
                ns = 5 * 10 ** 9 + k * 10 ** 6
                for topic, message in actuator_messages(ns, 0.01 + 1e-5 * k, 0.002, 1.2e5 + k,
                                                        3.0 + 1e-3 * k, layout='split'):
                    if topic not in connections:
                        connections[topic] = writer.add_connection(
                            topic, message.__msgtype__, typestore=STORE)
                    data = bytes(STORE.serialize_cdr(message, message.__msgtype__))
                    writer.write(connections[topic], ns, data)
                    written.append((topic, ns, data))
            _flush(writer)
            offsets.append(writer.storage.bio.tell())
    return path, offsets, written


def kill(bag, size):
    """Leave what a SIGKILL leaves: no metadata.yaml, the MCAP cut at `size` bytes."""
    (bag / 'metadata.yaml').unlink()
    mcap = bag / 'bag.mcap'
    os.truncate(mcap, size)
    # killed a minute ago: `repair` need not watch the file for a writer that takes no lock
    os.utime(mcap, (mcap.stat().st_atime - 60, mcap.stat().st_mtime - 60))
    return mcap.read_bytes()


def tree(directory):
    """{relative path: bytes} of every file below `directory` (the lock file aside)."""
    return {str(p.relative_to(directory)): p.read_bytes() for p in sorted(directory.rglob('*'))
            if p.is_file() and p.name != LOCK_NAME}


def messages_of(bag):
    with Reader(bag) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        return counts, [(c.topic, t, bytes(data)) for c, t, data in reader.messages()]


def by_time(messages):
    return sorted(messages, key=lambda m: (m[1], TOPICS.index(m[0])))


@pytest.fixture
def recorded(tmp_path):
    return record_bag(tmp_path / 'bag')


def test_a_killed_bag_keeps_every_whole_chunks_messages_byte_for_byte(recorded):
    bag, offsets, written = recorded
    damaged = kill(bag, (offsets[-2] + offsets[-1]) // 2)  # cut inside the last chunk
    result = repair(bag)
    assert result.repaired and result.path == bag
    kept = (CHUNKS - 1) * PER_CHUNK
    assert result.counts == {topic: kept for topic in TOPICS}
    counts, messages = messages_of(bag)
    assert counts == result.counts  # metadata.yaml counts what the file holds
    assert by_time(messages) == by_time(written[:kept * len(TOPICS)])
    # the input is kept as it was, beside the rebuilt file
    assert (bag / f'bag.mcap{DAMAGED_SUFFIX}').read_bytes() == damaged
    # what the kill left of the last chunk: the bytes after the last whole record
    assert result.truncated_bytes == len(damaged) - offsets[-2] > 0
    assert sorted(p.name for p in bag.iterdir()) == ['bag.mcap', 'bag.mcap.damaged',
                                                     'metadata.yaml']


def test_a_bag_killed_right_after_a_flush_loses_nothing(recorded):
    bag, offsets, written = recorded
    kill(bag, offsets[-1])  # every chunk whole; only the summary and footer missing
    result = repair(bag)
    assert result.counts == {topic: CHUNKS * PER_CHUNK for topic in TOPICS}
    assert result.truncated_bytes == 0
    assert by_time(messages_of(bag)[1]) == by_time(written)


def test_a_corrupt_record_length_ends_what_is_kept(recorded):
    # The fourth chunk's length field (after its 1-byte opcode) says 1 TiB: the reader takes no
    # record longer than the file, and what came before is kept.
    bag, offsets, written = recorded
    (bag / 'metadata.yaml').unlink()
    mcap = bag / 'bag.mcap'
    data = bytearray(mcap.read_bytes())
    assert data[offsets[2]] == 0x06  # MCAP's Chunk opcode
    struct.pack_into('<Q', data, offsets[2] + 1, 1 << 40)
    mcap.write_bytes(bytes(data))
    os.utime(mcap, (mcap.stat().st_atime - 60, mcap.stat().st_mtime - 60))
    result = repair(bag)
    assert result.counts == {topic: 3 * PER_CHUNK for topic in TOPICS}
    assert by_time(messages_of(bag)[1]) == by_time(written[:3 * PER_CHUNK * len(TOPICS)])
    assert (bag / f'bag.mcap{DAMAGED_SUFFIX}').read_bytes() == bytes(data)


def test_a_bag_that_opens_is_left_as_it_is(recorded, capsys):
    bag, _, _ = recorded
    before = tree(bag)
    result = repair(bag)
    assert not result.repaired
    assert result.counts == {topic: CHUNKS * PER_CHUNK for topic in TOPICS}
    assert tree(bag) == before
    assert main(['reindex', str(bag)]) == 0
    assert 'opens as it is (720 messages); nothing to do' in capsys.readouterr().out
    assert tree(bag) == before


def test_an_earlier_damaged_copy_is_never_replaced(recorded, capsys):
    bag, offsets, _ = recorded
    kill(bag, offsets[-1] - 100)
    (bag / f'bag.mcap{DAMAGED_SUFFIX}').write_bytes(b'an earlier reindex kept this')
    before = tree(bag)
    with pytest.raises(BellowsError, match=r'bag\.mcap\.damaged: exists already'):
        repair(bag)
    assert tree(bag) == before and not list(bag.glob('.reindex-*'))
    assert main(['reindex', str(bag)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and 'exists already' in lines[0] and 'move it away' in lines[0]
    assert tree(bag) == before


def test_the_command_reports_what_it_kept(recorded, capsys):
    bag, offsets, _ = recorded
    kill(bag, (offsets[0] + offsets[1]) // 2)
    assert main(['reindex', str(bag)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert [line for line in out if line.startswith('/')] == \
        [f'{topic}: {PER_CHUNK} messages' for topic in TOPICS]
    assert f'rebuilt {bag}: {len(TOPICS) * PER_CHUNK} messages kept' in out[-1]
    assert main(['reindex', str(bag)]) == 0  # now it opens: nothing more to do
    assert 'nothing to do' in capsys.readouterr().out


def test_what_is_not_one_bag_is_refused_in_one_line(tmp_path, capsys):
    plain = tmp_path / 'r.csv'
    plain.write_text('t\n0\n')
    empty = tmp_path / 'empty'
    empty.mkdir()
    two = tmp_path / 'two'
    two.mkdir()
    for name in ('a.mcap', 'b.mcap'):
        (two / name).write_bytes(b'')
    for path, needle in [(plain, 'not a directory (a rosbag2 bag is a directory)'),
                         (empty, 'expected one .mcap file in the bag, found 0'),
                         (two, 'expected one .mcap file in the bag, found 2')]:
        before = tree(tmp_path)
        assert main(['reindex', str(path)]) == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert lines == [f'bellows reindex: error: {path}: {needle}'], lines
        assert tree(tmp_path) == before
