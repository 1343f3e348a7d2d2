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
rosbag2 recordings (sqlite3 or MCAP) as data tables (docs/interfaces.md "Data files").

The rows are the samples of the wanted device group, one message each (`bellows_ros.interfaces`):
the arm's on `/joint_states`, the actuator's on `/actuator/joint_states`; a row's joint values,
chamber pressures and the actuator's spring force are found by name in its own message. The
arm's force/torque sensor (`/bellows/wrench`) is aligned onto the rows by stamp, zero-order hold:
each row takes the latest message stamped at or before it (the first message for rows before
any). A value a sample holds as NaN (its device measured none) counts as a message missing from
that channel: the hold fills it in from the sample before. A row whose channel was silent for
longer than `table.MAX_HELD_STEPS` sample steps is marked (`Table.held`), and the readers refuse
it (`table.check_held`): a channel that stops, starts late or has a hole is never filled in.
`t` is the sample stamp in seconds from the first row.

Older recordings are read too. Before one message per sample (a sample message that names no
chambers), the pressures came on `/bellows/chambers` and `/actuator/chambers` and the actuator's
spring force on `/bellows/wrench` (frame_id `actuator`), each aligned as the wrench is. Before
the actuator had topics of its own, its samples were on `/joint_states` and `/bellows/chambers`:
where the bag has no `/actuator/...` topic, that one is read instead.

Topic and joint names are the contract's (`bellows_ros.interfaces`, also for the wrench axes),
in the root namespace. Columns:
- segment (`segment_1`): psi, psi_dot = position, velocity of joint `segment_1`;
  p1, p2 = effort of chambers `segment_1/chain_1`, `segment_1/chain_2`;
  tau_ext = `wrench.torque.z` of the wrench with frame_id `segment_1`.
- actuator: x_c, x_s = positions of `air_chamber`, `spring`; f = effort of `spring` (older:
  `wrench.force.z` of the wrench with frame_id `actuator`); p = effort of chamber `actuator`.
"""
import math
from pathlib import Path

from lz4.frame import LZ4FrameDecompressor
import numpy as np
from rosbags.rosbag2 import Reader, storage_mcap
from rosbags.typesys import get_types_from_msg, get_typestore, Stores
import yaml

from bellows_ros import interfaces
from bellows_ros.errors import DataError
from bellows_ros.io.bag_lock import check_not_written
from bellows_ros.io.params import load_bounded, MAX_YAML_BYTES
from bellows_ros.io.table import check_increasing, COLUMNS, Table

SEGMENT = interfaces.segment_joint(1)
SPRING = interfaces.ACTUATOR_JOINTS[1]
JOINT_STATES, ACTUATOR_JOINT_STATES, WRENCH = (
    topic.resolved() for topic in (interfaces.JOINT_STATES, interfaces.ACTUATOR_JOINT_STATES,
                                   interfaces.WRENCH))
# Older recordings' topics, from before one message per sample: the chambers' pressures, and the
# actuator's spring force as `wrench.force.z` of the wrench with this frame_id.
LEGACY_CHAMBERS = '/bellows/chambers'
LEGACY_ACTUATOR_CHAMBERS = '/actuator/chambers'
LEGACY_ACTUATOR_FRAME = 'actuator'
TYPES = {name: interfaces.by_name()[name]
         for name in (JOINT_STATES, ACTUATOR_JOINT_STATES, WRENCH)}
TYPES.update(dict.fromkeys((LEGACY_CHAMBERS, LEGACY_ACTUATOR_CHAMBERS), TYPES[JOINT_STATES]))

# The message types of a recording, without ROS: rosbags' Jazzy type store, plus the types it
# lacks (it holds only ROS 2's core packages), as their .msg text installs them with Jazzy's
# package, comments left out (they are not part of the type, nor of its RIHS01 hash).
EXTRA_DEFINITIONS = {
    # control_msgs 5.x (ros2_control for Jazzy): the arm controller's ~/state.
    'control_msgs/msg/JointTrajectoryControllerState': """
std_msgs/Header header
string[] joint_names
trajectory_msgs/JointTrajectoryPoint reference
trajectory_msgs/JointTrajectoryPoint feedback
trajectory_msgs/JointTrajectoryPoint error
trajectory_msgs/JointTrajectoryPoint output
string[] multi_dof_joint_names
trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_reference
trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_feedback
trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_error
trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_output
float64 speed_scaling_factor
""",
}
TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
for _name, _text in EXTRA_DEFINITIONS.items():
    TYPESTORE.register(get_types_from_msg(_text, _name))

# Messages a bag's table is read from, at most: the reader holds them all (~150 bytes each);
# 30 million is about eight hours of one sample topic at 1 kHz (three hours of an older
# recording's three actuator topics).
MAX_BAG_MESSAGES = 30_000_000
# Bytes one MCAP chunk may inflate to. rosbag2 and `bellows record` write chunks of about 1 MiB;
# a chunk is read whole, so this is the memory one read of a bag may take at once.
MAX_CHUNK_BYTES = 256 * 2**20


def _bounded(decompressor):
    """
    Return a rosbags chunk decompressor that never inflates past the chunk's declared size.

    rosbags' MCAP reader inflates a whole chunk, then compares its length with the size the chunk
    declares: a few kilobytes of zstd or lz4 that inflate to gigabytes (a corrupt or hostile
    file) would take the memory first. Here a declared size over MAX_CHUNK_BYTES is refused, and
    inflating stops one byte past the declared size, which rosbags' own check then refuses.
    """
    def inflate(data, size):
        if size > MAX_CHUNK_BYTES:
            raise ValueError(f'a chunk declares {size:,} bytes uncompressed: over '
                             f'{MAX_CHUNK_BYTES:,} (bag.MAX_CHUNK_BYTES)')
        return decompressor().decompress(data, max_length=size + 1)
    return inflate


storage_mcap.DECOMPRESSORS.update(zstd=_bounded(storage_mcap.zstd.ZstdDecompressor),
                                  lz4=_bounded(LZ4FrameDecompressor))
# The actuator's topics, and where a recording from before they existed held its samples.
ACTUATOR_FALLBACK = {ACTUATOR_JOINT_STATES: JOINT_STATES,
                     LEGACY_ACTUATOR_CHAMBERS: LEGACY_CHAMBERS}


def _first_line(exc):
    lines = str(exc).strip().splitlines()
    return lines[0] if lines else type(exc).__name__


def _stamp(msg):
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


def _messages(path, reader, typestore, topic):
    """Return the deserialised messages on `topic`; a corrupt or mistyped bag raises DataError."""
    connections = [c for c in reader.connections if c.topic == topic]
    if not connections:
        return  # rosbags reads every topic when given no connection
    for connection in connections:
        if connection.msgtype != TYPES[topic]:
            raise DataError(path, f'{topic} holds {connection.msgtype}, expected {TYPES[topic]}')
    messages = reader.messages(connections=connections)
    while True:
        # rosbags and its storage back ends raise many types for damaged files (ReaderError,
        # SerdeError, struct.error, UnicodeDecodeError, MemoryError for a corrupt length, apsw
        # errors); to the user each means the same: this recording cannot be read.
        try:
            item = next(messages, None)
            if item is None:
                return
            connection, timestamp, raw = item
            message = typestore.deserialize_cdr(raw, connection.msgtype)
        except Exception as exc:
            raise DataError(path, f'{topic}: damaged message data ({_first_line(exc)})') from None
        yield message


def _actuator_topic(reader, topic):
    """
    Return (topic to read, its name in an error) for the actuator's `topic`.

    `topic` if the bag holds it, else the shared topic a recording from before the actuator had
    topics of its own used, where the bag holds that one.
    """
    held = {connection.topic for connection in reader.connections}
    older = ACTUATOR_FALLBACK[topic]
    if topic not in held and older in held:
        return older, f'{topic} (nor, as recorded before it existed, on {older})'
    return topic, topic


def _joint_rows(path, reader, typestore, topic, wanted, own=(), named=None):
    """
    Stamps and values of `wanted` ((name, field) pairs) from the messages that name them all.

    `own` ((name, field) pairs): a sample's own chamber pressures and force, returned as a third
    array, NaN where a message holds none; None when no message names them all (a recording from
    before one message per sample, which sent them on topics of their own).
    """
    joint_index = interfaces.SampleIndex(name for name, _ in wanted)
    own_index = interfaces.SampleIndex(name for name, _ in own)
    stamps, rows, own_rows, named_own = [], [], [], False
    for msg in _messages(path, reader, typestore, topic):
        layout = joint_index(msg.name)
        if layout is None:
            continue
        row = []
        for (name, field_name), i in zip(wanted, layout):
            values = getattr(msg, field_name)
            if len(values) <= i:
                raise DataError(path, f"{topic}: joint '{name}' has no {field_name} "
                                      f'(stamp {_stamp(msg)} ns)')
            row.append(float(values[i]))
        stamps.append(_stamp(msg))
        rows.append(row)
        if own:
            where = own_index(msg.name)
            named_own = named_own or where is not None
            fields = [getattr(msg, field_name) for _, field_name in own]
            own_rows.append([math.nan] * len(own) if where is None else
                            [float(v[i]) if i < len(v) else math.nan
                             for v, i in zip(fields, where)])
    if not stamps:
        names = ', '.join(dict.fromkeys(name for name, _ in wanted))
        raise DataError(path, f'no messages on {named or topic} with joint(s) {names}')
    return (np.array(stamps, dtype=np.int64), np.array(rows, dtype=float),
            np.array(own_rows, dtype=float) if named_own else None)


def _own_channel(path, topic, stamps, values, what):
    """
    Return (name, stamps, values) of a channel that a sample message holds itself.

    A sample holding NaN (its device measured none) is left out, as a missing message of a
    channel on a topic of its own was: the hold fills it in, or refuses a long gap.
    """
    present = ~np.isnan(values).any(axis=1)
    if not present.any():
        raise DataError(path, f'no {what} on {topic}: NaN in every message')
    return f'{what} on {topic}', stamps[present], values[present]


def _wrench_rows(path, reader, typestore, frame, axis):
    """Return (WRENCH, stamps, values) of `axis` of the wrenches of `frame`."""
    stamps, values = [], []
    for msg in _messages(path, reader, typestore, WRENCH):
        if msg.header.frame_id in (frame, ''):
            kind, component = axis
            stamps.append(_stamp(msg))
            values.append(float(getattr(getattr(msg.wrench, kind), component)))
    if not stamps:
        raise DataError(path, f"no messages on {WRENCH} with frame_id '{frame}'")
    return WRENCH, np.array(stamps, dtype=np.int64), np.array(values, dtype=float)[:, None]


def _median_step(stamps):
    return float(np.median(np.diff(stamps))) if len(stamps) > 1 else 0.0


def _hold(sample_stamps, stamps, values):
    """
    Zero-order hold of (stamps, values) onto sample_stamps: (values, (age s, step s)).

    The first value fills the rows before it. The age of a row's value is how far its message's
    stamp lies from the row's (before the first message: after it), the step the larger of the
    rows' and the channel's median steps: `table.check_held` refuses a row older than
    MAX_HELD_STEPS steps (the channel had a gap there).
    """
    order = np.argsort(stamps, kind='stable')
    stamps, values = stamps[order], values[order]
    index = np.searchsorted(stamps, sample_stamps, side='right') - 1
    taken = np.clip(index, 0, len(stamps) - 1)
    step = max(_median_step(sample_stamps), _median_step(stamps)) * 1e-9
    age = np.abs(sample_stamps - stamps[taken]).astype(float) * 1e-9
    return values[taken], (age, step)


def _check_metadata(path):
    """Parse metadata.yaml first, so that a broken one is named with its line, not a traceback."""
    metadata = path / 'metadata.yaml'
    try:
        if metadata.exists() and not metadata.is_file():
            raise DataError(metadata, 'not a regular file')
        with open(metadata, 'rb') as stream:
            raw = stream.read(MAX_YAML_BYTES + 1)
        document = load_bounded(raw, yaml.SafeLoader)
    except FileNotFoundError:
        storage = any(p.suffix in ('.mcap', '.db3') for p in path.iterdir())
        hint = (f'; a recording that was killed lacks it: `bellows reindex {path}` rebuilds it'
                if storage else '')
        raise DataError(path, f'not a rosbag2 directory (it has no metadata.yaml){hint}') \
            from None
    except OSError as exc:
        raise DataError(metadata, f'cannot read file ({exc.strerror})') from None
    except yaml.YAMLError as exc:  # also for bytes that are not text
        mark = getattr(exc, 'problem_mark', None)
        problem = getattr(exc, 'problem', None) or _first_line(exc)
        raise DataError(metadata, f'not valid YAML: {problem}',
                        None if mark is None else mark.line + 1) from None
    if not isinstance(document, dict) \
            or not isinstance(document.get('rosbag2_bagfile_information'), dict):
        raise DataError(metadata, "no 'rosbag2_bagfile_information' map: not rosbag2 metadata")


def _open(path):
    """Open a rosbags Reader of `path`, or raise DataError naming what is wrong."""
    check_not_written(path)  # a bag being recorded would be read in part (bag_lock)
    _check_metadata(path)
    try:
        reader = Reader(path)
        reader.open()
    except Exception as exc:  # rosbags' many error types for a bag it cannot open (see _messages)
        raise DataError(path, f'cannot open the rosbag2 recording ({_first_line(exc)})') from None
    # rosbags takes metadata.yaml's counts as they are written: a damaged file may hold any
    # YAML value there (a flipped bit makes `100` the text `1p0`).
    for connection in reader.connections:
        count = connection.msgcount
        if isinstance(count, bool) or not isinstance(count, int) or count < 0:
            reader.close()
            raise DataError(path / 'metadata.yaml', f'topic {connection.topic}: message_count '
                                                    f'{count!r} is not a count of messages')
    # Said before any chunk is read (its bytes are read whole, compressed or not): the index
    # of an MCAP file lists every chunk's sizes.
    for storage in getattr(reader.storage, 'storages', ()):
        for chunk in getattr(storage, 'chunks', ()):
            size = max(chunk.compressed_size, chunk.uncompressed_size)
            if size > MAX_CHUNK_BYTES:
                reader.close()
                raise DataError(path, f'{storage.path.name}: a chunk of {size:,} bytes, over '
                                      f'{MAX_CHUNK_BYTES:,} (bag.MAX_CHUNK_BYTES); a damaged '
                                      'file, or one written with chunks this reader cannot hold')
    return reader


def read_bag_table(path, system):
    """Read a rosbag2 directory as a `Table` with the columns of `system` (docs/interfaces.md)."""
    path = Path(path)
    typestore = TYPESTORE
    reader = _open(path)
    try:
        messages = sum(c.msgcount for c in reader.connections if c.topic in TYPES)
        if messages > MAX_BAG_MESSAGES:  # said before reading, not after minutes of it
            raise DataError(path, f'{messages:,} messages on the topics read: over '
                                  f'{MAX_BAG_MESSAGES:,} (bag.MAX_BAG_MESSAGES), more than '
                                  'this reader holds in memory; record shorter parts')
        if system == 'segment':
            chambers = [(interfaces.chain_chamber(1, chain), 'effort') for chain in (1, 2)]
            stamps, joints, own = _joint_rows(path, reader, typestore, JOINT_STATES,
                                              [(SEGMENT, 'position'), (SEGMENT, 'velocity')],
                                              chambers)
            if own is None:  # an older recording: the pressures on a topic of their own
                pressures = (LEGACY_CHAMBERS, *_joint_rows(path, reader, typestore,
                                                           LEGACY_CHAMBERS, chambers)[:2])
            else:
                names = ', '.join(name for name, _ in chambers)
                pressures = _own_channel(path, JOINT_STATES, stamps, own, f'effort of {names}')
            columns = {'psi': joints[:, 0], 'psi_dot': joints[:, 1]}
            channels = {('p1', 'p2'): pressures,
                        ('tau_ext',): _wrench_rows(path, reader, typestore, SEGMENT,
                                                   ('torque', 'z'))}
        elif system == 'actuator':
            topic, named = _actuator_topic(reader, ACTUATOR_JOINT_STATES)
            chamber = (interfaces.ACTUATOR_CHAMBER, 'effort')
            stamps, joints, own = _joint_rows(
                path, reader, typestore, topic,
                [(joint, 'position') for joint in interfaces.ACTUATOR_JOINTS],
                [chamber, (SPRING, 'effort')], named)
            if own is None:  # an older recording: pressure and force on topics of their own
                topic, named = _actuator_topic(reader, LEGACY_ACTUATOR_CHAMBERS)
                pressure = (topic, *_joint_rows(path, reader, typestore, topic, [chamber],
                                                named=named)[:2])
                force = _wrench_rows(path, reader, typestore, LEGACY_ACTUATOR_FRAME,
                                     ('force', 'z'))
            else:
                pressure = _own_channel(path, topic, stamps, own[:, :1],
                                        f'effort of {interfaces.ACTUATOR_CHAMBER}')
                force = _own_channel(path, topic, stamps, own[:, 1:], f'effort of {SPRING}')
            columns = {'x_c': joints[:, 0], 'x_s': joints[:, 1]}
            channels = {('p',): pressure, ('f',): force}
        else:
            raise DataError(path, f"unknown system '{system}' (segment or actuator)")
        held = {}
        for channel_columns, (channel, channel_stamps, channel_values) in channels.items():
            values, gaps = _hold(stamps, channel_stamps, channel_values)
            for i, name in enumerate(channel_columns):
                columns[name], held[name] = values[:, i], (channel, *gaps)
    finally:
        reader.close()
    required, optional = COLUMNS[system]
    values = {'t': (stamps - stamps[0]) * 1e-9}
    values.update(columns)
    names = [n for n in required + optional if n in values]
    table = Table(str(path), names, {n: values[n] for n in names}, held=held)
    check_increasing(table, 't')
    for name in names:
        bad = np.flatnonzero(~np.isfinite(table[name]))
        if bad.size:  # the CSV reader refuses these too; a NaN would poison a fit silently
            raise DataError(path, f'{table[name][bad[0]]} is not a finite number (stamp '
                                  f'{stamps[bad[0]]} ns)', column=name)
    return table
