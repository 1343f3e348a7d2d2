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

"""Actuator board serial protocol: round trips, resynchronisation, fuzzing of the decoder."""
import math
import zlib

from cobs import cobs
from hypothesis import given, settings
from hypothesis import strategies as st
import pytest

from bellows_ros.hardware import serial_protocol as sp

MESSAGES = [
    sp.Telemetry(seq=0, t_us=0, encoder_counts=0, pressure_pa=101325, spring_um=0, force_mn=0,
                 status=0),
    sp.Telemetry(seq=65535, t_us=2**32 - 1, encoder_counts=-2**31, pressure_pa=2**32 - 1,
                 spring_um=2**31 - 1, force_mn=-2**31, status=0xFFFF),
    sp.MotorCommand(seq=7, duty_q15=-32767),
    sp.MotorCommand(seq=8, duty_q15=32767),
    sp.Heartbeat(seq=12345),
]

telemetry = st.builds(
    sp.Telemetry, seq=st.integers(0, 0xFFFF), t_us=st.integers(0, 2**32 - 1),
    encoder_counts=st.integers(-2**31, 2**31 - 1), pressure_pa=st.integers(0, 2**32 - 1),
    spring_um=st.integers(-2**31, 2**31 - 1), force_mn=st.integers(-2**31, 2**31 - 1),
    status=st.integers(0, 0xFFFF))
messages = st.one_of(telemetry,
                     st.builds(sp.MotorCommand, st.integers(0, 0xFFFF), st.integers(-32767,
                                                                                    32767)),
                     st.builds(sp.Heartbeat, st.integers(0, 0xFFFF)))


def test_round_trip_every_type_and_extreme_values():
    stream = b''.join(sp.encode(m) for m in MESSAGES)
    decoder = sp.FrameDecoder()
    assert decoder.feed(stream) == MESSAGES
    assert decoder.crc_errors == decoder.framing_errors == 0


def test_frame_layout_matches_the_spec():
    frame = sp.encode(MESSAGES[0])
    assert frame.endswith(b'\x00') and b'\x00' not in frame[:-1]
    raw = cobs.decode(frame[:-1])
    payload, crc = raw[:-4], int.from_bytes(raw[-4:], 'little')
    assert zlib.crc32(payload) == crc
    assert payload[0] == sp.VERSION and payload[1] == sp.TYPE_TELEMETRY
    assert len(frame) == 32  # docs/protocols.md: 32 bytes on the wire per telemetry frame


def test_resynchronises_after_garbage_and_counts_it():
    garbage = bytes(range(1, 200))  # no 0x00: one long run the decoder must throw away
    decoder = sp.FrameDecoder()
    out = decoder.feed(garbage + b'\x00' + sp.encode(MESSAGES[2]) + b'\x13\x37\x00'
                       + sp.encode(MESSAGES[4]))
    assert out == [MESSAGES[2], MESSAGES[4]]
    assert decoder.framing_errors + decoder.crc_errors == 2


def test_a_flipped_bit_is_a_crc_error_not_a_message():
    frame = bytearray(sp.encode(MESSAGES[0]))
    frame[10] ^= 0x04  # inside the payload; not a COBS code byte for this frame
    decoder = sp.FrameDecoder()
    assert decoder.feed(bytes(frame) + sp.encode(MESSAGES[4])) == [MESSAGES[4]]
    assert decoder.crc_errors + decoder.framing_errors == 1


def test_wrong_version_is_rejected():
    frame = bytearray(cobs.decode(sp.encode(MESSAGES[4])[:-1]))
    frame[0] = sp.VERSION + 1
    payload = bytes(frame[:-4])
    decoder = sp.FrameDecoder()
    frame = cobs.encode(payload + zlib.crc32(payload).to_bytes(4, 'little')) + b'\0'
    assert decoder.feed(frame) == []
    assert decoder.version_errors == 1


@settings(max_examples=300, deadline=None)
@given(st.lists(messages, min_size=1, max_size=5), st.lists(st.integers(1, 40), max_size=10))
def test_any_chunking_gives_the_same_messages(sent, cuts):
    stream = b''.join(sp.encode(m) for m in sent)
    decoder = sp.FrameDecoder()
    out, position = [], 0
    for cut in cuts + [len(stream)]:
        out += decoder.feed(stream[position:position + cut])
        position += cut
    out += decoder.feed(stream[position:])
    assert out == sent


@settings(max_examples=500, deadline=None)
@given(st.binary(max_size=300))
def test_random_bytes_never_raise_and_never_yield_unchecked_frames(data):
    decoder = sp.FrameDecoder()
    for message in decoder.feed(data) + decoder.feed(b'\x00'):
        # Anything returned must be exactly what its own valid frame decodes to.
        assert sp.FrameDecoder().feed(sp.encode(message)) == [message]


@settings(max_examples=500, deadline=None)
@given(st.lists(messages, min_size=1, max_size=4),
       st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 255)), min_size=1, max_size=4))
def test_mutated_streams_yield_only_messages_that_were_sent(sent, mutations):
    stream = bytearray(b''.join(sp.encode(m) for m in sent))
    for position, value in mutations:
        stream[position % len(stream)] = value
    decoder = sp.FrameDecoder()
    out = decoder.feed(bytes(stream)) + decoder.feed(b'\x00')
    for message in out:
        assert message in sent  # CRC-32: a corrupted frame is never passed as a good one


@pytest.mark.parametrize('sent', MESSAGES, ids=lambda m: type(m).__name__)
def test_every_single_byte_corruption_loses_that_frame_only_and_is_counted(sent):
    """
    Exhaustive: each byte of one frame set to each other value, between two good frames.

    COBS code bytes and the delimiter included. Never a different message; the frame after it
    survives unless its delimiter was hit (then the two run together and are lost as one).
    """
    before, after = sp.encode(MESSAGES[4]), sp.encode(MESSAGES[2])
    frame = sp.encode(sent)
    for position in range(len(frame)):
        for value in range(256):
            if value == frame[position]:
                continue
            spoilt = bytearray(frame)
            spoilt[position] = value
            decoder = sp.FrameDecoder()
            out = decoder.feed(before + bytes(spoilt) + after)
            delimiter_hit = position == len(frame) - 1
            assert out == ([MESSAGES[4]] if delimiter_hit else [MESSAGES[4], MESSAGES[2]]), \
                (position, value)
            assert errors(decoder) >= 1


def errors(decoder):
    return (decoder.crc_errors + decoder.framing_errors + decoder.version_errors
            + decoder.unknown_types)


def delimited_chunks(stream):
    """Non-empty runs ended by a 0x00: each must come out as one message or one counted error."""
    return sum(1 for chunk in stream.split(b'\x00')[:-1] if chunk)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.one_of(messages.map(sp.encode), st.binary(max_size=60)), max_size=8),
       st.lists(st.tuples(st.integers(0, 10 ** 6), st.integers(0, 255)), max_size=3))
def test_every_delimited_chunk_is_a_message_or_one_counted_error(parts, mutations):
    stream = bytearray(b''.join(parts))
    for position, value in mutations:
        if stream:
            stream[position % len(stream)] = value
    decoder = sp.FrameDecoder()
    out = decoder.feed(bytes(stream))
    assert len(out) == decoder.frames
    assert decoder.frames + errors(decoder) == delimited_chunks(bytes(stream))


def test_a_duty_saturates_and_a_non_finite_one_stops_the_motor():
    assert sp.duty_to_q15(2.0) == 32767 and sp.duty_to_q15(-2.0) == -32767
    assert sp.duty_to_q15(0.5) == 16384
    assert [sp.duty_to_q15(v) for v in (math.nan, math.inf, -math.inf)] == [0, 0, 0]
