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

"""The precompiled frame codec gives cantools' bytes and values for every frame of the DBC."""
import cantools
from hypothesis import given, settings
from hypothesis import strategies as st
import pytest

from bellows_ros.hardware import can_protocol as cp

DB = cp.load_dbc()


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
