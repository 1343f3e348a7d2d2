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

"""Control effort figures (`control.effort`) against signals whose effort is known by hand."""
import math

import numpy as np
import pytest

from bellows_ros.control import effort


def test_command_variation_counts_both_chains_per_second():
    t = np.arange(11) * 0.1  # 1 s
    square = np.where(np.arange(11) % 2, 2e5, 1e5)  # 10 jumps of 1 bar
    flat = np.full(11, 1e5)
    assert effort.command_variation(t, square, flat) == pytest.approx(10 * 1e5)
    assert effort.command_variation(t, square, square) == pytest.approx(20 * 1e5)
    assert effort.command_variation(t, flat, flat) == 0.0


def test_air_used_counts_only_filling():
    # fill 1 bar, vent it, fill it again: 2 bar admitted = 2 x 101325 / P_NORMAL NL per L
    p = np.array([1.0, 1.5, 2.0, 1.0, 2.0]) * 101325.0
    assert effort.air_used(p) == pytest.approx(2.0)
    assert effort.air_used(p, p) == pytest.approx(4.0)
    assert effort.air_used(p[::-1][:2]) == 0.0  # venting only


def test_hold_chatter_takes_each_hold_after_settling():
    t = np.arange(0, 4.0, 0.01)
    holding = (t >= 1.0) & (t < 3.0)
    command = np.full_like(t, 1e5)
    command[(t >= 1.0) & (t < 1.2)] = 5e5  # the end of the move: inside the settling time
    command[(t >= 2.0) & (t < 2.5)] += 2e4 * np.sin(40 * t[(t >= 2.0) & (t < 2.5)])
    median, worst = effort.hold_chatter(t, holding, (command, np.full_like(t, 1e5)), settle=0.3)
    assert median == worst == pytest.approx(4e4, rel=0.01)
    assert all(math.isnan(v) for v in effort.hold_chatter(t, np.zeros_like(t, bool), (command,)))
