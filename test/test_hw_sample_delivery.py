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
The stamps the driver puts on device samples (hardware/sample_delivery.py): pure arithmetic.

`DeviceClock` maps a device's own clock onto the host's from the least-delayed arrival;
`arrival_ns` takes a bus's receive timestamp off the node clock. The arm's clock settings
(`nodes.device_topics.ARM_CLOCK`: drift, resync, settle) are held to their promises in
test_nodes_device_topics.py.
"""
import time

from bellows_ros.hardware.sample_delivery import arrival_ns, DeviceClock, on_host_clock


def test_device_clock_stamps_a_burst_at_the_times_the_board_took_it():
    clock, ms = DeviceClock(), 1_000_000
    # 1 kHz samples; the reader stalls 18 ms at sample 10 and reads the backlog in a burst.
    burst = [33 * ms + k * 50_000 for k in range(19)]
    arrivals = [5 * ms + k * ms for k in range(10)] + burst
    stamps = [clock.stamp(k * ms, t) for k, t in enumerate(arrivals)]
    assert all(abs(b - a - ms) <= 200 for a, b in zip(stamps, stamps[1:])), stamps  # ns
    assert stamps[0] == 5 * ms  # the least-delayed arrival sets the offset (+ 100 ppm drift)
    # A reader stalled 3 s on a loaded machine: the backlog keeps the device's time base.
    clock = DeviceClock()
    arrivals = [k * ms for k in range(10)] + [3000 * ms + k * 20_000 for k in range(3000)]
    stamps = [clock.stamp(k * ms, t) for k, t in enumerate(arrivals)]
    assert all(abs(b - a - ms) <= 200 for a, b in zip(stamps, stamps[1:]))
    # A device clock 50 ppm slow is followed (the offset rises by at most 100 ppm) ...
    clock = DeviceClock()
    stamps = [clock.stamp(k * ms, int(k * ms * 1.00005)) for k in range(0, 200_000, 50)]
    assert abs(stamps[-1] - int(199_950 * ms * 1.00005)) < ms
    # ... a restarted device (its clock back at 0) starts again, and stamps never go backwards.
    assert clock.stamp(0, stamps[-1] + 7 * ms) == stamps[-1] + 7 * ms
    assert clock.stamp(ms, stamps[-1] + 7 * ms) > stamps[-1] + 7 * ms


def test_a_receive_timestamp_on_another_clock_is_no_arrival_time():
    """Some python-can interfaces stamp from the adapter's start: such a time is not used."""
    now = 5_000_000_000
    assert arrival_ns(now, 1234.5) == now and not on_host_clock(1234.5)
    assert not on_host_clock(None) and not on_host_clock(0.0)
    assert on_host_clock(time.time() - 0.3)
    assert now - 0.4e9 < arrival_ns(now, time.time() - 0.3) < now - 0.29e9
