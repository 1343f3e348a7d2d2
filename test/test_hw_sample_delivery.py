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
`arrival_ns` takes a bus's receive timestamp off the node clock. The arm's clock settings are
`nodes.device_topics.ARM_CLOCK`.
"""
import time

from bellows_ros.hardware.sample_delivery import arrival_ns, DeviceClock, on_host_clock
from bellows_ros.nodes.device_topics import ARM_CLOCK


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


def test_the_arms_clock_follows_an_oscillator_off_by_half_a_percent():
    """
    The arm's time is its sample count times 1 ms: its oscillator's error is drift on the host.

    On timed arrivals (`device_topics.ARM_CLOCK[True]`) samples from an arm whose clock is 0.5 %
    slow or fast keep ages under a millisecond over 5 minutes: with 100 ppm they grew past
    `max_sample_age` within a minute, and the arm controller took no sample.
    """
    ms = 1_000_000
    for error in (0.005, -0.005):
        clock = DeviceClock(**ARM_CLOCK[True])
        ages = []
        for k in range(0, 300_000, 10):
            arrival = round(k * ms * (1 + error)) + 2 * ms + (k % 7) * 20_000  # jitter 0-0.12 ms
            ages.append(arrival - clock.stamp(k * ms, arrival))
        assert max(ages[1000:]) < ms and min(ages) >= 0, (error, max(ages))


def test_the_untimed_arms_clock_takes_a_new_base_after_an_outage():
    """
    Without timestamps on the host clock (`ARM_CLOCK[False]`): an outage of over 256 ms.

    The 8-bit frame counter leaves the arm's time 256 ms behind: without a new base every later
    sample would look 256 ms old, and the arm would stay vented. After `settle` it is taken; a
    reader stalled for 1.5 s meanwhile (read times late, then a burst) keeps its base.
    """
    untimed = ARM_CLOCK[False]
    ms = 1_000_000
    clock = DeviceClock(**untimed)
    for k in range(1000):
        clock.stamp(k * ms, k * ms + 3 * ms)
    # a stall: 1.5 s of samples read at once, then on time again
    burst = [clock.stamp(k * ms, 2503 * ms + (k - 1000) * 20_000) for k in range(1000, 2500)]
    # their own times, so they are as old as they are (within the drift allowance of the
    # burst's last `resync`)
    assert max(abs(b - (k * ms + 3 * ms)) for k, b in zip(range(1000, 2500), burst)) <= (
        untimed['drift'] * untimed['resync'] * 1e9)
    for k in range(2500, 3000):
        assert clock.stamp(k * ms, k * ms + 3 * ms) == k * ms + 3 * ms
    # an outage of 300 ms counted as one instant: the arm's time 256 ms behind the truth
    late = [clock.stamp(k * ms, (k + 256) * ms + 3 * ms) for k in range(3000, 6000)]
    ages = [(k + 256) * ms + 3 * ms - s for k, s in zip(range(3000, 6000), late)]
    moved = ages.index(0)
    assert ages[0] == 256 * ms and moved == untimed['settle'] * 1000
    assert set(ages[moved:]) == {0}


def test_a_receive_timestamp_on_another_clock_is_no_arrival_time():
    """Some python-can interfaces stamp from the adapter's start: such a time is not used."""
    now = 5_000_000_000
    assert arrival_ns(now, 1234.5) == now and not on_host_clock(1234.5)
    assert not on_host_clock(None) and not on_host_clock(0.0)
    assert on_host_clock(time.time() - 0.3)
    assert now - 0.4e9 < arrival_ns(now, time.time() - 0.3) < now - 0.29e9


def test_device_clock_on_timed_arrivals_follows_a_time_base_that_moved():
    """
    The arm's clock (`device_topics.ARM_CLOCK[True]`): arrivals timed by the bus, not the reader.

    An outage the arm's 8-bit frame counter could not count leaves its time base behind by the
    outage: the clock takes the new base after `settle`. A simulated arm that paused and sent its
    backlog at once keeps its base: those samples are as old as they are.
    """
    timed = ARM_CLOCK[True]
    ms, settle = 1_000_000, int(timed['settle'] * 1e9)
    clock = DeviceClock(**timed)
    assert [clock.stamp(k * ms, k * ms + 5 * ms) for k in range(100)][-1] == 104 * ms
    # 1.3 s without frames, counted as one instant: the device's time goes on from 100 ms.
    device = [(100 + k) * ms for k in range(2000)]
    arrivals = [(1400 + k) * ms + 5 * ms for k in range(2000)]
    stamps = [clock.stamp(d, a) for d, a in zip(device, arrivals)]
    # at first the old base (+ its drift allowance): these look 1.3 s old
    assert abs(stamps[0] - (device[0] + 5 * ms)) <= timed['drift'] * ms
    moved = next(k for k, (s, a) in enumerate(zip(stamps, arrivals)) if s == a)
    assert device[moved] - device[0] == settle  # after `settle` of device time, the new base
    assert stamps[moved:] == arrivals[moved:]
    # A pause of 0.5 s, then its 500 samples at once and on time again: the base does not move.
    clock = DeviceClock(**timed)
    for k in range(100):
        clock.stamp(k * ms, k * ms + 5 * ms)
    burst = [clock.stamp(k * ms, 605 * ms + k * 10_000) for k in range(100, 600)]
    after = [clock.stamp(k * ms, k * ms + 5 * ms) for k in range(600, 3000)]
    # (within the burst's last `resync` the offset may rise by its drift allowance: 0.5 ms)
    assert max(abs(a - (k * ms + 5 * ms)) for k, a in zip(range(100, 600), burst)) <= (
        timed['drift'] * timed['resync'] * 1e9)
    assert after == [k * ms + 5 * ms for k in range(600, 3000)]
