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
Safety limits applied in the driver layer before anything reaches a device.

Pure functions plus one small watchdog; the drivers count every event they report.

API
---
- ``clamp_pressures(values, p_min, p_max) -> (list[float], n_clamped, n_invalid)``: non-finite
  set-points become `p_min` (vent: the safe state of a soft arm), the rest are clamped into [p_min,
  p_max].
- ``limit_duty(duty, duty_max, at_low_stop, at_high_stop) -> (duty, reason)``; reason is one of
  None, 'invalid', 'clamped', 'end_stop'.
- ``Watchdog(timeout)``: ``kick(now)``, ``expired(now) -> bool`` (time.monotonic seconds).
"""
import math


def clamp_pressures(values, p_min, p_max):
    """Clamp pressure set-points (Pa abs) into [p_min, p_max]."""
    out, clamped, invalid = [], 0, 0
    for value in values:
        value = float(value)
        if not math.isfinite(value):
            out.append(p_min)
            invalid += 1
        elif value < p_min or value > p_max:
            out.append(min(max(value, p_min), p_max))
            clamped += 1
        else:
            out.append(value)
    return out, clamped, invalid


def into_end_stop(duty, at_low_stop, at_high_stop):
    """
    Tell whether `duty` drives further into an end stop the plate is already at.

    Positive duty compresses the air chamber (x_c grows) towards the high stop.
    """
    return (duty < 0 and at_low_stop) or (duty > 0 and at_high_stop)


def limit_duty(duty, duty_max, at_low_stop, at_high_stop):
    """Motor duty (-1..1) limited to +-duty_max and never driving further into an end stop."""
    duty = float(duty)
    if not math.isfinite(duty):
        return 0.0, 'invalid'
    if into_end_stop(duty, at_low_stop, at_high_stop):
        return 0.0, 'end_stop'
    if abs(duty) > duty_max:
        return math.copysign(duty_max, duty), 'clamped'
    return duty, None


class Watchdog:
    """Expires `timeout` seconds after the last kick (or after creation)."""

    def __init__(self, timeout, now):
        self.timeout = float(timeout)
        self.last_kick = now

    def kick(self, now):
        self.last_kick = now

    def expired(self, now):
        return now - self.last_kick > self.timeout
