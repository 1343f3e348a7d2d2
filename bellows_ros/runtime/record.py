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
"""
from pathlib import Path
import sys
import time

from rosbags.rosbag2 import Writer
from rosbags.rosbag2.enums import StoragePlugin

from bellows_ros.errors import BellowsError
from bellows_ros.interfaces import by_name, SAMPLE_DEPTH
from bellows_ros.runtime import dds_node
from bellows_ros.runtime.messages import message_class, TYPESTORE

TOPICS = by_name()  # the contract's topics in the root namespace: {name: type}


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
    if output.exists():
        raise BellowsError(f'{output}: already exists (rosbag2 writes a new directory)')
    if not output.parent.is_dir():
        raise BellowsError(f'{output.parent}: no such directory')
    dds_node.init([])
    node = dds_node.Node('bellows_record')
    counts = dict.fromkeys(topics, 0)
    writer = Writer(output, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.open()
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
        while end is None or time.monotonic() < end:
            dds_node.spin_once(node, timeout_sec=0.05)
    except KeyboardInterrupt:
        pass
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
