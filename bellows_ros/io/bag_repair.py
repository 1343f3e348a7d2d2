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
`bellows reindex BAG`: make a recording that was killed readable again (as `ros2 bag reindex`).

A recorder killed by SIGKILL (or a crash, or a power cut) leaves its MCAP file without the
summary and footer that readers look for, and the bag without metadata.yaml. The file still holds
every chunk the recorder had flushed (it flushes every second: runtime/record.py). `repair` reads
the file record by record up to the first incomplete one, writes the messages into a new MCAP
with a summary, checks that a reader opens it with every message, then puts it in place and
writes metadata.yaml. Nothing is deleted: the damaged file is kept beside it as
`<name>.mcap.damaged`, and a bag that readers already open is left alone.

A bag that is still being written is refused, not cut short: reindex takes the bag's writer lock
(`bag_lock.hold`; a recorder holds it while it records), and, for a writer that takes no lock,
refuses a storage file that grows while it looks (`_check_still`). So the metadata.yaml it writes
counts exactly the messages the rebuilt file holds, read back before anything is moved.
"""
from dataclasses import dataclass
import os
from pathlib import Path
import struct
import tempfile
import time

from mcap.exceptions import McapError
from mcap.records import Channel, Message, Schema
from mcap.stream_reader import StreamReader
from rosbags.rosbag2 import Reader, Writer
from rosbags.rosbag2.enums import StoragePlugin
import yaml

from bellows_ros.errors import BellowsError
from bellows_ros.io.bag import TYPESTORE
from bellows_ros.io.bag_lock import check_not_written, hold
from bellows_ros.io.outputs import write_text

DAMAGED_SUFFIX = '.damaged'


@dataclass
class Repair:
    """What `repair` found and did: messages kept per topic, and where the bag stood."""

    path: Path
    counts: dict
    repaired: bool
    truncated_bytes: int = 0


def _readable(bag):
    try:
        with Reader(bag) as reader:
            return {c.topic: c.msgcount for c in reader.connections}
    except Exception:  # any reader error means: not readable as it is  # noqa: B902
        return None


def _mcap_file(bag):
    if not bag.is_dir():
        raise BellowsError(f'{bag}: not a directory (a rosbag2 bag is a directory)')
    files = sorted(p for p in bag.iterdir() if p.suffix == '.mcap')
    if len(files) != 1:
        raise BellowsError(f'{bag}: expected one .mcap file in the bag, found {len(files)}')
    return files[0]


def _reader(stream, path):
    """
    Return a StreamReader of `stream` that takes no record longer than the file.

    A corrupt length field would otherwise allocate up to mcap's default 4 GiB before failing.
    """
    return StreamReader(stream, validate_crcs=True,
                        record_size_limit=max(1, os.path.getsize(path)))


def _records(path):
    """Yield the file's records up to the first incomplete or corrupt one; then its offset."""
    with open(path, 'rb') as stream:
        try:
            for record in _reader(stream, path).records:
                yield record
        except (McapError, struct.error, EOFError, ValueError):
            pass  # the end of what the recorder had flushed


# A recorder flushes its chunk every second (runtime/record.py); a file changed more recently than
# RECENT_S may still be written, and is watched for WATCH_S (over one flush) before it is touched.
RECENT_S = 3.0
WATCH_S = 1.5


def _check_still(bag, source):
    """Refuse a storage file that changes while it is watched (a writer that takes no lock)."""
    def state():
        info = source.stat()
        return info.st_size, info.st_mtime_ns
    before = state()
    if time.time() - before[1] * 1e-9 > RECENT_S:
        return
    end = time.monotonic() + WATCH_S
    while time.monotonic() < end:
        time.sleep(0.1)
        if state() != before:
            raise BellowsError(f'{bag}: {source.name} is still being written (it grew while '
                               'reindex looked); reindex a recording once its recorder has '
                               'ended')


def repair(bag):
    """Rebuild what readers need in the bag directory `bag`; returns a `Repair`."""
    bag = Path(bag)
    source = _mcap_file(bag)
    check_not_written(bag, 'bellows reindex')
    counts = _readable(bag)
    if counts is not None:
        return Repair(bag, counts, repaired=False)
    with hold(bag, 'bellows reindex'):  # and no second reindex at the same time
        _check_still(bag, source)
        return _rebuild(bag, source)


def _rebuild(bag, source):
    """Write the messages of the damaged `source` into a new MCAP with metadata.yaml."""
    aside = source.with_name(source.name + DAMAGED_SUFFIX)
    if os.path.lexists(aside):
        raise BellowsError(f'{aside}: exists already (an earlier reindex?); move it away first')
    building = Path(tempfile.mkdtemp(dir=bag, prefix='.reindex-'))
    target = building / 'bag'
    schemas, connections, counts = {}, {}, {}
    writer = Writer(target, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.open()
    try:
        for record in _records(source):
            if isinstance(record, Schema):
                schemas[record.id] = record.name
            elif isinstance(record, Channel) and record.id not in connections:
                if record.schema_id not in schemas:
                    continue
                connections[record.id] = writer.add_connection(
                    record.topic, schemas[record.schema_id], typestore=TYPESTORE)
                counts.setdefault(record.topic, 0)
            elif isinstance(record, Message) and record.channel_id in connections:
                writer.write(connections[record.channel_id], record.log_time, record.data)
                counts[connections[record.channel_id].topic] += 1
    finally:
        writer.close()
    if _readable(target) != counts:
        raise BellowsError(f'{bag}: the rebuilt bag does not read back whole; nothing changed '
                           f'(the rebuilt copy is in {building})')
    metadata = yaml.safe_load((target / 'metadata.yaml').read_text())
    info = metadata['rosbag2_bagfile_information']
    info['relative_file_paths'] = [source.name]
    for entry in info.get('files', []):
        entry['path'] = source.name
    # The damaged file steps aside (kept), the rebuilt one takes its name, then metadata.yaml.
    os.rename(source, aside)
    os.rename(target / 'bag.mcap', source)
    write_text(bag / 'metadata.yaml', yaml.safe_dump(metadata, sort_keys=False))
    os.unlink(target / 'metadata.yaml')  # the copy this function wrote a moment ago
    os.rmdir(target)
    os.rmdir(building)
    return Repair(bag, counts, repaired=True,
                  truncated_bytes=aside.stat().st_size - _used_bytes(aside))


def _used_bytes(path):
    """How many bytes of `path` held complete records (the rest was cut off by the kill)."""
    with open(path, 'rb') as stream:
        reader = _reader(stream, path)
        used = stream.tell()
        try:
            for _ in reader.records:
                used = stream.tell()  # the end of the last record read whole
        except (McapError, struct.error, EOFError, ValueError):
            pass
        return used
