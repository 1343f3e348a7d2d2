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
Binary protocol of the actuator board's serial link (spec: docs/protocols.md, "Serial").

Wire format of every frame::

    COBS( payload || CRC-32(payload) as uint32 little-endian ) 0x00
    payload = version:u8  type:u8  seq:u16  body          (all little-endian, `struct`)

COBS (the `cobs` package) keeps 0x00 out of the frame, so a receiver resynchronises at the next
0x00 after any garbage. CRC-32 (``zlib.crc32``, IEEE 802.3) guards the payload.

API
---
- Messages (wire units, exact integers): ``Telemetry(seq, t_us, encoder_counts, pressure_pa,
  spring_um, force_mn, status)``, ``Identity(seq, serial)``, ``MotorCommand(seq, duty_q15)``,
  ``Heartbeat(seq)``.
- ``IDENTITY_PERIOD``: the board sends IDENTITY at least this often; ``IDENTITY_TIMEOUT``: a host
  that has heard none this long after opening a port is not talking to a board and closes it.
- ``encode(message) -> bytes`` (one complete frame including the trailing 0x00).
- ``FrameDecoder().feed(data: bytes) -> list[message]``; counters ``crc_errors``,
  ``framing_errors``, ``version_errors``, ``unknown_types`` and ``frames``. Never raises on any
  input; only frames whose CRC matched are returned.
- Status bits ``END_STOP_LOW``, ``END_STOP_HIGH``, ``MOTOR_ON``, ``HEARTBEAT_LOST``,
  ``SENSOR_FAULT``.
- ``duty_to_q15(duty)``, ``q15_to_duty(q)``.
"""
import dataclasses
import math
import operator
import struct
import zlib

from cobs import cobs

VERSION = 1
BOARD_HEARTBEAT_TIMEOUT = 0.1  # s without MOTOR or HEARTBEAT from the host before the board stops

TYPE_TELEMETRY = 0x01
TYPE_IDENTITY = 0x02
# The board names itself (its serial number, as a USB device does in its descriptor) at least every
# IDENTITY_PERIOD, and at once when a host speaks after a silence. A host sends nothing to a port
# until it has heard the board's IDENTITY there, and closes a port that gives none within
# IDENTITY_TIMEOUT: a tty number or a link the kernel gave to another program is never driven.
IDENTITY_PERIOD = 0.05
IDENTITY_TIMEOUT = 0.5
TYPE_MOTOR = 0x10
TYPE_HEARTBEAT = 0x11

END_STOP_LOW = 1 << 0    # chamber fully extended: negative duty would drive further into the stop
END_STOP_HIGH = 1 << 1   # chamber fully compressed: positive duty would drive further into it
MOTOR_ON = 1 << 2
HEARTBEAT_LOST = 1 << 3  # the board stopped the motor because the host went quiet
SENSOR_FAULT = 1 << 4

_HEADER = struct.Struct('<BBH')
_CRC = struct.Struct('<I')
_BODIES = {
    TYPE_TELEMETRY: struct.Struct('<IiIiiH'),
    TYPE_IDENTITY: struct.Struct('<Q'),
    TYPE_MOTOR: struct.Struct('<h'),
    TYPE_HEARTBEAT: struct.Struct(''),
}
# Longest frame on the wire, with COBS overhead; a longer run without 0x00 is garbage.
MAX_FRAME = _HEADER.size + max(s.size for s in _BODIES.values()) + _CRC.size + 2


@dataclasses.dataclass(frozen=True)
class Telemetry:
    """
    Board -> host at 1 kHz.

    t_us: board clock, us (wraps at 2**32); pressure_pa: system pressure, Pa abs; spring_um: spring
    compression x_s, um; force_mn: spring force, mN; status: bit flags.
    """

    seq: int
    t_us: int
    encoder_counts: int
    pressure_pa: int
    spring_um: int
    force_mn: int
    status: int


@dataclasses.dataclass(frozen=True)
class Identity:
    """
    Board -> host, every IDENTITY_PERIOD: the board's serial number (u64).

    seq: the sequence number of the last TELEMETRY sent; IDENTITY does not advance it, so the
    host's gap count of telemetry stays a count of lost samples.
    """

    seq: int
    serial: int


@dataclasses.dataclass(frozen=True)
class MotorCommand:
    """Host -> board. duty_q15: motor duty x 32767 (-32767..32767); also counts as a heartbeat."""

    seq: int
    duty_q15: int


@dataclasses.dataclass(frozen=True)
class Heartbeat:
    """Host -> board, every 20 ms: the host is alive."""

    seq: int


_TYPES = {Telemetry: TYPE_TELEMETRY, Identity: TYPE_IDENTITY, MotorCommand: TYPE_MOTOR,
          Heartbeat: TYPE_HEARTBEAT}
_CLASSES = {code: cls for cls, code in _TYPES.items()}


def _fields_getter(cls):
    """Return a function giving a message's fields as a tuple, in wire order."""
    names = [field.name for field in dataclasses.fields(cls)]
    get = operator.attrgetter(*names)
    return get if len(names) > 1 else lambda message: (get(message),)


# `dataclasses.astuple` deep-copies every field: 4.7 of the 5.3 µs a telemetry frame took to
# encode, at the simulated board's 1 kHz.
_FIELDS = {cls: _fields_getter(cls) for cls in _TYPES}


def duty_to_q15(duty):
    """Duty -1..1 -> int16 wire value (saturating); a non-finite duty is 0 (motor stopped)."""
    if not math.isfinite(duty):
        return 0  # min/max would make NaN a full duty
    return int(round(max(-1.0, min(1.0, duty)) * 32767))


def q15_to_duty(q):
    return q / 32767


def encode(message):
    """One frame: COBS(payload || CRC-32) followed by the 0x00 delimiter."""
    kind = type(message)
    code = _TYPES[kind]
    fields = _FIELDS[kind](message)
    payload = _HEADER.pack(VERSION, code, fields[0] & 0xFFFF) + _BODIES[code].pack(*fields[1:])
    return cobs.encode(payload + _CRC.pack(zlib.crc32(payload))) + b'\x00'


class FrameDecoder:
    """Incremental decoder: feed any bytes, get the good messages; everything else is counted."""

    def __init__(self):
        self._buffer = bytearray()
        self._overflow = False
        self.frames = 0
        self.crc_errors = 0
        self.framing_errors = 0
        self.version_errors = 0
        self.unknown_types = 0

    def feed(self, data):
        messages = []
        # The last chunk has no delimiter yet: it stays in the buffer for the next call.
        chunks = bytes(data).split(b'\x00')
        for i, chunk in enumerate(chunks):
            last = i == len(chunks) - 1
            if not self._overflow:
                self._buffer += chunk
                if len(self._buffer) > MAX_FRAME:
                    self._buffer.clear()
                    self._overflow = True
            if last:
                break
            if self._overflow:
                self.framing_errors += 1
                self._overflow = False
            elif self._buffer:
                message = self._decode(bytes(self._buffer))
                if message is not None:
                    messages.append(message)
            self._buffer.clear()
        return messages

    def _decode(self, encoded):
        try:
            frame = cobs.decode(encoded)
        except cobs.DecodeError:
            self.framing_errors += 1
            return None
        if len(frame) < _HEADER.size + _CRC.size:
            self.framing_errors += 1
            return None
        payload, crc = frame[:-_CRC.size], _CRC.unpack(frame[-_CRC.size:])[0]
        if zlib.crc32(payload) != crc:
            self.crc_errors += 1
            return None
        version, code, seq = _HEADER.unpack_from(payload)
        if version != VERSION:
            self.version_errors += 1
            return None
        body = _BODIES.get(code)
        if body is None:
            self.unknown_types += 1
            return None
        if len(payload) != _HEADER.size + body.size:
            self.framing_errors += 1
            return None
        self.frames += 1
        return _CLASSES[code](seq, *body.unpack_from(payload, _HEADER.size))
