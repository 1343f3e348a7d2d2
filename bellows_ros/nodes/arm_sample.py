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
Reads an arm sample message: (Ψ, Ψ̇, p1, p2) per segment, checked.

The driver publishes each 1 kHz arm sample as one `/joint_states` message: the segments' joints,
then their chambers (docs/interfaces.md topic contract). A node that needs Ψ and the chain
pressures of the same instant (the model node, the arm controller) takes both from it by name.
"""
import math

from bellows_ros import interfaces


class ArmSampleReader:
    """
    Read (Ψ rad, Ψ̇ rad/s, p1 Pa, p2 Pa) of `segments` (1-based numbers) from arm sample messages.

    `rows(msg)` -> one tuple per segment, or None to reject the message: it misses a name, holds
    a non-finite value, or a pressure outside [0, p_limit] Pa (the caller counts it). A message
    without rates (an empty `velocity`) reads Ψ̇ = 0: a driver without a rate estimate.
    """

    def __init__(self, segments, p_limit):
        self.p_limit = p_limit
        self.index = interfaces.SampleIndex(
            name for i in segments for name in interfaces.segment_sample_names(i))

    def rows(self, msg):
        layout = self.index(msg.name)
        if layout is None:
            return None
        position, velocity, effort = msg.position, msg.velocity, msg.effort
        try:
            rows = [(position[layout[k]], velocity[layout[k]] if len(velocity) else 0.0,
                     effort[layout[k + 1]], effort[layout[k + 2]])
                    for k in range(0, len(layout), 3)]
        except IndexError:  # arrays shorter than the names: a malformed message
            return None
        if not all(math.isfinite(v) for row in rows for v in row) or \
                not all(0.0 <= p <= self.p_limit for row in rows for p in row[2:]):
            return None
        return rows
