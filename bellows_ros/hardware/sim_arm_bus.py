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
Simulated arm: the firmware side of the arm's CAN protocol on a python-can bus.

API
---
- ``SimArmBus(bus, step, n_segments=4, faults=None, dbc=None)`` ``step(dt: float, setpoints:
  tuple[float, ...]) -> sequence of n_segments (p1, p2, psi)`` advances the plant by dt seconds
  with the chamber pressure set-points the valves apply (Pa abs, order seg1 chain1, seg1 chain2,
  ...) and returns the measured chain pressures (Pa abs) and angle (rad) per segment.
- ``.start()`` starts the 1 kHz loop, ``.stop()`` stops it (the arm goes silent), ``.close()``
  (also shuts `bus` down: the emulator owns it).
- ``.faults`` (`Faults`, settable at run time); ``.setpoints`` (what the valves apply now);
  ``.health()``; ``.stats`` (LoopStats).
- A `device.Device` seen from the arm's side: ``.read()`` the last sample it sent (an `ArmSample`),
  ``.write(pressures)`` set-points as if from a host, ``.vent()``, ``.release()``, ``.vented``,
  ``.at_rest(tolerance)``.

Arm behaviour (docs/protocols.md): one ARM_SEGi_SAMPLE per segment per period (DBC cycle time, 1
ms), all carrying the instant's number as Counter; ARM_STATUS every 100 ms; host frames are
CRC/counter-checked like on the driver side; every chamber vents after `ARM_HEARTBEAT_TIMEOUT`
without a host heartbeat.
"""
import logging
import time

import can

from bellows_ros.config.hardware import vent_pressure as ambient_pressure
from bellows_ros.hardware import can_protocol as cp
from bellows_ros.hardware.arm_bus import ArmSample
from bellows_ros.hardware.can_echo_filter import drop_own_frames
from bellows_ros.hardware.device import Device
from bellows_ros.hardware.faults import Faults
from bellows_ros.hardware.loop_timing import device_steps, LoopStats, LoopThread, PeriodicLoop
from bellows_ros.hardware.safety import clamp_pressures

log = logging.getLogger(__name__)


class SimArmBus(Device):
    name = 'arm'

    def __init__(self, bus, step, n_segments=4, faults=None, dbc=None, vent_pressure=None):
        self.db = cp.load_dbc(dbc)
        self._bus = bus
        self._step = step
        self.n_segments = n_segments
        self.faults = faults if faults is not None else Faults()
        self.stats = LoopStats()
        self._checker = cp.FrameChecker(self.db)
        self._samples = [self.db.get_message_by_name(f'ARM_SEG{i + 1}_SAMPLE')
                         for i in range(n_segments)]
        self._status = self.db.get_message_by_name('ARM_STATUS')
        self._heartbeat_id = self.db.get_message_by_name('ARM_HOST_HEARTBEAT').frame_id
        self._setpoint_ids = {m.frame_id for m in self.db.messages
                              if m.name.startswith('ARM_SETPOINT_')}
        self._own_ids = {m.frame_id for m in self._samples} | {self._status.frame_id}
        self.echo_filtered = drop_own_frames(bus, self._own_ids)  # in the kernel where possible
        self.period = self._samples[0].cycle_time * 1e-3
        self._status_every = max(1, round(self._status.cycle_time * 1e-3 / self.period))
        p1 = self._samples[0].get_signal_by_name('P1')
        psi = self._samples[0].get_signal_by_name('Psi')
        self._p_range = (p1.minimum, p1.maximum)
        # The highest set-point a frame can carry (below the sample's P1 range).
        self._setpoint_max = min(signal.maximum for m in self.db.messages
                                 if m.name.startswith('ARM_SETPOINT_') for signal in m.signals
                                 if cp.chamber_of(signal.name) is not None)
        self._psi_range = (psi.minimum, psi.maximum)
        # Vented valves hold ambient: the segment's p0 (config/segment.yaml).
        self.vent_pressure = ambient_pressure() if vent_pressure is None else vent_pressure
        self.setpoints = (self.vent_pressure,) * (2 * n_segments)
        self._commanded = list(self.setpoints)
        self._last_host = None      # never heard: vented until a host speaks
        self._heartbeat_lost = True
        self._counts = {'sent': 0, 'dropped': 0, 'corrupted': 0, 'replayed': 0, 'tx_errors': 0,
                        'heartbeat_vents': 0}
        self._last = None  # (time.monotonic(), tick, measured) of the last instant
        self._thread = LoopThread(self._loop, 'sim-arm-bus', log, 'simulated arm')

    @property
    def link(self):
        return str(self._bus.channel_info)

    def start(self):
        self._thread.start()

    # -- the device's side of the contract: what it measured, what it was told ------------------
    def read(self):
        last = self._last
        if last is None or time.monotonic() - last[0] > 20 * self.period:
            return None  # stale once the loop has stopped
        t_receive, tick, measured = last
        return ArmSample(t_receive=t_receive, index=tick, t_device=tick * self.period,
                         psi=tuple(psi for _, _, psi in measured),
                         pressures=tuple(p for p1, p2, _ in measured for p in (p1, p2)))

    def write(self, pressures):
        """Take set-points as if a host had sent them (and a heartbeat); None while latched."""
        if len(pressures) != 2 * self.n_segments:
            raise ValueError(f'expected {2 * self.n_segments} pressure set-points, '
                             f'got {len(pressures)}')
        if self.latched:
            return None
        # What a set-point frame can carry: the DBC's range; a non-finite value vents its chamber.
        self._commanded, _, _ = clamp_pressures(pressures, self.vent_pressure, self._setpoint_max)
        self._last_host = time.monotonic()
        return tuple(self._commanded)

    def vent(self):
        self.latched = True
        self.setpoints = (self.vent_pressure,) * (2 * self.n_segments)

    def release(self):
        self.latched = False

    @property
    def vented(self):
        return self.latched or self._heartbeat_lost

    def at_rest(self, tolerance):
        sample = self.read()
        return sample is not None and sample.at(self.vent_pressure, tolerance)

    def stop(self):
        self._thread.stop()

    def close(self):
        self.stop()
        self._bus.shutdown()

    def health(self):
        out = dict(self._counts)
        out.update({f'rx_{k}': v for k, v in self._checker.counters().items()})
        return out

    def _loop(self, stop):
        tick = 0
        previous = None
        for dt in PeriodicLoop(self.period, self.stats).ticks(stop):
            self._read_host()
            self._apply_heartbeat()
            # Every missed sample is taken (`device_steps`): the driver numbers the rows it
            # receives and times them by that index, so a late tick that stepped the plant by the
            # whole delay and sent one row squeezed the delay into one sample period.
            for step in device_steps(dt, self.period):
                measured = self._step(step, self.setpoints)
                self._last = (time.monotonic(), tick, measured)  # `read` makes the sample
                for frame in self._encode(tick, measured):
                    previous = self._transmit(frame, previous)
                if tick % self._status_every == 0:
                    values = {'HeartbeatLost': int(self._heartbeat_lost), 'SensorFault': 0,
                              'RxErrors': min(255, self._checker.crc_errors
                                              + self._checker.replayed)}
                    data = cp.encode_frame(self._status, values, tick // self._status_every)
                    status = can.Message(arbitration_id=self._status.frame_id,
                                         is_extended_id=False, data=data)
                    self._transmit(status, None)
                tick += 1

    def _read_host(self):
        for _ in range(64):  # bounded: a flooding host cannot stall the 1 kHz loop
            frame = self._bus.recv(timeout=0)
            if frame is None:
                return
            if frame.arbitration_id in self._own_ids:
                continue
            checked = self._checker.check(frame.arbitration_id, frame.data, time.monotonic())
            if checked is None:
                continue
            message, values = checked
            if message.frame_id == self._heartbeat_id:
                self._last_host = time.monotonic()
            elif message.frame_id in self._setpoint_ids:
                for name, value in values.items():
                    chamber = cp.chamber_of(name)
                    if chamber is not None and chamber < len(self._commanded):
                        self._commanded[chamber] = value

    def _apply_heartbeat(self):
        lost = self._last_host is None or \
            time.monotonic() - self._last_host > cp.ARM_HEARTBEAT_TIMEOUT
        if lost and not self._heartbeat_lost:
            self._counts['heartbeat_vents'] += 1
        self._heartbeat_lost = lost
        self.setpoints = ((self.vent_pressure,) * (2 * self.n_segments) if lost or self.latched
                          else tuple(self._commanded))

    def _encode(self, counter, measured):
        lo, hi = self._p_range
        psi_lo, psi_hi = self._psi_range
        frames = []
        for i, (message, (p1, p2, psi)) in enumerate(zip(self._samples, measured)):
            if i == 0:
                p1 = self.faults.sensor(p1)
            # A real sensor saturates at its range; the DBC would refuse an out-of-range value.
            values = {'P1': min(max(p1, lo), hi), 'P2': min(max(p2, lo), hi),
                      'Psi': min(max(psi, psi_lo), psi_hi)}
            frames.append(can.Message(arbitration_id=message.frame_id, is_extended_id=False,
                                      data=cp.encode_frame(message, values, counter)))
        return frames

    def _transmit(self, frame, previous):
        """Send `frame` through the fault switches; returns what a replay would resend."""
        if self.faults.drop():
            self._counts['dropped'] += 1
            return previous
        data, corrupted = self.faults.corrupt(bytes(frame.data))
        out = frame
        if corrupted:
            self._counts['corrupted'] += 1
            out = can.Message(arbitration_id=frame.arbitration_id, is_extended_id=False, data=data)
        self._send(out)
        if previous is not None and self.faults.replay():
            self._counts['replayed'] += 1
            self._send(previous)
        return out

    def _send(self, frame):
        try:
            self._bus.send(frame, timeout=0.01)
            self._counts['sent'] += 1
        except can.CanError:
            self._counts['tx_errors'] += 1
