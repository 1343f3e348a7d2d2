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
CAN protocol of the arm: frames described by config/arm.dbc, used through cantools.

Every frame ends with two DBC signals, ``Counter`` (8-bit, +1 per transmission of that frame ID)
and ``CRC`` (CRC-8 SAE J1850 over the frame ID as two bytes little-endian followed by the frame's
other data bytes -- the data-ID idea of AUTOSAR E2E profile 1, so a frame with a valid CRC under
another ID is still rejected). The ID goes first so that the CRC byte, last in every frame,
directly follows the bytes it covers, as on the wire: then every error burst of up to 8 bits is
detected (with the ID after the data, a burst across the last data byte and the CRC byte could
pass). Spec and bus-load budget: docs/protocols.md, "CAN".

API
---
- ``load_dbc(path=None) -> cantools.database.can.Database`` (default config/arm.dbc).
- ``crc8_j1850(data: bytes) -> int``; ``chamber_of(signal_name) -> int | None``.
- ``encode_frame(message, values: dict, counter: int) -> bytes``: signals in physical units, CRC
  filled.
- ``codec(message) -> FrameCodec`` (cached per Message): ``.encode(values, counter) -> bytes``,
  ``.decode(data) -> dict``; the same bytes and values as cantools, without its per-call cost.
- ``FrameChecker(db, resync_after=0.05)``; ``.check(frame_id, data, now) -> (Message, dict) |
  None``; counters ``unknown_ids``, ``malformed``, ``crc_errors``, ``replayed``, ``lost`` (frames
  missing per counter gaps), ``accepted``. Never raises on any input.
- ``frame_bits(length, extended=False) -> int`` (worst-case stuffed length), ``bus_load(db,
  bitrate, names=None) -> float`` (fraction of the bus used by the DBC's cyclic frames).
"""
import functools
import re

import cantools

from bellows_ros.io import params

ARM_HEARTBEAT_TIMEOUT = 0.1  # s without ARM_HOST_HEARTBEAT before the arm vents every chamber


def load_dbc(path=None):
    """Load the arm's CAN database (default: config/arm.dbc)."""
    path = path or params.config_dir() / 'arm.dbc'
    db = cantools.database.load_file(str(path))
    for message in db.messages:
        names = [s.name for s in message.signals]
        if 'Counter' not in names or 'CRC' not in names:
            raise ValueError(f'{path}: frame {message.name} lacks a Counter or CRC signal')
        crc = message.get_signal_by_name('CRC')
        if crc.length != 8 or crc.start != 8 * (message.length - 1):
            raise ValueError(f'{path}: frame {message.name}: CRC must be the last whole byte')
    return db


@functools.lru_cache(maxsize=None)
def dbc_segments(path=None):
    """Return how many arm segments the CAN database defines (its ARM_SEG<i>_SAMPLE frames)."""
    return sum(1 for m in load_dbc(path).messages if re.fullmatch(r'ARM_SEG\d+_SAMPLE', m.name))


@functools.lru_cache(maxsize=None)  # the DBC's signal names are few and fixed
def chamber_of(signal_name):
    """
    Return the 0-based chamber index of a set-point signal ``S<segment>_P<chain>``.

    The order is seg1 chain1, seg1 chain2, seg2 chain1, ...; None for any other signal.
    """
    match = re.fullmatch(r'S(\d+)_P([12])', signal_name)
    return None if match is None else 2 * (int(match[1]) - 1) + int(match[2]) - 1


def _j1850_table():
    table = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
        table.append(crc)
    return table


_TABLE = _j1850_table()


def crc8_j1850(data):
    """
    Compute the CRC-8 SAE J1850 of `data`.

    Poly 0x1D, init 0xFF, final XOR 0xFF (check value of b'123456789' = 0x4B).
    """
    crc = 0xFF
    for byte in data:
        crc = _TABLE[crc ^ byte]
    return crc ^ 0xFF


class FrameCodec:
    """
    Encoder/decoder of one frame, precomputed from its DBC definition (a cantools Message).

    cantools spends ~30 us per `encode` (argument and range checks, bitstruct) -- a quarter of the
    simulated arm's 1 kHz tick with four sample frames. The arm's frames are plain little-endian
    integer signals, so each signal is a shift and mask of the frame read as one little-endian
    integer; start bit, length, sign, conversion and range all come from the DBC. The checks stay:
    a missing, unknown or out-of-range value raises cantools' EncodeError (the same tolerance of
    1e-6 x scale as cantools' strict mode), and the CRC covers the data as before. Frames with
    big-endian, float or multiplexed signals keep using cantools.
    """

    def __init__(self, message):
        self.message = message
        self.length = message.length
        self.frame_id = message.frame_id
        self.crc_byte = message.get_signal_by_name('CRC').start // 8
        self._id_bytes = message.frame_id.to_bytes(2, 'little')
        self.plain = not message.is_multiplexed() and all(
            s.byte_order == 'little_endian' and not s.is_float for s in message.signals)
        self._signals = tuple(
            (s.name, s.start, (1 << s.length) - 1, (1 << (s.length - 1)) if s.is_signed else 0,
             s.conversion, s.conversion.offset, s.conversion.scale,
             _bound(s.minimum, -1, s.conversion.scale), _bound(s.maximum, 1, s.conversion.scale))
            for s in message.signals)
        self._names = frozenset(s.name for s in message.signals)

    def crc(self, data):
        """CRC-8 of the frame ID, then `data` without its CRC byte (see module docstring)."""
        i = self.crc_byte
        return crc8_j1850(self._id_bytes + bytes(data[:i]) + bytes(data[i + 1:]))

    def encode(self, values, counter):
        """Encode data bytes with `values` (physical units), the rolling `counter` and the CRC."""
        values = dict(values, Counter=counter & 0xFF, CRC=0)
        if not self.plain:
            data = bytearray(self.message.encode(values))  # strict: out of range raises
        else:
            if len(values) != len(self._names) or not self._names.issuperset(values):
                raise cantools.database.EncodeError(
                    f'frame {self.message.name} needs exactly the signals {sorted(self._names)}, '
                    f'got {sorted(values)}')
            word = 0
            for name, start, mask, _sign, _conversion, offset, scale, lo, hi in self._signals:
                value = values[name]
                if not lo <= value <= hi:  # also refuses NaN: never wrap, never send garbage
                    raise cantools.database.EncodeError(
                        f'signal "{name}" of {self.message.name}: {value} outside the DBC range')
                # cantools' numeric_scaled_to_raw for integer signals, inlined (same result: an
                # exact multiple of the scale divides exactly in IEEE arithmetic).
                word |= (round((value - offset) / scale) & mask) << start
            data = bytearray(word.to_bytes(self.length, 'little'))
        data[self.crc_byte] = self.crc(data)
        return bytes(data)

    def decode(self, data):
        """Signal values (physical units; ints where cantools gives ints) of `data`."""
        if not self.plain:
            return self.message.decode(bytes(data), decode_choices=False)
        word = int.from_bytes(data, 'little')
        values = {}
        for name, start, mask, sign, conversion, *_ in self._signals:
            raw = (word >> start) & mask
            if raw & sign:
                raw -= sign << 1
            values[name] = conversion.raw_to_scaled(raw, False)
        return values


def _bound(limit, direction, scale):
    """Widen a DBC minimum/maximum by cantools' strict-mode tolerance (none: unbounded)."""
    if limit is None:
        return direction * float('inf')
    return limit + direction * abs(scale) * 1e-6


@functools.lru_cache(maxsize=None)  # one per Message of the loaded DBCs
def codec(message):
    """Return the `FrameCodec` of a cantools Message (built once per Message)."""
    return FrameCodec(message)


def encode_frame(message, values, counter):
    """Encode `message` (a cantools Message) with `values`, the rolling counter and the CRC."""
    return codec(message).encode(values, counter)


class FrameChecker:
    """
    Decode received frames; reject and count unknown, malformed, corrupt and replayed ones.

    A frame is a replay when its counter did not advance (delta 0) or went back (delta > 128, i.e.
    it is older than the last accepted one). After `resync_after` seconds of silence from an ID the
    counter is taken afresh (a restarted sender).
    """

    def __init__(self, db, resync_after=0.05):
        self.db = db
        self.resync_after = resync_after
        self._last = {}  # frame_id -> (counter, time)
        self.unknown_ids = self.malformed = self.crc_errors = 0
        self.replayed = self.lost = self.accepted = 0

    def counters(self):
        return {'unknown_ids': self.unknown_ids, 'malformed': self.malformed,
                'crc_errors': self.crc_errors, 'replayed': self.replayed, 'lost': self.lost,
                'accepted': self.accepted}

    def check(self, frame_id, data, now):
        try:
            message = self.db.get_message_by_frame_id(frame_id)
        except KeyError:
            self.unknown_ids += 1
            return None
        if len(data) != message.length:
            self.malformed += 1
            return None
        frame_codec = codec(message)
        try:
            values = frame_codec.decode(data)
        except Exception:  # cantools raises several types for undecodable data; all mean malformed
            self.malformed += 1
            return None
        if values['CRC'] != frame_codec.crc(data):
            self.crc_errors += 1
            return None
        counter = values['Counter']
        last = self._last.get(frame_id)
        if last is not None and now - last[1] <= self.resync_after:
            delta = (counter - last[0]) & 0xFF
            if delta == 0 or delta > 128:
                self.replayed += 1
                return None
            self.lost += delta - 1
        self._last[frame_id] = (counter, now)
        self.accepted += 1
        return message, values


def frame_bits(length, extended=False):
    """
    Count the worst-case bits of a classic CAN data frame with `length` data bytes.

    Stuff bits and the 3-bit interframe space included (Davis, Burns, Bril, Lukkien 2007, eq. (2)):
    g + 8n + 13 + floor((g+8n-1)/4), g = 34 (11-bit ID) or 54 (29-bit ID) bits exposed to
    stuffing.
    """
    g = 54 if extended else 34
    return g + 8 * length + 13 + (g + 8 * length - 1) // 4


def bus_load(db, bitrate, names=None):
    """
    Return the fraction of a `bitrate` bit/s bus the cyclic frames of `db` take.

    All frames, or those in `names`.
    """
    bits_per_second = 0.0
    for message in db.messages:
        if names is not None and message.name not in names:
            continue
        if not message.cycle_time:
            raise ValueError(f'frame {message.name} has no GenMsgCycleTime')
        bits_per_second += frame_bits(message.length, message.is_extended_frame) \
            * 1000.0 / message.cycle_time
    return bits_per_second / bitrate
