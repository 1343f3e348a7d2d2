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
sensor_msgs/msg/JointState as serialized bytes, for the 1 kHz sample topics.

The 1 kHz nodes publish and take their samples serialized (rclpy's `Publisher.publish(bytes)`
and `create_subscription(..., raw=True)`). Building a JointState object and converting it
costs a node more CPU than packing the same numbers into bytes laid out once for its names
(bench_results/0.1.0/notebook.md, 2026-11-29, "raw samples"):
- `JointStateWriter(names)` lays out the message once; `serialize(stamp_ns, position, velocity,
  effort)` copies that template and packs the stamp and the arrays into it;
- `JointStateReader()` reads stamp, names and arrays back; the names of the previous message
  are kept, so a publisher's unchanging names are compared as bytes instead of decoded again.

The bytes are ROS 2's CDR: XCDR1 little endian, the encapsulation header 00 01 00 00, each
primitive aligned to its size counted from the end of that header, strings with their NUL and
the length counting it, as `rclpy.serialization` writes them (test/test_runtime_joint_state_cdr.py
holds the two together). No rclpy here: the layout is the message definition's.
"""
from dataclasses import dataclass
import struct

HEADER = b'\x00\x01\x00\x00'  # CDR_LE: the encapsulation of every ROS 2 serialized message
_STAMP = struct.Struct('<iI')  # builtin_interfaces/Time: int32 sec, uint32 nanosec
_COUNT = struct.Struct('<I')   # a sequence's or string's length
_BODY = len(HEADER)            # alignment counts from here
_FRAME_ID = _BODY + _STAMP.size


@dataclass(frozen=True)
class JointStateSample:
    """A JointState's content: stamp (ns), names (tuple of str), the three arrays (tuples)."""

    stamp_ns: int
    name: tuple
    position: tuple
    velocity: tuple
    effort: tuple


def _align(offset, size):
    """`offset` (in the buffer) moved up to a multiple of `size` from the end of the header."""
    return offset + (-(offset - _BODY) % size)


def _pad(buffer, size):
    """Extend `buffer` with zeros up to the alignment of a primitive of `size` bytes."""
    buffer.extend(bytes(_align(len(buffer), size) - len(buffer)))


def _pack_string(buffer, text):
    _pad(buffer, 4)
    encoded = text.encode()
    buffer.extend(_COUNT.pack(len(encoded) + 1) + encoded + b'\0')


class JointStateWriter:
    """
    Serialize JointStates with fixed `names`; `position`, `velocity`, `effort`: arrays sent.

    An array not sent is empty in every message (an arm sample's chambers have no position).
    """

    def __init__(self, names, position=True, velocity=True, effort=True, frame_id=''):
        self.names = tuple(names)
        n = len(self.names)
        buffer = bytearray(HEADER + bytes(_STAMP.size))
        _pack_string(buffer, frame_id)
        _pad(buffer, 4)
        buffer.extend(_COUNT.pack(n))
        for name in self.names:
            _pack_string(buffer, name)
        self._arrays = []  # buffer offset of each array sent
        for sent in (position, velocity, effort):
            _pad(buffer, 4)
            buffer.extend(_COUNT.pack(n if sent else 0))
            if sent and n:
                _pad(buffer, 8)
                self._arrays.append(len(buffer))
                buffer.extend(bytes(8 * n))
            else:
                self._arrays.append(None)
        self.template = bytes(buffer)
        self._doubles = struct.Struct(f'<{n}d')

    def serialize(self, stamp_ns, position=(), velocity=(), effort=()):
        """Return the serialized message: `stamp_ns` (node clock, ns) and the arrays sent."""
        out = bytearray(self.template)
        _STAMP.pack_into(out, _BODY, *divmod(stamp_ns, 1_000_000_000))
        for offset, values in zip(self._arrays, (position, velocity, effort)):
            if offset is not None:
                self._doubles.pack_into(out, offset, *values)
        return bytes(out)


class JointStateReader:
    """
    Read serialized JointStates: `reader(data)` -> `JointStateSample`.

    Raises ValueError on bytes that are no JointState (truncated, wrong encapsulation, a
    length past the end).
    """

    def __init__(self):
        self._names_bytes = None  # frame_id and names of the previous message, as sent
        self._names = ()

    def __call__(self, data):
        data = bytes(data)
        if data[:_BODY] != HEADER:
            raise ValueError('not little-endian CDR')
        try:
            sec, nanosec = _STAMP.unpack_from(data, _BODY)
            end = self._names_end(data)
            arrays = []
            for _ in range(3):
                offset = _align(end, 4)
                (n,) = _COUNT.unpack_from(data, offset)
                end = offset + 4
                if n:
                    end = _align(end, 8)
                    arrays.append(struct.unpack_from(f'<{n}d', data, end))
                    end += 8 * n
                else:
                    arrays.append(())
        except struct.error as exc:
            raise ValueError(f'not a JointState: {exc}') from None
        return JointStateSample(sec * 1_000_000_000 + nanosec, self._names, *arrays)

    def _names_end(self, data):
        """Offset just past the names; decodes them only when they differ from the last ones."""
        known = self._names_bytes
        if known is not None and data.startswith(known, _FRAME_ID):
            return _FRAME_ID + len(known)
        offset = self._skip_string(data, _FRAME_ID)
        offset = _align(offset, 4)
        (count,) = _COUNT.unpack_from(data, offset)
        offset += 4
        names = []
        for _ in range(count):
            start = _align(offset, 4)
            offset = self._skip_string(data, start)
            names.append(data[start + 4:offset - 1].decode())
        self._names_bytes, self._names = data[_FRAME_ID:offset], tuple(names)
        return offset

    @staticmethod
    def _skip_string(data, offset):
        """Offset just past the string at `offset` (aligned to 4 by the caller)."""
        (length,) = _COUNT.unpack_from(data, offset)
        end = offset + 4 + length
        if length == 0 or end > len(data) or data[end - 1] != 0:
            raise ValueError('not a JointState: a string runs past the message')
        return end
