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

"""The struct-based CDR path of the message classes writes and reads cyclonedds' exact bytes."""
from cyclonedds.idl import IdlStruct
from hypothesis import given, settings
from hypothesis import strategies as st
import pytest

from bellows_ros.runtime.messages import msg

names = st.lists(st.text(max_size=12), max_size=6)
floats = st.lists(st.floats(allow_nan=False), max_size=5)


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(names, floats, floats, floats, st.integers(-2**31, 2**31 - 1), st.integers(0, 2**32 - 1),
       st.text(max_size=7))
def test_joint_state_bytes_and_round_trip_match_cyclonedds(name, position, velocity, effort, sec,
                                                           nanosec, frame_id):
    state = msg.JointState(name=name, position=position, velocity=velocity, effort=effort)
    state.header.stamp.sec, state.header.stamp.nanosec = sec, nanosec
    state.header.frame_id = frame_id
    data = state.serialize(use_version_2=False)     # what the DataWriter asks for (XCDR1)
    assert data == IdlStruct.serialize(state, use_version_2=False)
    back = msg.JointState.deserialize(data)
    assert back == msg.JointState.__idl__.deserialize(data) == state


def test_other_fast_types_and_the_generic_fallbacks():
    wrench = msg.WrenchStamped()
    wrench.header.frame_id, wrench.wrench.force.z = 'actuator', -12.5
    data = wrench.serialize(use_version_2=False)
    assert data == IdlStruct.serialize(wrench, use_version_2=False)
    assert msg.WrenchStamped.deserialize(data) == wrench
    # XCDR2 goes through cyclonedds unchanged.
    assert wrench.serialize(use_version_2=True) == IdlStruct.serialize(wrench, use_version_2=True)
    assert msg.WrenchStamped.deserialize(wrench.serialize(use_version_2=True)) == wrench
    array = msg.DiagnosticArray(status=[msg.DiagnosticStatus(name='n', values=[
        msg.KeyValue(key='k', value='v')])])
    data = array.serialize(use_version_2=False)  # a sequence of messages: the struct path too
    assert data == IdlStruct.serialize(array, use_version_2=False)
    assert msg.DiagnosticArray.deserialize(data) == array
