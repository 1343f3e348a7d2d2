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

"""Pairing the two halves of an arm sample (nodes/sample_pairing.py), as the nodes configure it."""
from types import SimpleNamespace

from bellows_ros import interfaces
from bellows_ros.nodes import model_node
from bellows_ros.nodes.sample_pairing import CHAMBERS, JOINTS, SamplePairs


def half(index):
    """Return a half-sample stamped `index` ms (only the header matters to the pairing)."""
    stamp = SimpleNamespace(sec=index // 1000, nanosec=index % 1000 * 1_000_000)
    return SimpleNamespace(header=SimpleNamespace(stamp=stamp))


def default(specs, name):
    return next(spec.default for spec in specs if spec.name == name)


def test_a_burst_of_one_topic_as_deep_as_its_queue_still_pairs_whole():
    # A reliable reader delivers what it holds at once (a repaired hole, an executor that fell
    # behind): every joint-state half of a queue's depth may come before the first chamber half.
    pairs = SamplePairs(default(model_node.PARAMETERS, 'max_pending'))
    depth = interfaces.SAMPLE_DEPTH
    assert [pairs.add(half(i), JOINTS) for i in range(depth)] == [None] * depth
    paired = [pairs.add(half(i), CHAMBERS) for i in range(depth)]
    assert [sample[0] for sample in paired] == [i * 1_000_000 for i in range(depth)]
    assert pairs.dropped == 0 and not pairs.pending


def test_halves_beyond_max_pending_are_dropped_oldest_first_and_counted():
    pairs = SamplePairs(3)
    for i in range(5):
        assert pairs.add(half(i), JOINTS) is None
    assert pairs.dropped == 2 and list(pairs.pending) == [2_000_000, 3_000_000, 4_000_000]
    assert pairs.add(half(0), CHAMBERS) is None           # its partner is gone: pending again
    assert pairs.add(half(4), CHAMBERS)[0] == 4_000_000   # a kept one pairs
    assert pairs.dropped == 3
