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
The interface contract (interfaces.py): its own rules, which docs/interfaces.md is held to.

Topic names are relative, so a namespace moves the whole graph, except the three ROS defines as
absolute (`/diagnostics`, `/clock`, `/bellows/estop`); a private name lies under its node. No two
topics share a name in any namespace, every type is a class the runtime can import, and a sample
message names its group's joints, then its chambers, found by name (`SampleIndex`).
"""
import re

import pytest

from bellows_ros import interfaces
from bellows_ros.interfaces import SampleIndex, Topic, TOPICS
from bellows_ros.runtime import messages

ABSOLUTE = {'/diagnostics', '/clock', '/bellows/estop'}


def test_names_are_relative_but_the_three_ros_defines_as_absolute():
    assert {topic.name for topic in TOPICS if topic.name.startswith('/')} == ABSOLUTE
    for topic in TOPICS:
        # a ROS name: tokens of letters, digits and underscores, no empty token, no trailing '/'
        assert re.fullmatch(r'(~/|/)?[a-z][a-z0-9_]*(/[a-z][a-z0-9_]*)*', topic.name), topic
        # a private name belongs to a node, and only a private name does
        assert bool(topic.node) == topic.name.startswith('~/'), topic


def test_no_two_topics_share_a_name_in_any_namespace():
    assert len({topic.name for topic in TOPICS}) == len(TOPICS)
    for namespace in ('/', '/arm_a', '/lab/arm_b/'):
        names = interfaces.by_name(namespace)
        assert len(names) == len(TOPICS), namespace


def test_a_namespace_moves_every_relative_name_and_no_absolute_one():
    moved = interfaces.by_name('/arm_a')
    root = interfaces.by_name()
    assert '/joint_states' in root and '/arm_a/joint_states' in moved
    assert interfaces.JOINT_TRAJECTORY.resolved('/arm_a') == \
        '/arm_a/arm_controller_node/joint_trajectory'
    assert interfaces.TRAJECTORY_STATE.resolved() == '/arm_controller_node/state'
    for topic in TOPICS:
        name = topic.resolved('/arm_a/')
        assert name.startswith('/arm_a/') != (topic.name in ABSOLUTE), name
        assert '//' not in name and topic.resolved() == topic.resolved('/')


def test_every_type_is_a_message_the_runtime_knows():
    short_names = {name.rsplit('/', 1)[1]: name for name in messages.USED_TYPES.values()}
    for topic in TOPICS:
        assert re.fullmatch(r'[a-z_]+/msg/[A-Z][A-Za-z0-9]*', topic.ros_type), topic
        assert short_names.get(topic.message) == topic.ros_type, topic  # runtime's `msg.<name>`
        package = topic.ros_type.split('/')[0]
        try:
            cls = messages.message_class(topic.ros_type)
        except ImportError:
            # the one package without a wheel on PyPI (runtime/messages.py)
            assert package in messages.OPTIONAL_PACKAGES, topic
            continue
        assert cls.__name__ == topic.message and getattr(messages.msg, topic.message) is cls


def test_sample_topics_keep_a_deep_queue_and_latched_ones_the_last_message():
    for topic in (interfaces.JOINT_STATES, interfaces.ACTUATOR_JOINT_STATES, interfaces.WRENCH):
        assert topic.depth == interfaces.SAMPLE_DEPTH
    assert interfaces.SAMPLE_DEPTH * interfaces.SAMPLE_PERIOD >= 5.0  # a 5 s stall loses none
    latched = [topic for topic in TOPICS if topic.latched]
    assert {topic.name for topic in latched} == {'/bellows/estop', 'bellows/vented'}
    assert all(topic.depth == 1 and topic.message == 'Bool' for topic in latched)


def test_a_sample_names_the_joints_then_the_chambers():
    assert interfaces.arm_sample_names([1, 2]) == (
        'segment_1', 'segment_2', 'segment_1/chain_1', 'segment_1/chain_2',
        'segment_2/chain_1', 'segment_2/chain_2')
    assert interfaces.segment_sample_names(3) == ('segment_3', 'segment_3/chain_1',
                                                  'segment_3/chain_2')
    assert interfaces.actuator_sample_names() == ('air_chamber', 'spring', 'actuator')
    names = interfaces.arm_sample_names(range(1, 5)) + interfaces.actuator_sample_names()
    assert len(set(names)) == len(names)  # one arm's and the actuator's names never collide


def test_sample_index_finds_entries_by_name_in_any_order():
    index = SampleIndex(['spring', 'actuator'])
    assert index(['air_chamber', 'spring', 'actuator']) == (1, 2)
    assert index(('actuator', 'extra', 'spring')) == (2, 0)  # another publisher's order
    assert index(['air_chamber', 'spring']) is None           # one lacks the chamber


def test_sample_index_keeps_a_bounded_number_of_layouts():
    index = SampleIndex(['a'])
    for k in range(10 * SampleIndex.MAX_LAYOUTS):
        assert index(['a', f'other_{k}']) == (0,)
        assert len(index._layouts) <= SampleIndex.MAX_LAYOUTS
    assert index(['x', 'a']) == (1,)  # still right after the cache was cleared


def test_a_topic_is_immutable():
    with pytest.raises(AttributeError):
        interfaces.JOINT_STATES.name = 'other'
    assert Topic('a/b', 'std_msgs/msg/Bool', 1, '').message == 'Bool'
