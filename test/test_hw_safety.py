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
The driver layer's safety rules (hardware/safety.py): pressure clamp, duty limit, watchdog.

A non-finite pressure set-point vents its chamber (p_min, the soft arm's safe state); a motor duty
never drives further into an end stop the plate is at; the watchdog reads the clock it is given.
"""
import math

import pytest

from bellows_ros.hardware.safety import clamp_pressures, into_end_stop, limit_duty, Watchdog

P_MIN, P_MAX = 101325.0, 7.5e5  # Pa abs: the segment's p0 and p_max


def test_pressures_in_range_pass_unchanged_and_the_bounds_are_in_range():
    values = [P_MIN, 2e5, 3.5e5, P_MAX]
    assert clamp_pressures(values, P_MIN, P_MAX) == (values, 0, 0)


def test_pressures_out_of_range_are_clamped_and_counted():
    out, clamped, invalid = clamp_pressures([8e5, 5e4, 0.0, -1e5, 2e5], P_MIN, P_MAX)
    assert out == [P_MAX, P_MIN, P_MIN, P_MIN, 2e5]
    assert (clamped, invalid) == (4, 0)


def test_non_finite_pressures_vent_and_are_counted_as_invalid_not_clamped():
    out, clamped, invalid = clamp_pressures([math.nan, math.inf, -math.inf, 3e5], P_MIN, P_MAX)
    # +inf would clamp to p_max: the vent is the safe state, not the most pressure allowed
    assert out == [P_MIN, P_MIN, P_MIN, 3e5]
    assert (clamped, invalid) == (0, 3)
    out, _, _ = clamp_pressures([200000], P_MIN, P_MAX)  # an int set-point comes out a float
    assert out == [2e5] and type(out[0]) is float


@pytest.mark.parametrize('duty, low, high, expected', [
    (0.5, False, False, (0.5, None)),
    (-0.5, False, False, (-0.5, None)),
    (0.95, False, False, (0.8, 'clamped')),
    (-3.0, False, False, (-0.8, 'clamped')),
    # positive duty compresses the chamber, towards the high stop
    (0.5, False, True, (0.0, 'end_stop')),
    (-0.5, True, False, (0.0, 'end_stop')),
    (0.95, False, True, (0.0, 'end_stop')),   # the end stop wins over the clamp
    (0.5, True, False, (0.5, None)),          # away from the stop it is at
    (-0.5, False, True, (-0.5, None)),
    (0.0, True, True, (0.0, None)),
    (math.nan, False, False, (0.0, 'invalid')),
    (math.inf, False, False, (0.0, 'invalid')),
    (-math.inf, True, False, (0.0, 'invalid')),
])
def test_limit_duty(duty, low, high, expected):
    assert limit_duty(duty, 0.8, low, high) == expected


def test_zero_duty_drives_into_no_end_stop():
    assert not into_end_stop(0.0, True, True)
    assert into_end_stop(1e-9, False, True) and into_end_stop(-1e-9, True, False)


def test_watchdog_expires_only_after_its_timeout_since_the_last_kick():
    # the times are the clock readings given, not waited for
    dog = Watchdog(0.25, now=100.0)
    assert not dog.expired(100.25)         # at the timeout exactly: not yet
    assert dog.expired(100.2501)
    dog.kick(101.0)
    assert not dog.expired(101.25) and dog.expired(101.3)
