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
`bellows record`: write the contract topics to a rosbag2 (MCAP) directory.

An rclpy node subscribes to each topic as serialized messages (`raw=True`) and hands the CDR
bytes to rosbags' writer as they came: nothing is decoded or encoded on the way, as `ros2 bag
record` does. The bag timestamp is the receive time, as rosbag2's; the sample time stays in
`header.stamp`. Latched topics (the emergency stop, the driver's vent state) are subscribed
transient local, so the bag holds their state at the start.

A recording survives being stopped:
- SIGINT and SIGTERM end the recording the same way: the bag is closed (summary, footer,
  metadata.yaml) with every message received; signals that arrive while it closes (a second
  Ctrl-C, `ros2 launch` and the terminal both signalling) are ignored until it is closed;
- every `FLUSH_PERIOD` the pending MCAP chunk is closed and handed to the kernel, so after a
  SIGKILL or a crash the file holds every message up to the last flush, and `bellows reindex`
  (bellows_ros/io/bag_repair.py) rebuilds what readers need from it.
"""
import contextlib
import os
from pathlib import Path
import signal
import sys
import time

import rclpy
from rclpy.executors import ExternalShutdownException
import rclpy.node
from rclpy.signals import SignalHandlerOptions
from rclpy.task import Future
from rosbags.rosbag2 import Writer, WriterError
from rosbags.rosbag2.enums import StoragePlugin

from bellows_ros import interfaces
from bellows_ros.errors import BellowsError
from bellows_ros.io.bag import TYPESTORE
from bellows_ros.io.bag_lock import hold
from bellows_ros.io.outputs import check_output
from bellows_ros.runtime import messages
from bellows_ros.runtime.node import executor, LATCHED

# Longest time a received message stays only in the recorder's memory (a SIGKILL loses it).
FLUSH_PERIOD = 1.0  # s
SPIN_SLICE = 0.05  # s between looks at the stop request, the duration and the flush


def topics_of(namespace='/'):
    """{full topic name: contract Topic} of the contract in `namespace`."""
    return {topic.resolved(namespace): topic for topic in interfaces.TOPICS}


class _Stop:
    """
    SIGINT/SIGTERM/SIGHUP only ask the recording to stop; the loop ends at its next turn.

    No exception is raised into the writer: a chunk half written when a signal arrived would
    corrupt the bag. Further signals change nothing; the bag is closed whole. Once a signal has
    asked, the process ignores these signals to its end: rclpy's objects are finalised after
    `record` returns, and a second Ctrl-C raised as KeyboardInterrupt inside one of those C++
    calls aborts the process; and at exit Python puts its own handlers back to the default, so a
    second Ctrl-C during the interpreter's shutdown killed a recorder whose bag was already
    closed (exit status -2). An ignored signal stays ignored (CPython's _PySignal_Fini).
    """

    def __init__(self):
        self.requested = False
        self.previous = {}

    def __enter__(self):
        for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            self.previous[signum] = signal.signal(signum, self._on_signal)
        return self

    def _on_signal(self, signum, frame):
        self.requested = True

    def __exit__(self, *exc):
        for signum, handler in self.previous.items():
            # Asked to end, the process ends without a second signal's abort or kill.
            signal.signal(signum, signal.SIG_IGN if self.requested else handler)
        return False


def _flush(writer):
    """Close the pending MCAP chunk and hand the file's bytes to the kernel (rosbags' writer)."""
    storage = writer.storage
    if storage.chunk.bio.tell():
        storage.close_chunk()
    storage.bio.flush()


def record(output, topics=None, duration=None, ready=None, namespace='/'):
    """
    Record `topics` (default: every topic of the contract in `namespace`) into new dir `output`.

    Runs for `duration` seconds, or until SIGINT/SIGTERM. `ready()` is called once subscribed.
    Returns {topic: message count}.
    """
    known = topics_of(namespace)
    named, topics = bool(topics), list(topics or known)
    unknown = [t for t in topics if t not in known]
    if unknown:
        raise BellowsError(f"record: unknown topic '{unknown[0]}' (known in namespace "
                           f"{namespace}: {', '.join(known)})")
    twice = sorted({t for t in topics if topics.count(t) > 1})
    if twice:  # one connection per topic: a second would record every message twice
        raise BellowsError(f'--topics: {twice[0]} is given twice')
    output = Path(output)
    if os.path.lexists(output):
        raise BellowsError(f'{output}: already exists (rosbag2 writes a new directory)')
    check_output(output)  # its directory exists and can be written, before anything starts
    classes = {}
    for topic in topics:
        try:
            classes[topic] = messages.message_class(known[topic].ros_type)
        except ImportError as exc:  # control_msgs where ROS 2 came from PyPI (messages.py)
            if named:
                raise BellowsError(f"record: topic '{topic}': its type does not import "
                                   f'({exc})') from None
            print(f'bellows record: not recording {topic}: {exc}', file=sys.stderr)
    topics = [t for t in topics if t in classes]
    counts = dict.fromkeys(topics, 0)
    with _Stop() as stop:
        rclpy.init(args=[], signal_handler_options=SignalHandlerOptions.NO)
        node = rclpy.node.Node('bellows_record')
        writer = Writer(output, version=9, storage_plugin=StoragePlugin.MCAP)
        try:
            writer.open()
        except (OSError, WriterError) as exc:  # WriterError: another recorder made it first
            node.destroy_node()
            rclpy.try_shutdown()
            why = exc.strerror if isinstance(exc, OSError) else 'it exists already'
            raise BellowsError(f'{output}: cannot create the bag ({why})') from None
        node_executor = executor()
        try:
            # One writer (bag_lock): readers and `reindex` refuse the bag while this one writes;
            # the bag is closed (metadata.yaml written) before the lock goes.
            with hold(output), contextlib.closing(writer):
                for topic in topics:
                    connection = writer.add_connection(topic, known[topic].ros_type,
                                                       typestore=TYPESTORE)
                    qos = LATCHED if known[topic].latched else interfaces.SAMPLE_DEPTH
                    node.create_subscription(classes[topic], topic,
                                             _writer_callback(writer, connection, counts, topic),
                                             qos, raw=True)
                node_executor.add_node(node)
                if ready:
                    ready()
                _spin(node_executor, writer, stop, duration)
        except ExternalShutdownException:
            pass
        except OSError as exc:  # a full disk, a write error: what was flushed stays readable
            raise BellowsError(f'{output}: {exc.strerror or exc} while recording; the bag holds '
                               f'what was written before (bellows reindex {output})') from None
        finally:
            node.destroy_node()
            rclpy.try_shutdown()
    return counts


def _spin(node_executor, writer, stop, duration):
    """Spin until a signal or `duration` s; flush the pending chunk every FLUSH_PERIOD."""
    end = None if duration is None else time.monotonic() + duration
    next_flush = time.monotonic() + FLUSH_PERIOD
    never = Future()
    while not stop.requested and (end is None or time.monotonic() < end):
        node_executor.spin_until_future_complete(never, timeout_sec=SPIN_SLICE)
        if time.monotonic() >= next_flush:
            _flush(writer)
            next_flush += FLUSH_PERIOD


def _writer_callback(writer, connection, counts, topic):
    def write(data):
        # The serialized message as it came (CDR with its encapsulation header): rosbag2's form.
        writer.write(connection, time.time_ns(), bytes(data))
        counts[topic] += 1
    return write


def record_command(args):
    """CLI entry: `bellows record --output DIR [--topics T ...] [--duration S]`."""
    def ready():
        count = len(args.topics or interfaces.TOPICS)
        print(f'bellows record: recording {count} topics to {args.output} '
              + ('until Ctrl-C' if args.duration is None else f'for {args.duration:g} s'),
              file=sys.stderr, flush=True)
    counts = record(args.output, args.topics, args.duration, ready,
                    getattr(args, 'namespace', None) or '/')
    for topic, count in counts.items():
        print(f'{topic}: {count} messages')
    return 0
