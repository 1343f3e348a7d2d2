"""CAN protocol of the arm: DBC round trips, integrity checks, fuzzing, bus load from the DBC."""
import re
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bellows_ros import params
from bellows_ros.hardware import can_protocol as cp

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
    with pytest.raises(Exception):
        cp.encode_frame(SEG1, {'P1': 2e6, 'P2': 1e5, 'Psi': 0.0}, 0)


def test_replayed_corrupt_and_misaddressed_frames_are_rejected_and_counted():
    checker = cp.FrameChecker(DB)
    f0 = cp.encode_frame(SEG1, {'P1': 2e5, 'P2': 1e5, 'Psi': 0.1}, 10)
    f1 = cp.encode_frame(SEG1, {'P1': 2e5, 'P2': 1e5, 'Psi': 0.2}, 11)
    f4 = cp.encode_frame(SEG1, {'P1': 2e5, 'P2': 1e5, 'Psi': 0.3}, 14)
    assert checker.check(SEG1.frame_id, f0, 0.000) is not None
    assert checker.check(SEG1.frame_id, f1, 0.001) is not None
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
        covered = data[:crc_byte] + data[crc_byte + 1:] + message.frame_id.to_bytes(2, 'little')
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
