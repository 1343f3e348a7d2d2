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
Handing a driver's samples to the next layer: the freshness check and the reader-thread callback.

Shared by `actuator_board` and `arm_bus`, whose reader threads deliver samples the same way.
"""
import time


def fresh(sample, stale_timeout):
    """`sample`, or None when there is none or it was received more than `stale_timeout` s ago."""
    if sample is None or time.monotonic() - sample.t_receive > stale_timeout:
        return None
    return sample


def deliver(on_sample, sample, counts, log, device):
    """
    Call `on_sample(sample)` (if any) from the reader thread.

    A failure is counted in counts['callback_errors'] and logged once on the driver's `log` as
    `device`, never raised.
    """
    if on_sample is None:
        return
    try:
        on_sample(sample)
    except Exception:  # a failing consumer must not kill the reader (and the watchdogs)
        counts['callback_errors'] += 1
        if counts['callback_errors'] == 1:
            log.exception('%s: on_sample callback failed (further failures only counted)', device)
