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
A kernel-side filter that stops a udp_multicast CAN bus hearing its own frames.

A SocketCAN socket does not receive the frames it sends (CAN_RAW_RECV_OWN_MSGS is off by default).
python-can's udp_multicast bus does: IP multicast loopback hands every datagram to every member on
the host, the sender included. The simulated arm sends 4000 sample frames a second and used to
receive each one back only to discard it, at about 24 us per frame in python-can (select, recvmsg,
msgpack, Message): its bus work took 0.37 core with the echoes, 0.245 without (measured).

`drop_own_frames(bus, frame_ids)` attaches a classic BPF program (socket(7) SO_ATTACH_FILTER) that
drops such datagrams in the kernel. The program compares the start of the datagram with
python-can's own encoding of a frame with that ID (`pack_message`): map header, timestamp type, the
`arbitration_id` and `is_extended_id` entries, skipping the 8 timestamp bytes. If python-can packs
frames some other way, no pattern is found and nothing is attached. The filter only saves work and
decides nothing, so callers keep their own check of the IDs they send.
"""
import ctypes
import socket
import struct
import sys

import can
from can.interfaces.udp_multicast.utils import pack_message
import msgpack

SO_ATTACH_FILTER = 26  # <asm-generic/socket.h>
_LD_ABS = {4: 0x20, 2: 0x28, 1: 0x30}  # BPF_LD | BPF_W / BPF_H / BPF_B | BPF_ABS
_JEQ_K = 0x15  # BPF_JMP | BPF_JEQ | BPF_K
_RET_K = 0x06  # BPF_RET | BPF_K
_UDP_HEADER = 8  # a UDP socket's filter sees the datagram from its UDP header on
_FLOAT64 = 0xCB  # msgpack's type byte of a float64; python-can's timestamps are floats


def drop_own_frames(bus, frame_ids):
    """
    Make the kernel drop frames with `frame_ids` (standard 11-bit IDs) before `bus` reads them.

    Returns True when a filter was attached: `bus` is a udp_multicast bus on Linux and its packing
    is the known one. Any other bus is left as it is (False).
    """
    sock = getattr(getattr(bus, '_multicast', None), '_socket', None)
    if sock is None or not sys.platform.startswith('linux') or not frame_ids:
        return False
    patterns = [frame_pattern(frame_id) for frame_id in sorted(frame_ids)]
    if None in patterns:
        return False
    program = compile_filter(patterns)
    instructions = ctypes.create_string_buffer(program)
    fprog = struct.pack('@HP', len(program) // 8, ctypes.addressof(instructions))  # sock_fprog
    try:
        sock.setsockopt(socket.SOL_SOCKET, SO_ATTACH_FILTER, fprog)
    except OSError:
        return False
    return True


def frame_pattern(frame_id, pack=pack_message):
    """
    Return the [(offset, bytes), ...] a datagram carrying standard frame `frame_id` starts with.

    That is every udp_multicast datagram of that frame; None when `pack` (python-can's packing by
    default) lays frames out in a way this module does not know.
    """
    packed = pack(can.Message(arbitration_id=frame_id, is_extended_id=False, timestamp=0.0))
    timestamp_key = msgpack.packb('timestamp')
    identity = (msgpack.packb('arbitration_id') + msgpack.packb(frame_id) +
                msgpack.packb('is_extended_id') + msgpack.packb(False))
    value = packed.find(timestamp_key) + len(timestamp_key)
    at = packed.find(identity)
    if value < len(timestamp_key) or at < 0 or packed[value] != _FLOAT64 or at < value + 9:
        return None
    return [(0, packed[:value + 1]), (value + 9, packed[value + 9:at + len(identity)])]


def compile_filter(patterns):
    """
    Build a classic BPF program (bytes, a `struct sock_filter` array) for `patterns`.

    It drops a datagram that starts with any of `patterns` and keeps everything else.
    """
    code = []
    for chunks in patterns:
        loads = []
        for offset, data in chunks:
            while data:
                size = 4 if len(data) >= 4 else 2 if len(data) >= 2 else 1
                loads.append((offset, size, int.from_bytes(data[:size], 'big')))  # BPF loads BE
                offset, data = offset + size, data[size:]
        for i, (offset, size, value) in enumerate(loads):
            code.append((_LD_ABS[size], 0, 0, _UDP_HEADER + offset))
            # On a mismatch skip the rest of this pattern and its drop: on to the next pattern.
            code.append((_JEQ_K, 0, 2 * (len(loads) - 1 - i) + 1, value))
        code.append((_RET_K, 0, 0, 0))  # every byte matched: our own frame
    code.append((_RET_K, 0, 0, 0xFFFFFFFF))  # keep the whole datagram
    if any(jump > 255 for _, _, jump, _ in code):
        raise ValueError('frame pattern too long for a classic BPF jump')
    return b''.join(struct.pack('=HBBI', *instruction) for instruction in code)
