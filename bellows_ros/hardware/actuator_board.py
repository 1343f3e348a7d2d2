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
Driver for the actuator board (DC motor + encoder, system pressure, spring position and force).

Talks the serial protocol of `serial_protocol` over pyserial. One reader thread parses telemetry
and reconnects when the port vanishes; one heartbeat thread sends heartbeats and runs the command
watchdog; one command thread sends the newest motor duty (a write to the port can block for its
write timeout: `write` never does).

API
---
- ``config``: ``bellows_ros.config.hardware.actuator_board_config(params_path=None) ->
  ActuatorBoardConfig`` (config/hardware.yaml, ``hardware.actuator_board.*``).
- ``ActuatorBoard(config, on_sample=None)``, a `device.Device`; ``.start()`` starts the threads;
  ``on_sample(sample: ActuatorSample)`` is called from the reader thread for every good telemetry
  frame (keep it short).
- ``.read() -> ActuatorSample | None``: newest good sample, None when there is none or it is
  stale.
- ``.write(duty: float) -> float | None``: duty -1..1 (positive compresses the air chamber);
  returns the duty that goes out after the safety limits (None: refused, the board is latched).
  Only the newest duty not yet sent is sent.
- ``.vent()`` (stops the motor and latches: the board's safe state), ``.release()``, ``.vented``,
  ``.at_rest(tolerance)``; ``.connected``, ``.stale`` (bool); ``.health() -> dict[str, int]``;
  ``.close()``.

Identity: after it opens the port the driver sends nothing and delivers nothing until the board
has named itself (IDENTITY, `serial_protocol`); the first board it hears is the one it keeps
(``.serial``), and on every reconnect it takes only that serial number again. A port that gives no
IDENTITY within IDENTITY_TIMEOUT (a tty the kernel gave to another program after the board died,
a wrong device) or another serial number is closed and counted (`identity_refusals`), and the
driver keeps looking for its board.

Safety: |duty| <= duty_max; no duty into an end stop (board status flags or the x_c soft limits);
duty 0 while the data is stale; duty 0 when no command arrives for `command_timeout` (watchdog);
the board itself stops after `BOARD_HEARTBEAT_TIMEOUT` without heartbeats. A sample that failed any
check is never delivered.
"""
import dataclasses
import logging
import threading
import time

import serial

from bellows_ros.hardware import serial_protocol as sp
from bellows_ros.hardware.device import Device
from bellows_ros.hardware.safety import into_end_stop, limit_duty, Watchdog
from bellows_ros.hardware.sample_delivery import deliver, fresh

log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class ActuatorSample:
    """
    One good telemetry frame in SI units (names: `actuator` columns of docs/interfaces.md).

    t_receive: time.monotonic() at reception, s; t_device: board clock (unwrapped), s; index:
    sequence number, unwrapped (starts at the first frame's seq when the port (re)opens); x_c:
    air-chamber compression from the encoder, m; x_s: spring compression, m; p: system pressure, Pa
    abs; f: spring force, N; status: `serial_protocol` status bits.
    """

    t_receive: float
    t_device: float
    index: int
    encoder_counts: int
    x_c: float
    x_s: float
    p: float
    f: float
    status: int


class ActuatorBoard(Device):
    name = 'actuator'

    def __init__(self, config, on_sample=None):
        self.config = config
        self._on_sample = on_sample
        self._serial = None
        self._io_lock = threading.Lock()   # guards the port object and writes
        self._stop = threading.Event()
        self._latest = None
        self._decoder = sp.FrameDecoder()
        self._tx_seq = 0
        self._last_seq = None
        self._index = 0
        self._t_offset_us = 0
        self._last_t_us = None
        self._duty = 0.0
        self._watchdog = Watchdog(config.command_timeout, time.monotonic())
        self._watchdog_tripped = True       # nothing commanded yet
        self.serial = None          # the board's serial number, from its first IDENTITY
        self._identified = False    # the open port has named itself as that board
        self._opened_at = None      # time.monotonic() the port was opened
        self._refusal_reported = None   # why a port was last refused, as logged in this outage
        self.latched = False    # stopped on request (vent()): duties refused until release()
        self._pending = None    # the newest duty (limited) the command thread has not sent yet
        self._pending_ready = threading.Condition()
        self._opened = False
        self._counts = dict.fromkeys(
            ['samples', 'callback_errors', 'dropped', 'duplicates', 'sequence_resets',
             'reconnects', 'disconnects', 'tx_errors', 'duty_clamps', 'duty_invalid',
             'end_stop_stops', 'stale_stops', 'watchdog_stops', 'refused_while_stopped',
             'identity_refusals', 'unidentified_frames'], 0)
        self._reader = threading.Thread(target=self._read_loop, name='actuator-reader',
                                        daemon=True)
        self._heart = threading.Thread(target=self._heartbeat_loop, name='actuator-heartbeat',
                                       daemon=True)
        self._sender = threading.Thread(target=self._command_loop, name='actuator-commands',
                                        daemon=True)

    @property
    def link(self):
        return self.config.port

    def start(self):
        if not self._opened:
            self._opened = True
            for thread in (self._reader, self._heart, self._sender):
                thread.start()

    # -- state for the next layer ---------------------------------------------------------------
    @property
    def connected(self):
        """The port is open and the board on it has named itself as this driver's board."""
        return self._serial is not None and self._identified

    def read(self):
        return fresh(self._latest, self.config.stale_timeout)

    @property
    def vented(self):
        """The motor is held stopped: latched, or no duty since the watchdog (or ever)."""
        return self.latched or self._watchdog_tripped

    def at_rest(self, tolerance):
        return self._duty == 0.0  # the gas is sealed: a still lead screw is the safe state

    def health(self):
        d = self._decoder
        out = dict(self._counts)
        out.update(crc_errors=d.crc_errors, framing_errors=d.framing_errors,
                   version_errors=d.version_errors, unknown_types=d.unknown_types)
        return out

    # -- commands -------------------------------------------------------------------------------
    def vent(self):
        """
        Stop the motor now and refuse duties until `release()` (the stop that latches).

        The actuator's gas is sealed: there is no valve to vent, and the safe state is a still
        lead screw (the pressure stays where it is). Should the stop frame not get through (a
        stuck port), the board stops by itself once heartbeats and commands stop reaching it.
        """
        self.latched = True
        with self._pending_ready:
            self._pending = None
        self._command(0.0)

    def release(self):
        """Accept motor duties again."""
        self.latched = False

    def write(self, duty):
        """Limit a motor duty and hand it to the command thread; kicks the command watchdog."""
        if self.latched:
            self._counts['refused_while_stopped'] += 1
            return None
        self._watchdog.kick(time.monotonic())
        self._watchdog_tripped = False
        limited = self._limit(duty)
        with self._pending_ready:
            self._pending = limited
            self._pending_ready.notify()
        return limited

    def _command(self, duty):
        """Limit and send a duty now, from the calling thread: the stops."""
        limited = self._limit(duty)
        q15 = sp.duty_to_q15(limited)
        self._send(lambda seq: sp.MotorCommand(seq, q15))
        return limited

    def _limit(self, duty):
        """Return `duty` after the safety limits, counting what they did; it is now the duty."""
        sample = self.read()
        if sample is None:
            limited, reason = 0.0, ('stale' if duty != 0 else None)
        else:
            limited, reason = limit_duty(duty, self.config.duty_max, *self._at_stops(sample))
        if reason is not None:
            key = {'stale': 'stale_stops', 'invalid': 'duty_invalid', 'clamped': 'duty_clamps',
                   'end_stop': 'end_stop_stops'}[reason]
            self._counts[key] += 1
        self._duty = limited
        return limited

    def _at_stops(self, sample):
        """(at the low stop, at the high stop): the board's switches or the x_c soft limits."""
        return (bool(sample.status & sp.END_STOP_LOW) or sample.x_c <= self.config.x_c_min,
                bool(sample.status & sp.END_STOP_HIGH) or sample.x_c >= self.config.x_c_max)

    def _send(self, make, unless_latched=False):
        """Send `make(seq)`; the sequence number is taken under the lock the threads share."""
        with self._io_lock:
            if self._serial is None or not self._identified:  # not a byte to an unknown device
                return
            if unless_latched and self.latched:  # a vent came after this duty was taken
                self._counts['refused_while_stopped'] += 1
                return
            self._tx_seq = (self._tx_seq + 1) & 0xFFFF
            try:
                self._serial.write(sp.encode(make(self._tx_seq)))
            except (serial.SerialException, OSError):
                self._counts['tx_errors'] += 1  # the reader notices a vanished port and reconnects

    # -- threads --------------------------------------------------------------------------------
    def _command_loop(self):
        while True:
            with self._pending_ready:
                while self._pending is None and not self._stop.is_set():
                    self._pending_ready.wait()
                if self._stop.is_set():
                    return
                duty, self._pending = self._pending, None
            q15 = sp.duty_to_q15(duty)
            self._send(lambda seq: sp.MotorCommand(seq, q15), unless_latched=True)

    def _heartbeat_loop(self):
        while not self._stop.wait(self.config.heartbeat_period):
            self._send(sp.Heartbeat)
            if not self._watchdog_tripped and self._watchdog.expired(time.monotonic()):
                self._watchdog_tripped = True
                if self._duty != 0.0:
                    self._counts['watchdog_stops'] += 1
                    log.warning('actuator board: no motor command for %.3f s, motor stopped',
                                self.config.command_timeout)
                    self._command(0.0)

    def _open(self):
        try:
            port = serial.Serial(self.config.port, self.config.baud, timeout=0.02,
                                 write_timeout=0.05)
        except (serial.SerialException, OSError):
            return False
        with self._io_lock:
            self._serial = port
            self._identified = False
        self._opened_at = time.monotonic()
        self._last_seq = None  # a re-plugged board restarts its sequence and clock
        self._last_t_us = None
        return True

    def _refuse_port(self, why):
        """Close a port whose device is not this driver's board; count it, say it once."""
        with self._io_lock:
            port, self._serial = self._serial, None
            self._identified = False
        try:
            port.close()
        except Exception:  # a port that vanished may not close cleanly; it is closed either way
            pass
        self._counts['identity_refusals'] += 1
        if why != self._refusal_reported:  # each reason once: a slow IDENTITY, then the serial
            log.error('actuator board: %s %s; not using it (retrying every %.2f s)',
                      self.config.port, why, self.config.reconnect_interval)
            self._refusal_reported = why
        self._stop.wait(self.config.reconnect_interval)

    def _identify(self, identity):
        """Take IDENTITY: True if the open port's board is this driver's board (learnt first)."""
        if self.serial is None:
            self.serial = identity.serial
        if identity.serial != self.serial:
            self._refuse_port(f'is another board (serial {identity.serial:016x}, this '
                              f'driver has board {self.serial:016x})')
            return False
        with self._io_lock:
            self._identified = self._serial is not None
        return True

    def _drop_port(self, error):
        with self._io_lock:
            port, self._serial = self._serial, None
            self._identified = False
        try:
            port.close()
        except Exception:  # closing a vanished port may fail; it is gone either way
            pass
        self._counts['disconnects'] += 1
        log.warning('actuator board: lost %s (%s); reconnecting', self.config.port, error)

    def _read_loop(self):
        ever_opened, outage_reported = False, False
        while not self._stop.is_set():
            if self._serial is None:
                if not self._open():
                    if not outage_reported:
                        log.warning('actuator board: cannot open %s; retrying every %.2f s',
                                    self.config.port, self.config.reconnect_interval)
                        outage_reported = True
                    self._stop.wait(self.config.reconnect_interval)
                    continue
            if not self._identified and \
                    time.monotonic() - self._opened_at > sp.IDENTITY_TIMEOUT:
                self._refuse_port(f'gives no IDENTITY within {sp.IDENTITY_TIMEOUT:g} s: not a '
                                  'bellows actuator board (a tty of another program, a wrong '
                                  'device)')
                continue
            try:
                data = self._serial.read(max(1, self._serial.in_waiting))
            except (serial.SerialException, OSError, TypeError) as error:
                # TypeError: pyserial reading a port that close() shut under it
                if self._stop.is_set():
                    break
                self._drop_port(error)
                continue
            for message in self._decoder.feed(data):
                if isinstance(message, sp.Identity) and not self._identified:
                    if not self._identify(message):
                        break
                    if ever_opened:
                        self._counts['reconnects'] += 1
                        log.warning('actuator board: reconnected to %s (board %016x)',
                                    self.config.port, self.serial)
                    else:
                        log.info('actuator board: opened %s (board %016x)', self.config.port,
                                 self.serial)
                    ever_opened, outage_reported, self._refusal_reported = True, False, None
                elif isinstance(message, sp.Telemetry):
                    if self._identified:
                        self._accept(message)
                    else:  # from a device that has not named itself: never a sample
                        self._counts['unidentified_frames'] += 1

    def _accept(self, t):
        now = time.monotonic()
        if self._last_seq is not None:
            delta = (t.seq - self._last_seq) & 0xFFFF
            if delta == 0:
                self._counts['duplicates'] += 1
                return
            if delta < 0x8000:
                self._counts['dropped'] += delta - 1
                self._index += delta
            else:  # the board restarted
                self._counts['sequence_resets'] += 1
                self._index += 1
        else:  # first frame since the port (re)opened
            self._index = t.seq
        self._last_seq = t.seq
        if self._last_t_us is not None and t.t_us < self._last_t_us:
            self._t_offset_us += 1 << 32
        self._last_t_us = t.t_us
        m = self.config.metres_per_count
        sample = ActuatorSample(
            t_receive=now, t_device=(t.t_us + self._t_offset_us) * 1e-6, index=self._index,
            encoder_counts=t.encoder_counts, x_c=t.encoder_counts * m, x_s=t.spring_um * 1e-6,
            p=float(t.pressure_pa), f=t.force_mn * 1e-3, status=t.status)
        self._latest = sample
        self._counts['samples'] += 1
        if self._duty != 0.0:  # re-check the end stops against every new position
            if into_end_stop(self._duty, *self._at_stops(sample)):
                self._counts['end_stop_stops'] += 1
                self._duty = 0.0
                self._send(lambda seq: sp.MotorCommand(seq, 0))
        deliver(self._on_sample, sample, self._counts, log, 'actuator board')

    def close(self):
        """Stop the motor, stop the threads, close the port."""
        if self._stop.is_set():
            return
        with self._pending_ready:  # first the command thread: no duty goes out after the stop
            self._stop.set()
            self._pending = None
            self._pending_ready.notify()
        if self._opened:
            self._sender.join(timeout=1.0)
        self._duty = 0.0
        self._send(lambda seq: sp.MotorCommand(seq, 0))
        if self._opened:
            self._heart.join(timeout=1.0)
            self._reader.join(timeout=1.0)
        with self._io_lock:
            port, self._serial = self._serial, None
        if port is not None:
            port.close()
