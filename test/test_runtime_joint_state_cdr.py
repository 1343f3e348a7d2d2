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

"""runtime/joint_state_cdr.py against rclpy's own serialization of sensor_msgs/JointState."""
import math

from hypothesis import given, settings, strategies as st
import pytest
from rclpy.serialization import deserialize_message, serialize_message

from bellows_ros import interfaces
from bellows_ros.runtime.joint_state_cdr import JointStateReader, JointStateWriter
from bellows_ros.runtime.messages import msg

# ROS strings are C strings: no NUL inside (rclpy cuts one off there).
text = st.characters(blacklist_characters='\x00', blacklist_categories=('Cs',))
names = st.lists(st.text(text, max_size=12), max_size=6)
values = st.floats(allow_nan=True, allow_infinity=True)
stamps = st.integers(min_value=0, max_value=2 ** 31 * 1_000_000_000 - 1)
frame_ids = st.text(text, max_size=8)


def same(a, b):
    """Whether two float sequences are equal, NaN equal to NaN."""
    return len(a) == len(b) and all(x == y or (math.isnan(x) and math.isnan(y))
                                    for x, y in zip(a, b))


def message(stamp, name, position, velocity, effort, frame_id=''):
    out = msg.JointState(name=list(name), position=list(position), velocity=list(velocity),
                         effort=list(effort))
    out.header.stamp.sec, out.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
    out.header.frame_id = frame_id
    return out


@settings(max_examples=300, deadline=None)
@given(names, st.tuples(st.booleans(), st.booleans(), st.booleans()), stamps, frame_ids,
       st.data())
def test_what_the_writer_sends_is_what_rclpy_reads(name, sent, stamp, frame_id, data):
    writer = JointStateWriter(name, *sent, frame_id=frame_id)
    arrays = [data.draw(st.lists(values, min_size=len(name), max_size=len(name))) if s else []
              for s in sent]
    got = deserialize_message(writer.serialize(stamp, *arrays), msg.JointState)
    assert (got.header.stamp.sec * 1_000_000_000 + got.header.stamp.nanosec) == stamp
    assert got.header.frame_id == frame_id
    assert list(got.name) == list(name)
    for array, got_array in zip(arrays, (got.position, got.velocity, got.effort)):
        assert same(list(got_array), array)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(names, st.lists(values, max_size=5), st.lists(values, max_size=5),
                          st.lists(values, max_size=5), stamps, frame_ids),
                min_size=1, max_size=4))
def test_the_reader_reads_what_rclpy_sends_names_changing_or_not(messages):
    # One reader for the whole series: the names it keeps from one message must not leak into
    # the next when they change (arrays of any length: JointState does not tie them together).
    reader = JointStateReader()
    for name, position, velocity, effort, stamp, frame_id in messages * 2:
        got = reader(serialize_message(message(stamp, name, position, velocity, effort,
                                               frame_id)))
        assert got.stamp_ns == stamp
        assert got.name == tuple(name)
        assert same(got.position, position) and same(got.velocity, velocity)
        assert same(got.effort, effort)


def test_an_arm_sample_round_trips_through_both():
    names = interfaces.arm_sample_names(range(1, 5))
    n = len(names)
    position, velocity = [0.1 * k for k in range(n)], [0.2] * n
    effort = [1e5 + k for k in range(n)]
    got = JointStateReader()(JointStateWriter(names).serialize(7, position, velocity, effort))
    assert (got.stamp_ns, got.name) == (7, tuple(names))
    assert got.position == tuple(position) and got.velocity == tuple(velocity)
    assert got.effort == tuple(effort)


def test_bytes_that_are_no_joint_state_raise_value_error():
    # The writer's bytes end with the last array (rclpy's may carry padding after it).
    sample = JointStateWriter(['segment_1', 'segment_1/chain_1']).serialize(
        5, [0.1, 0.2], [0.0, 0.0], [1e5, 2e5])
    reader = JointStateReader()
    reader(sample)  # the names are now known: truncations after them must still be caught
    for cut in range(len(sample)):
        with pytest.raises(ValueError):
            reader(sample[:cut])
    with pytest.raises(ValueError):
        reader(b'\x01\x00\x00\x00' + sample[4:])  # big-endian CDR: not what ROS 2 sends here
