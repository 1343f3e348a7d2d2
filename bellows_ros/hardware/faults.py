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
Fault switches of the simulated devices, settable while they run.

API: ``Faults(drop_rate=0.0, corrupt_rate=0.0, replay_rate=0.0, silent=False, stuck=False,
seed=None)``
- ``drop_rate``: probability that a frame the device should send is not sent.
- ``corrupt_rate``: probability that one byte of a sent frame is overwritten with a random
  different value.
- ``replay_rate``: probability that the previous frame is sent again (CAN: same counter and CRC).
- ``silent``: the device sends nothing (a dead board / unplugged bus stub).
- ``stuck``: the first sensor channel (actuator: pressure; arm: segment 1 chain 1 pressure) freezes
  at the value it had when the switch was set; the device passes that channel through
  ``.sensor(value)`` every tick.

The emulator threads read the attributes every tick, so a test or node may simply assign them
(``sim.faults.silent = True``); single attribute writes are atomic in CPython.
"""
import dataclasses
import random


@dataclasses.dataclass
class Faults:
    drop_rate: float = 0.0
    corrupt_rate: float = 0.0
    replay_rate: float = 0.0
    silent: bool = False
    stuck: bool = False
    seed: int | None = None

    def __post_init__(self):
        self.rng = random.Random(self.seed)
        self._held = None

    def sensor(self, value):
        """Return what the first sensor channel reads: `value`, or while `stuck` the held one."""
        if not self.stuck:
            self._held = None
            return value
        if self._held is None:
            self._held = value
        return self._held

    def drop(self):
        """Whether to drop the frame about to be sent."""
        return self.silent or (self.drop_rate > 0 and self.rng.random() < self.drop_rate)

    def corrupt(self, frame):
        """Return `frame` (bytes), one byte changed with probability `corrupt_rate`."""
        if self.corrupt_rate <= 0 or not frame or self.rng.random() >= self.corrupt_rate:
            return frame, False
        data = bytearray(frame)
        i = self.rng.randrange(len(data))
        data[i] ^= self.rng.randrange(1, 256)
        return bytes(data), True

    def replay(self):
        """Whether to send the previous frame again."""
        return self.replay_rate > 0 and self.rng.random() < self.replay_rate
