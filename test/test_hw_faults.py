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
The fault switches of the simulated devices (hardware/faults.py), called as the emulators do.

Each switch alone: what it does at rate 0 and 1, that a seed makes a run repeatable, and that
`stuck` holds the first sensor channel only while it is set.
"""
from bellows_ros.hardware.faults import Faults

FRAME = bytes(range(1, 9))


def test_no_fault_is_on_by_default():
    faults = Faults(seed=1)
    assert not any(faults.drop() or faults.replay() for _ in range(1000))
    assert all(faults.corrupt(FRAME) == (FRAME, False) for _ in range(1000))
    assert [faults.sensor(v) for v in (1.0, 2.0, 3.0)] == [1.0, 2.0, 3.0]


def test_silent_drops_every_frame_whatever_the_rate():
    faults = Faults(silent=True, drop_rate=0.0, seed=1)
    assert all(faults.drop() for _ in range(1000))
    faults.silent = False  # switched at run time, as a test or node does
    assert not any(faults.drop() for _ in range(1000))


def test_rates_are_probabilities_and_a_seed_repeats_the_run():
    def draws(seed):
        faults = Faults(drop_rate=0.25, replay_rate=0.75, seed=seed)
        return [(faults.drop(), faults.replay()) for _ in range(4000)]
    run = draws(7)
    assert run == draws(7) and run != draws(8)
    dropped = sum(d for d, _ in run) / len(run)
    replayed = sum(r for _, r in run) / len(run)
    # binomial, n = 4000: the standard deviation is under 0.007; a seeded run, not a flaky one
    assert abs(dropped - 0.25) < 0.03 and abs(replayed - 0.75) < 0.03
    assert all(Faults(drop_rate=1.0).drop() for _ in range(100))
    assert all(Faults(replay_rate=1.0).replay() for _ in range(100))


def test_a_corrupted_frame_differs_in_exactly_one_byte():
    faults = Faults(corrupt_rate=1.0, seed=3)
    positions = set()
    for _ in range(500):
        data, corrupted = faults.corrupt(FRAME)
        assert corrupted and isinstance(data, bytes) and len(data) == len(FRAME)
        changed = [i for i, (a, b) in enumerate(zip(data, FRAME)) if a != b]
        assert len(changed) == 1  # a real change: the XOR mask is never 0
        positions.update(changed)
    assert positions == set(range(len(FRAME)))  # any byte, the CRC included
    assert faults.corrupt(b'') == (b'', False)  # nothing to change


def test_stuck_holds_the_value_it_had_when_set_and_lets_go_when_cleared():
    faults = Faults()
    assert faults.sensor(1.0e5) == 1.0e5
    faults.stuck = True
    assert [faults.sensor(v) for v in (2.0e5, 3.0e5, 4.0e5)] == [2.0e5] * 3
    faults.stuck = False
    assert faults.sensor(5.0e5) == 5.0e5
    faults.stuck = True  # set again: holds the new value, not the old one
    assert [faults.sensor(v) for v in (6.0e5, 7.0e5)] == [6.0e5, 6.0e5]
