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


# s: a receive timestamp further than this from the system clock is on another clock (some
# python-can interfaces count from the adapter's start) and says nothing about the wait.
ON_HOST_CLOCK = 3600.0


def on_host_clock(bus_timestamp):
    """Tell whether `bus_timestamp` (s) is a receive time on the system clock (`arrival_ns`)."""
    return bool(bus_timestamp) and abs(time.time() - bus_timestamp) < ON_HOST_CLOCK


def arrival_ns(now_ns, bus_timestamp=None):
    """
    When a sample reached the host, ns on the clock that read `now_ns` (the node clock).

    `bus_timestamp` is the interface's receive timestamp, s on the system clock (SocketCAN and
    python-can's udp_multicast take it in the kernel, SO_TIMESTAMPNS). The time the frame then
    waited in the socket, for a reader the machine did not schedule, is taken off `now_ns`; so a
    reader that has fallen behind does not stamp old samples as new. Without a timestamp on the
    system clock (None, 0, or one `on_host_clock` refuses) the arrival is `now_ns`.
    """
    if not on_host_clock(bus_timestamp):
        return now_ns
    waited = time.time_ns() - int(bus_timestamp * 1e9)
    return now_ns - max(0, waited)


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


class DeviceClock:
    """
    Stamp a device's samples on the host clock from the device's own clock, without arrival jitter.

    A sample stamped when it arrives carries every scheduling delay of the reader: on a busy
    machine the driver read the board's 1 kHz samples in bursts, stamps 10-19 ms apart and then
    0.05 ms apart, and the doctor refused the record for its "gaps" (docs/workflow.md). The board
    stamps each sample itself (`t_device`); the host time of a sample is its device time plus the
    offset between the clocks, and the least-delayed arrival seen bounds that offset from above:
    `stamp(t_device, t_arrival)` keeps the smallest t_arrival - t_device, lets it rise by at most
    `drift` s per s of device time (so a device clock that runs slow is followed; not while
    arrivals are more than `resync` late) and starts again
    when arrivals come more than `resync` s later than the offset predicts for `settle` s of device
    time (the device restarted, its clock was reset, during a silence; or, for the arm, its 8-bit
    frame counter could not count the instants of an outage). It then takes the least-delayed
    arrival of that stretch. A reader stalled for less than `resync` keeps the device's time base:
    with 1 s, a 1.2 s stall on a loaded machine would stamp the backlog after a hole. Stamps never
    go backwards. Times in ns (int).

    With arrivals timed where the frames reached the host (the arm's kernel timestamps,
    `arrival_ns`), no reader delay is in them, and `resync` can be short: `settle` then tells a
    device that paused and sent its backlog in a burst (arrivals late at first, back on time by
    the burst's end) from a time base that really moved.
    """

    def __init__(self, drift=1e-4, resync=10.0, settle=0.0):
        self.drift, self.resync_ns, self.settle_ns = drift, int(resync * 1e9), int(settle * 1e9)
        self.offset = self._last_device = self._last_stamp = None
        self._late = None  # (device time, least lag) since arrivals came later than `resync`

    def stamp(self, t_device, t_arrival):
        """Return the host-clock stamp, ns, of a sample taken at `t_device` that arrived then."""
        lag = t_arrival - t_device
        restarted = self._last_device is not None and t_device < self._last_device
        late = self.offset is not None and lag - self.offset > self.resync_ns
        if not late:
            self._late = None
        elif self._late is None:
            self._late = (t_device, lag)
        else:
            self._late = (self._late[0], min(self._late[1], lag))
        if self.offset is None or restarted:
            self.offset = lag
        elif late and t_device - self._late[0] >= self.settle_ns:
            self.offset, self._late = self._late[1], None
        elif late:
            pass    # a backlog, or a base that moved (then after `settle`): no drift either way
        else:
            allowed = self.offset + int(self.drift * (t_device - self._last_device))
            self.offset = min(lag, allowed)
        self._last_device = t_device
        stamp = t_device + self.offset
        if self._last_stamp is not None and stamp <= self._last_stamp:
            stamp = self._last_stamp + 1
        self._last_stamp = stamp
        return stamp
