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

"""CAN protocol of the arm: DBC round trips, integrity checks, fuzzing, bus load from the DBC."""
import itertools
from pathlib import Path
import re

import cantools
from hypothesis import given, settings
from hypothesis import strategies as st
import pytest

from bellows_ros.hardware import can_protocol as cp
from bellows_ros.io import params

ROOT = Path(__file__).resolve().parent.parent
DB = cp.load_dbc()
SEG1 = DB.get_message_by_name('ARM_SEG1_SAMPLE')
SEG2 = DB.get_message_by_name('ARM_SEG2_SAMPLE')
ARM_IDS = [m.frame_id for m in DB.messages]


def test_crc8_j1850_check_value():
    assert cp.crc8_j1850(b'123456789') == 0x4B  # the catalogued check value of CRC-8/SAE-J1850


def test_sample_round_trip_through_the_dbc():
    data = cp.encode_frame(SEG1, {'P1': 412345.0, 'P2': 101325.0, 'Psi': -0.73219}, counter=300)
    message, values = cp.FrameChecker(DB).check(SEG1.frame_id, data, now=0.0)
    assert message is SEG1
    assert values['P1'] == pytest.approx(412345.0, abs=7.5)     # half of the 15 Pa step
    assert values['P2'] == pytest.approx(101325.0, abs=7.5)
    assert values['Psi'] == pytest.approx(-0.73219, abs=5e-5)
    assert values['Counter'] == 300 % 256


def test_setpoint_round_trip_through_the_dbc():
    frame = DB.get_message_by_name('ARM_SETPOINT_B')
    sent = {'S3_P1': 750000.0, 'S3_P2': 101325.0, 'S4_P1': 250000.0, 'S4_P2': 0.0}
    _, values = cp.FrameChecker(DB).check(frame.frame_id, cp.encode_frame(frame, sent, 1), 0.0)
    for name, value in sent.items():
        assert values[name] == pytest.approx(value, abs=100.0)  # half of the 200 Pa step
    assert [cp.chamber_of(name) for name in sent] == [4, 5, 6, 7]
    assert cp.chamber_of('Counter') is None


def test_out_of_range_value_is_refused_not_wrapped():
    with pytest.raises(cantools.database.EncodeError, match='"P1" of ARM_SEG1_SAMPLE: 2000000.0 '
                                                            'outside the DBC range'):
        cp.encode_frame(SEG1, {'P1': 2e6, 'P2': 1e5, 'Psi': 0.0}, 0)


def test_replayed_corrupt_and_misaddressed_frames_are_rejected_and_counted():
    checker = cp.FrameChecker(DB)
    f0 = cp.encode_frame(SEG1, {'P1': 2e5, 'P2': 1e5, 'Psi': 0.1}, 10)
    f1 = cp.encode_frame(SEG1, {'P1': 2e5, 'P2': 1e5, 'Psi': 0.2}, 11)
    f4 = cp.encode_frame(SEG1, {'P1': 2e5, 'P2': 1e5, 'Psi': 0.3}, 14)
    assert checker.check(SEG1.frame_id, f0, 0.000)[1]['Psi'] == pytest.approx(0.1, abs=5e-5)
    assert checker.check(SEG1.frame_id, f1, 0.001)[1]['Psi'] == pytest.approx(0.2, abs=5e-5)
    assert checker.check(SEG1.frame_id, f1, 0.002) is None        # same counter again: replay
    assert checker.check(SEG1.frame_id, f0, 0.003) is None        # older counter: replay
    assert checker.check(SEG2.frame_id, f1, 0.003) is None        # valid data under another ID
    bad = bytearray(f4)
    bad[2] ^= 0x10
    assert checker.check(SEG1.frame_id, bytes(bad), 0.004) is None  # corrupt
    assert checker.check(SEG1.frame_id, f4, 0.005) is not None      # two frames lost on the way
    assert checker.check(0x7FF, f4, 0.006) is None
    assert checker.check(SEG1.frame_id, f4[:5], 0.006) is None
    assert checker.counters() == {'unknown_ids': 1, 'malformed': 1, 'crc_errors': 2,
                                  'replayed': 2, 'lost': 2, 'accepted': 3}


@settings(max_examples=500, deadline=None)
@given(st.sampled_from(ARM_IDS + [0, 0x7FF, 0x1234]), st.binary(max_size=8))
def test_random_frames_never_raise_and_never_pass_a_bad_crc(frame_id, data):
    result = cp.FrameChecker(DB).check(frame_id, data, 0.0)
    if result is not None:
        message, values = result
        crc_byte = message.get_signal_by_name('CRC').start // 8
        covered = message.frame_id.to_bytes(2, 'little') + data[:crc_byte] + data[crc_byte + 1:]
        assert values['CRC'] == cp.crc8_j1850(covered) == data[crc_byte]


@settings(max_examples=500, deadline=None)
@given(st.floats(0, 983025), st.floats(0, 983025), st.floats(-3.2768, 3.2767),
       st.integers(0, 255), st.integers(0, 7), st.integers(1, 255))
def test_any_single_byte_corruption_is_rejected(p1, p2, psi, counter, position, xor):
    data = bytearray(cp.encode_frame(SEG1, {'P1': p1, 'P2': p2, 'Psi': psi}, counter))
    data[position] ^= xor  # CRC-8 detects every error burst of up to 8 bits
    checker = cp.FrameChecker(DB)
    assert checker.check(SEG1.frame_id, bytes(data), 0.0) is None
    assert checker.crc_errors == 1


def _nominal_frame(message, counter=3):
    values = {s.name: (s.minimum + s.maximum) / 2 for s in message.signals
              if s.name not in ('Counter', 'CRC')}
    return cp.encode_frame(message, values, counter)


@pytest.mark.parametrize('message', DB.messages, ids=lambda m: m.name)
def test_every_error_of_two_bits_or_an_8_bit_burst_is_rejected(message):
    """
    Exhaustive, in wire order (bytes in order, most significant bit first).

    The CRC is linear, so which error patterns pass depends on the pattern alone, not on the
    frame's values.
    """
    good = _nominal_frame(message)
    bits = 8 * len(good)
    word = int.from_bytes(good, 'big')
    patterns = {burst << shift for burst in range(1, 256) for shift in range(bits - 7)}
    patterns |= {(1 << i) | (1 << j) for i, j in itertools.combinations(range(bits), 2)}
    checker = cp.FrameChecker(DB)
    for pattern in patterns:
        assert checker.check(message.frame_id, (word ^ pattern).to_bytes(len(good), 'big'),
                             0.0) is None, hex(pattern)
    assert checker.crc_errors == len(patterns) and checker.accepted == 0
    assert checker.check(message.frame_id, good, 0.0) is not None  # and the frame itself passes


@pytest.mark.parametrize('sent', DB.messages, ids=lambda m: m.name)
def test_a_good_frame_under_any_other_id_is_rejected(sent):
    frame = _nominal_frame(sent)
    for other in DB.messages:
        if other is not sent:
            checker = cp.FrameChecker(DB)
            assert checker.check(other.frame_id, frame, 0.0) is None
            assert checker.crc_errors + checker.malformed == 1  # length differs, or the ID's CRC


@st.composite
def traffic(draw):
    """
    Frames as a receiver may see them.

    Good ones in counter order, repeats, stale ones, up to two flipped bits, a foreign ID, a wrong
    length.
    """
    events, counters, sent = [], {}, []
    for _ in range(draw(st.integers(1, 30))):
        message = draw(st.sampled_from(DB.messages))
        counters[message.frame_id] = (counters.get(message.frame_id, 0)
                                      + draw(st.sampled_from([1, 1, 1, 0, 2, 200]))) % 256
        data = bytearray(_nominal_frame(message, counters[message.frame_id]))
        sent.append((message.frame_id, bytes(data)))
        kind = draw(st.sampled_from(['good'] * 4 + ['bits', 'id', 'short']))
        frame_id = message.frame_id
        if kind == 'bits':
            for bit in draw(st.lists(st.integers(0, 8 * len(data) - 1), min_size=1, max_size=2,
                                     unique=True)):
                data[bit // 8] ^= 0x80 >> (bit % 8)
        elif kind == 'id':
            frame_id = draw(st.sampled_from([0, 0x7FF] + [m.frame_id for m in DB.messages]))
        elif kind == 'short':
            data = data[:draw(st.integers(0, len(data) - 1))]
        events.append((frame_id, bytes(data), draw(st.floats(0.0, 0.1))))
    return events, sent


@settings(max_examples=100, deadline=None)
@given(traffic())
def test_every_frame_is_accepted_once_or_counted_once_and_nothing_else_is_accepted(case):
    events, sent = case
    checker = cp.FrameChecker(DB)
    now, outcomes = 0.0, 0
    for frame_id, data, dt in events:
        now += dt
        before = dict(checker.counters())
        result = checker.check(frame_id, data, now)
        changed = {k for k, v in checker.counters().items() if v != before[k]} - {'lost'}
        assert len(changed) == 1  # exactly one of accepted, unknown, malformed, crc, replayed
        outcomes += 1
        if result is not None:
            message, values = result
            # only a frame that was sent, under the ID it was sent with (at most two bits flipped
            # cannot make another valid frame), with values inside the DBC ranges
            assert (frame_id, data) in sent and message.frame_id == frame_id
            for signal in message.signals:
                assert signal.minimum <= values[signal.name] <= signal.maximum
    counts = checker.counters()
    assert outcomes == sum(v for k, v in counts.items() if k != 'lost')


def test_frame_bits_worst_case_stuffing():
    # 8 data bytes, 11-bit ID: 111 bits unstuffed incl. 3-bit IFS, + 24 worst-case stuff bits.
    assert cp.frame_bits(8) == 135
    assert cp.frame_bits(0) == 55


def test_bus_load_from_the_dbc_fits_the_budget_and_matches_the_doc():
    bitrate = params.load('hardware')['hardware.arm_bus.bitrate']
    samples = [f'ARM_SEG{i}_SAMPLE' for i in range(1, 5)]
    sample_load = cp.bus_load(DB, bitrate, names=samples)
    total = cp.bus_load(DB, bitrate)
    assert sample_load <= total <= 0.60
    assert [DB.get_message_by_name(n).cycle_time for n in samples] == [1, 1, 1, 1]  # 1 kHz
    doc = (ROOT / 'docs' / 'protocols.md').read_text()
    stated = re.search(r'total worst-case load: \*\*([0-9.]+) %\*\*', doc)
    assert stated is not None and float(stated.group(1)) == pytest.approx(100 * total, abs=0.05)


# The precompiled frame codec gives cantools' bytes and values for every frame of the DBC.
def _cantools_frame(message, values, counter):
    """Encode the reference way: cantools' strict encode, CRC over ID + data, encode again."""
    values = dict(values, Counter=counter & 0xFF, CRC=0)
    data = message.encode(values)
    crc_byte = message.get_signal_by_name('CRC').start // 8
    covered = bytes(data[:crc_byte]) + bytes(data[crc_byte + 1:])
    values['CRC'] = cp.crc8_j1850(message.frame_id.to_bytes(2, 'little') + covered)
    return message.encode(values, strict=False)


@st.composite
def frames(draw):
    message = draw(st.sampled_from(DB.messages))
    values = {}
    for signal in message.signals:
        if signal.name in ('Counter', 'CRC'):
            continue
        steps = draw(st.integers(round(signal.minimum / signal.scale),
                                 round(signal.maximum / signal.scale)))
        fraction = draw(st.sampled_from([0.0, 0.25, 0.5, 0.499]))
        value = min(max((steps + fraction) * signal.scale, signal.minimum), signal.maximum)
        values[signal.name] = value if draw(st.booleans()) else float(value)
    return message, values, draw(st.integers(0, 1000))


@settings(max_examples=400, deadline=None)
@given(frames())
def test_encode_and_decode_match_cantools(frame):
    message, values, counter = frame
    data = cp.encode_frame(message, values, counter)
    assert data == _cantools_frame(message, values, counter)
    decoded = cp.codec(message).decode(data)
    reference = message.decode(data, decode_choices=False)
    assert decoded == reference
    assert [type(v) for v in decoded.values()] == [type(v) for v in reference.values()]


@settings(max_examples=300, deadline=None)
@given(st.sampled_from(DB.messages), st.data())
def test_decode_of_arbitrary_bytes_matches_cantools(message, data):
    payload = data.draw(st.binary(min_size=message.length, max_size=message.length))
    assert cp.codec(message).decode(payload) == message.decode(payload, decode_choices=False)


@pytest.mark.parametrize('values', [
    {'P1': 2e6, 'P2': 1e5, 'Psi': 0.0},                 # above the DBC maximum
    {'P1': 2e5, 'P2': 1e5, 'Psi': -3.3},                # below the DBC minimum
    {'P1': float('nan'), 'P2': 1e5, 'Psi': 0.0},        # not a number
    {'P1': 2e5, 'P2': 1e5},                             # a signal missing
    {'P1': 2e5, 'P2': 1e5, 'Psi': 0.0, 'Typo': 1.0},    # an unknown signal
])
def test_bad_values_are_refused_like_cantools_strict_mode(values):
    with pytest.raises(cantools.database.EncodeError, match='ARM_SEG1_SAMPLE'):
        cp.encode_frame(DB.get_message_by_name('ARM_SEG1_SAMPLE'), values, 0)
