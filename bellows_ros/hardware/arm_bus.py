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
Driver for the soft arm on CAN (python-can + the DBC of `can_protocol`).

A reader thread decodes and checks every frame and assembles the per-segment frames of one sampling
instant (same Counter) into one `ArmSample`. A transmit thread sends, at the DBC cycle times, the
host heartbeat and the newest pressure set-points, and runs the command watchdog.

API
---
- ``config``: ``bellows_ros.config.hardware.arm_bus_config(params_path=None) -> ArmBusConfig``
  (config/hardware.yaml, ``hardware.arm_bus.*``).
- ``open_bus(config, **kwargs) -> can.BusABC``: ``can.Bus(interface=config.interface,
  channel=config.channel, **kwargs)`` (socketcan on the robot; virtual / udp_multicast in tests).
- ``ArmBus(config, bus=None, on_sample=None)``, a `device.Device`: takes ownership of `bus`
  (default ``open_bus(config)``); ``.start()`` starts the threads; ``on_sample(sample: ArmSample)``
  is called from the reader thread for every complete sample.
- ``.read() -> ArmSample | None`` (None when there is none or it is stale); ``.stale``;
  ``.arm_status -> dict | None`` (last ARM_STATUS signals).
- ``.write(pressures)``: 2 x n_segments set-points, Pa abs, order segment_1/chain_1,
  segment_1/chain_2, segment_2/chain_1, ...; clamped into [pressure_min, pressure_max], non-finite
  -> vent.
- ``.vent()``, ``.release()``, ``.vented``, ``.at_rest(tolerance)``; ``.health() -> dict[str,
  int]``; ``.close()`` (vents, stops the threads, shuts the bus down).
"""
import dataclasses
import logging
import threading
import time

import can

from bellows_ros.hardware import can_protocol as cp
from bellows_ros.hardware.can_echo_filter import drop_own_frames
from bellows_ros.hardware.device import Device
from bellows_ros.hardware.loopback_can import LoopbackUdpMulticastBus
from bellows_ros.hardware.safety import clamp_pressures, Watchdog
from bellows_ros.hardware.sample_delivery import deliver, fresh

log = logging.getLogger(__name__)


def open_bus(config, **kwargs):
    """
    Open the python-can bus named by the config.

    `kwargs` go to the interface (e.g. the udp_multicast port).
    """
    return open_can(config.interface, config.channel, **kwargs)


def open_can(interface, channel, **kwargs):
    """
    `can.Bus(interface=..., channel=...)`; `udp_multicast`, the simulated bus, stays on loopback.

    For `udp_multicast` the bus is `loopback_can.LoopbackUdpMulticastBus`: the channel must be an
    IPv4 multicast address (ParameterError otherwise, before any socket or lookup), and the socket
    is bound to loopback before it joins or sends anything (hardware/loopback_can.py).
    """
    if interface == 'udp_multicast':
        return LoopbackUdpMulticastBus(channel, **kwargs)
    return can.Bus(interface=interface, channel=channel, **kwargs)


@dataclasses.dataclass(frozen=True)
class ArmSample:
    """
    One sampling instant of every segment.

    t_receive: time.monotonic() when the reader took the last frame of the instant, s; index: the
    unwrapped frame counter (starts at the first counter received; exact unless more than 255
    instants in a row are lost, counted in `resyncs`); t_device: index x sample period, s
    (nominal); psi: segment angles, rad; pressures: chain pressures, Pa abs, order (seg1 chain1,
    seg1 chain2, seg2 chain1, ...); t_arrival: the bus's receive timestamp of that frame, s on the
    system clock (`time.time()`: SocketCAN's and udp_multicast's kernel timestamp), or None when
    the bus gives none. Unlike t_receive it does not grow while frames wait in the socket for a
    reader that is not scheduled: the driver stamps from it (`sample_delivery.arrival_ns`).
    """

    t_receive: float
    index: int
    t_device: float
    psi: tuple
    pressures: tuple
    t_arrival: float = None

    def at(self, pressure, tolerance):
        """Tell whether every chamber reads within `tolerance` Pa of `pressure` (Pa abs)."""
        return all(abs(p - pressure) <= tolerance for p in self.pressures)


class ArmBus(Device):
    name = 'arm'

    def __init__(self, config, bus=None, on_sample=None):
        self.config = config
        self.db = cp.load_dbc(config.dbc or None)
        self._bus = bus if bus is not None else open_bus(config)
        self._on_sample = on_sample
        self._checker = cp.FrameChecker(self.db)
        n = config.n_segments
        self._segment_ids = {self.db.get_message_by_name(f'ARM_SEG{i + 1}_SAMPLE').frame_id: i
                             for i in range(n)}
        self._sample_period = self.db.get_message_by_name('ARM_SEG1_SAMPLE').cycle_time * 1e-3
        self._status_id = self.db.get_message_by_name('ARM_STATUS').frame_id
        self._heartbeat = self.db.get_message_by_name('ARM_HOST_HEARTBEAT')
        self._setpoint_frames = [m for m in self.db.messages if m.name.startswith('ARM_SETPOINT_')]
        self._tx_period = self._heartbeat.cycle_time * 1e-3
        self._tx_counter = {m.frame_id: 0 for m in [self._heartbeat] + self._setpoint_frames}
        self.echo_filtered = drop_own_frames(self._bus, self._tx_counter)  # see can_echo_filter
        self._pending = {}          # counter -> {segment: values}
        self._last_counter = None
        self._last_stamp = 0.0
        self._index = 0
        self._latest = None
        self.arm_status = None
        self._setpoints = [config.pressure_min] * (2 * n)
        self._lock = threading.Lock()
        self._watchdog = Watchdog(config.command_timeout, time.monotonic())
        self._vented = True         # nothing commanded yet: hold the vented state
        self.latched = False        # vented on request (vent()): commands refused until release()
        self._counts = dict.fromkeys(
            ['samples', 'callback_errors', 'incomplete', 'resyncs', 'clamped_setpoints',
             'invalid_setpoints', 'watchdog_vents', 'tx_errors', 'refused_while_vented'], 0)
        self._stop = threading.Event()
        self._reader = threading.Thread(target=self._read_loop, name='arm-reader', daemon=True)
        self._writer = threading.Thread(target=self._tx_loop, name='arm-tx', daemon=True)
        self._opened = False

    @property
    def link(self):
        return f'{self.config.interface}:{self.config.channel}'

    def start(self):
        if not self._opened:
            self._opened = True
            self._reader.start()
            self._writer.start()

    # -- state for the next layer ---------------------------------------------------------------
    def read(self):
        return fresh(self._latest, self.config.stale_timeout)

    @property
    def vented(self):
        """True while the chambers are held vented: latched, or no set-point since the watchdog."""
        return self._vented or self.latched

    def at_rest(self, tolerance):
        sample = self.read()
        return sample is not None and sample.at(self.config.pressure_min, tolerance)

    def health(self):
        out = dict(self._counts)
        out.update(self._checker.counters())
        return out

    # -- commands -------------------------------------------------------------------------------
    def write(self, pressures):
        """Set-points per chamber (Pa abs); sent with the next ARM_SETPOINT cycle."""
        if len(pressures) != 2 * self.config.n_segments:
            raise ValueError(f'expected {2 * self.config.n_segments} pressure set-points, '
                             f'got {len(pressures)}')
        values, clamped, invalid = clamp_pressures(pressures, self.config.pressure_min,
                                                   self.config.pressure_max)
        with self._lock:
            if self.latched:
                self._counts['refused_while_vented'] += 1
                return None
            self._counts['clamped_setpoints'] += clamped
            self._counts['invalid_setpoints'] += invalid
            self._setpoints = values
            self._watchdog.kick(time.monotonic())
            self._vented = False
        return values

    def vent(self):
        """
        Vent every chamber now and refuse set-points until `release()` (the stop that latches).

        Takes effect at the transmit thread's next cycle, whatever the command path is doing:
        nothing else needs to run for the valves to exhaust.
        """
        with self._lock:
            self.latched = True
            self._vented = True
            self._setpoints = [self.config.pressure_min] * len(self._setpoints)

    def release(self):
        """Accept set-points again; the chambers stay vented until the next one arrives."""
        with self._lock:
            self.latched = False

    # -- threads --------------------------------------------------------------------------------
    def _send(self, message, values):
        counter = (self._tx_counter[message.frame_id] + 1) & 0xFF
        self._tx_counter[message.frame_id] = counter
        frame = can.Message(arbitration_id=message.frame_id, is_extended_id=False,
                            data=cp.encode_frame(message, values, counter))
        try:
            self._bus.send(frame, timeout=0.01)
        except can.CanError:
            self._counts['tx_errors'] += 1

    def _tx_loop(self):
        next_time = time.monotonic()
        while not self._stop.is_set():
            next_time = max(next_time + self._tx_period, time.monotonic() - self._tx_period)
            self._stop.wait(max(0.0, next_time - time.monotonic()))
            with self._lock:
                if not self._vented and self._watchdog.expired(time.monotonic()):
                    self._vented = True
                    self._counts['watchdog_vents'] += 1
                    log.warning('arm bus: no pressure command for %.3f s, venting all chambers',
                                self.config.command_timeout)
                if self._vented:
                    self._setpoints = [self.config.pressure_min] * len(self._setpoints)
                setpoints = list(self._setpoints)
            self._send_setpoints(setpoints)
            self._send(self._heartbeat, {'Enable': 1})

    def _send_setpoints(self, setpoints):
        for message in self._setpoint_frames:
            values = {}
            for signal in message.signals:
                chamber = cp.chamber_of(signal.name)
                if chamber is not None:  # chambers of absent segments stay vented
                    values[signal.name] = (setpoints[chamber] if chamber < len(setpoints)
                                           else self.config.pressure_min)
            self._send(message, values)

    def _read_loop(self):
        while not self._stop.is_set():
            try:
                frame = self._bus.recv(timeout=0.05)
            except can.CanError as error:
                log.warning('arm bus: receive failed (%s)', error)
                self._stop.wait(0.1)
                continue
            if frame is None or frame.is_error_frame or frame.is_remote_frame:
                continue
            if frame.arbitration_id in self._tx_counter:
                continue  # our own frames, echoed by the bus (udp_multicast loops back)
            now = time.monotonic()
            # Arrival time at the interface (kernel / bus timestamp): unlike `now`, not delayed by
            # frames queueing while this thread was not scheduled.
            stamp = frame.timestamp or now
            checked = self._checker.check(frame.arbitration_id, frame.data, stamp)
            if checked is None:
                continue
            message, values = checked
            segment = self._segment_ids.get(message.frame_id)
            if segment is not None:
                self._collect(segment, values, now, stamp, frame.timestamp or None)
            elif message.frame_id == self._status_id:
                self.arm_status = values

    def _collect(self, segment, values, now, stamp, arrival):
        counter = values['Counter']
        parts = self._pending.setdefault(counter, {})
        parts[segment] = values
        if len(parts) < self.config.n_segments:
            if len(self._pending) > 4:  # instants that never complete: a segment frame was lost
                oldest = next(iter(self._pending))
                del self._pending[oldest]
                self._counts['incomplete'] += 1
            return
        del self._pending[counter]
        # Older instants still pending can no longer complete in order.
        for old in [c for c in self._pending if (counter - c) & 0xFF < 128]:
            del self._pending[old]
            self._counts['incomplete'] += 1
        if self._last_counter is None:
            self._index = counter
        else:
            delta = (counter - self._last_counter) & 0xFF
            if stamp - self._last_stamp > 100 * self._sample_period:
                # After a silence the 8-bit counter cannot tell old from new or count the instants
                # missed beyond 255: take it as the next one (docs/protocols.md).
                delta = delta or 256
                self._counts['resyncs'] += 1
            elif delta == 0 or delta >= 128:  # completed out of order: older than the last one
                self._counts['incomplete'] += 1
                return
            self._index += delta
        self._last_counter = counter
        self._last_stamp = stamp
        n = self.config.n_segments
        sample = ArmSample(
            t_receive=now, index=self._index, t_device=self._index * self._sample_period,
            psi=tuple(parts[i]['Psi'] for i in range(n)),
            pressures=tuple(p for i in range(n) for p in (parts[i]['P1'], parts[i]['P2'])),
            t_arrival=arrival)
        self._latest = sample
        self._counts['samples'] += 1
        deliver(self._on_sample, sample, self._counts, log, 'arm bus')

    def close(self):
        """Vent every chamber, stop the threads, shut the bus down."""
        if self._stop.is_set():
            return
        self._stop.set()
        if self._opened:
            self._writer.join(timeout=1.0)
        self._send_setpoints([self.config.pressure_min] * (2 * self.config.n_segments))
        if self._opened:
            self._reader.join(timeout=1.0)
        self._bus.shutdown()
