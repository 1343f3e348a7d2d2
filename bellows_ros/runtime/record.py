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
`bellows record`: write the contract topics to a rosbag2 (MCAP) directory, without ROS.

Subscribes over Cyclone DDS with ROS 2's wire conventions (so it records ROS 2 nodes on
rmw_cyclonedds_cpp too), converts each message to the rosbags Jazzy type store's class and
serialises it to CDR with the type store. The bag timestamp is the receive time, as rosbag2 does;
the sample time stays in `header.stamp`.

A recording survives being stopped:
- SIGINT and SIGTERM end the recording the same way: the bag is closed (summary, footer,
  metadata.yaml) with every message received; signals that arrive while it closes (a second
  Ctrl-C, `ros2 launch` and the terminal both signalling) are ignored until it is closed;
- every `FLUSH_PERIOD` the pending MCAP chunk is closed and handed to the kernel, so after a
  SIGKILL or a crash the file holds every message up to the last flush, and `bellows reindex`
  (bellows_ros/bag_repair.py) rebuilds what readers need from it.
"""
import os
from pathlib import Path
import signal
import sys
import time

from rosbags.rosbag2 import Writer
from rosbags.rosbag2.enums import StoragePlugin

from bellows_ros.errors import BellowsError
from bellows_ros.interfaces import by_name, SAMPLE_DEPTH
from bellows_ros.outputs import check_output
from bellows_ros.runtime import dds_node
from bellows_ros.runtime.messages import message_class, TYPESTORE

TOPICS = by_name()  # the contract's topics in the root namespace: {name: type}
# Longest time a received message stays only in the recorder's memory (a SIGKILL loses it).
FLUSH_PERIOD = 1.0  # s


class _Stop:
    """
    SIGINT/SIGTERM only ask the recording to stop; the loop ends at its next turn (<= 0.1 s).

    No exception is raised into the writer: a chunk half written when a signal arrived would
    corrupt the bag. Further signals change nothing; the bag is closed whole.
    """

    def __init__(self):
        self.requested = False
        self.previous = {}

    def __enter__(self):
        for signum in (signal.SIGINT, signal.SIGTERM):
            self.previous[signum] = signal.signal(signum, self._on_signal)
        return self

    def _on_signal(self, signum, frame):
        self.requested = True

    def __exit__(self, *exc):
        for signum, handler in self.previous.items():
            signal.signal(signum, handler)
        return False


def _flush(writer):
    """Close the pending MCAP chunk and hand the file's bytes to the kernel (rosbags' writer)."""
    storage = writer.storage
    if storage.chunk.bio.tell():
        storage.close_chunk()
    storage.bio.flush()


def record(output, topics=None, duration=None, ready=None):
    """
    Record `topics` (default: all of TOPICS) into the new directory `output`.

    Runs for `duration` seconds, or until KeyboardInterrupt. `ready()` is called once subscribed.
    Returns {topic: message count}.
    """
    topics = list(topics or TOPICS)
    unknown = [t for t in topics if t not in TOPICS]
    if unknown:
        raise BellowsError(f"record: unknown topic '{unknown[0]}' (known: {', '.join(TOPICS)})")
    output = Path(output)
    if os.path.lexists(output):
        raise BellowsError(f'{output}: already exists (rosbag2 writes a new directory)')
    check_output(output)  # its directory exists and can be written, before anything starts
    counts = dict.fromkeys(topics, 0)
    with _Stop() as stop:
        dds_node.init([])
        node = dds_node.Node('bellows_record')
        writer = Writer(output, version=9, storage_plugin=StoragePlugin.MCAP)
        try:
            writer.open()
        except OSError as exc:
            dds_node.shutdown()
            raise BellowsError(f'{output}: cannot create the bag ({exc.strerror})') from None
        try:
            for topic in topics:
                ros_type = TOPICS[topic]
                connection = writer.add_connection(topic, ros_type, typestore=TYPESTORE)
                node.create_subscription(message_class(ros_type), topic,
                                         _writer_callback(writer, connection, counts, topic),
                                         SAMPLE_DEPTH)
            if ready:
                ready()
            end = None if duration is None else time.monotonic() + duration
            next_flush = time.monotonic() + FLUSH_PERIOD
            while not stop.requested and (end is None or time.monotonic() < end):
                dds_node.spin_once(node, timeout_sec=0.05)
                if time.monotonic() >= next_flush:
                    _flush(writer)
                    next_flush += FLUSH_PERIOD
        finally:
            writer.close()
            node.destroy_node()
            dds_node.shutdown()
    return counts


def _writer_callback(writer, connection, counts, topic):
    def write(msg):
        # The message classes serialise to the very CDR the type store would (tested), once.
        data = msg.serialize(use_version_2=False)
        writer.write(connection, time.time_ns(), data)
        counts[topic] += 1
    return write


def record_command(args):
    """CLI entry: `bellows record --output DIR [--topics T ...] [--duration S]`."""
    def ready():
        print(f'bellows record: recording {len(args.topics or TOPICS)} topics to {args.output} '
              + ('until Ctrl-C' if args.duration is None else f'for {args.duration:g} s'),
              file=sys.stderr, flush=True)
    counts = record(args.output, args.topics, args.duration, ready)
    for topic, count in counts.items():
        print(f'{topic}: {count} messages')
    return 0
