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

"""The kernel filter that keeps a udp_multicast bus's own frames from coming back to it."""
import random
import time

import can
import msgpack

from bellows_ros.hardware.arm_bus import open_can
from bellows_ros.hardware.can_echo_filter import drop_own_frames, frame_pattern


def _frame(frame_id):
    return can.Message(arbitration_id=frame_id, data=bytes(8), is_extended_id=False)


def _drain(bus, seconds=0.3):
    ids, deadline = [], time.monotonic() + seconds
    while time.monotonic() < deadline:
        frame = bus.recv(timeout=0.05)
        if frame is not None:
            ids.append(frame.arbitration_id)
    return sorted(ids)


def test_own_ids_are_dropped_and_everything_else_still_arrives():
    port = 44000 + random.randint(0, 999)
    group = f'239.74.167.{random.randint(1, 250)}'
    sender = open_can('udp_multicast', group, port=port)
    peer = open_can('udp_multicast', group, port=port)
    try:
        assert drop_own_frames(sender, {0x100, 0x180, 0x080})
        for frame_id in (0x100, 0x101, 0x180, 0x080, 0x081):
            sender.send(_frame(frame_id))
        peer.send(_frame(0x110))
        # The sender hears none of the IDs it filters (its own echoes), every other ID, from
        # itself or from the peer; the peer, unfiltered, hears all six.
        assert _drain(sender) == [0x081, 0x101, 0x110]
        assert _drain(peer) == [0x080, 0x081, 0x100, 0x101, 0x110, 0x180]
        # An extended frame with a filtered number is another frame and passes.
        peer.send(can.Message(arbitration_id=0x100, data=b'\x01', is_extended_id=True))
        extended = sender.recv(timeout=2.0)
        assert extended is not None and extended.is_extended_id
    finally:
        sender.shutdown()
        peer.shutdown()


def test_other_buses_are_left_alone():
    bus = can.Bus(interface='virtual', channel='echo-filter-test')
    try:
        assert not drop_own_frames(bus, {0x100})
    finally:
        bus.shutdown()


def test_an_unknown_packing_attaches_nothing():
    """
    Were python-can to pack frames differently, no pattern is made.

    The callers' own ID check then does the work.
    """
    assert frame_pattern(0x100, pack=lambda m: msgpack.packb([m.arbitration_id, m.timestamp])) \
        is None
    chunks = frame_pattern(0x100)
    # The known layout: everything before the timestamp's 8 bytes, then the identity up to
    # `is_extended_id` (a standard frame), which ends the pattern.
    assert chunks[1][1].endswith(msgpack.packb('is_extended_id') + msgpack.packb(False))
    assert chunks[1][0] == len(chunks[0][1]) + 8
