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
Pairs the two halves of an arm sample: `/joint_states` and `/bellows/chambers` with one stamp.

The driver publishes each 1 kHz sample as two messages with the same header stamp
(docs/interfaces.md topic contract); a node that needs Ψ and the chain pressures of the same
instant (the model node, the arm controller) waits until both have arrived. Halves that never find
their partner are kept up to `max_pending` stamps, then the oldest is dropped and counted.
`segment_rows` reads a paired sample as (Ψ, Ψ̇, p1, p2) per segment, checked.
"""
from collections import OrderedDict
import math

from bellows_ros.runtime import stamp_ns

JOINTS, CHAMBERS = 0, 1


class SamplePairs:
    """
    Pair the two halves of each sample (joint states, chambers).

    `add(msg, slot)` -> (stamp_ns, joint_states, chambers) when `msg` completes a sample, else
    None; slot is JOINTS or CHAMBERS. `dropped` counts halves given up on.
    """

    def __init__(self, max_pending):
        self.max_pending = max_pending
        self.pending = OrderedDict()  # stamp (ns) -> [joint_states or None, chambers or None]
        self.dropped = 0

    def add(self, msg, slot):
        stamp = stamp_ns(msg.header.stamp)
        entry = self.pending.get(stamp)
        if entry is None:
            entry = self.pending[stamp] = [None, None]
            while len(self.pending) > self.max_pending:
                self.pending.popitem(last=False)
                self.dropped += 1
        entry[slot] = msg
        if entry[0] is None or entry[1] is None:
            return None
        del self.pending[stamp]
        return stamp, entry[0], entry[1]


def segment_rows(joints, chambers, segments, p_limit):
    """
    Read (Ψ rad, Ψ̇ rad/s, p1 Pa, p2 Pa) per segment from a paired sample; None rejects it.

    segments: (name, (chain_1, chain_2)) per segment. A sample that misses a name, holds a
    non-finite value or a pressure outside [0, p_limit] Pa is rejected (the caller counts it).
    A missing Ψ̇ is 0 (a driver without a rate estimate).
    """
    position = dict(zip(joints.name, joints.position))
    velocity = dict(zip(joints.name, joints.velocity))
    pressure = dict(zip(chambers.name, chambers.effort))
    try:
        rows = [(position[name], velocity.get(name, 0.0), pressure[c1], pressure[c2])
                for name, (c1, c2) in segments]
    except KeyError:
        return None
    if not all(math.isfinite(v) for row in rows for v in row) or \
            not all(0.0 <= p <= p_limit for row in rows for p in row[2:]):
        return None
    return rows
