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
Simulated actuator board: the firmware side of the serial protocol on a pseudo-terminal.

The emulator holds the pty master; the driver opens the slave through a symlink the emulator
controls (``.port``), just as the real board appears under ``/dev/serial/by-id/...``: udev removes
that link when the USB device vanishes and creates it again, pointing at a new tty, when it comes
back. ``unplug()`` and ``replug()`` do exactly that with a fresh pty, so the driver's reconnect
path is the real one.

The link points at the board's own open slave, ``/proc/<pid>/fd/<n>``, not at ``/dev/pts/<n>``:
a board that dies (SIGKILL, a crash) leaves a link to nothing, never one to the tty the kernel
hands the next program under that number. A board started on a link of that form whose process
is gone takes it over (its own stale link); every other thing at the port is refused. The board
names itself on the wire (IDENTITY, `serial_protocol`) with a serial number that is the same for
the same port (``serial``, default from the port's path), so a restarted board is the board the
driver had, and anything else is not.

API
---
- ``SimActuatorBoard(step, config=None, link_path=None, faults=None, period=1e-3, record=False,
  serial=None)``
  ``step(dt: float, duty: float) -> state`` advances the plant by dt seconds with the motor duty
  the board applies and returns any object with attributes ``x_c`` (m), ``p`` (Pa abs), ``x_s``
  (m), ``f`` (N) -- e.g. ``ActuatorState``. `config` (ActuatorBoardConfig, default from
  hardware.yaml) gives the encoder resolution and the end-stop switch positions.
- ``.start()`` starts the 1 kHz loop, ``.stop()`` stops it (the board goes silent), ``.close()``;
  ``.port`` (path for the driver); ``.unplug()``, ``.replug()``.
- A `device.Device` seen from the board's side: ``.read()`` the last sample it sent (an
  `ActuatorSample`), ``.write(duty)`` a motor duty as if from a host, ``.vent()`` (motor stopped,
  latched), ``.release()``, ``.vented``, ``.at_rest(tolerance)``.
- ``.faults`` (`Faults`, settable at run time); ``.duty`` (duty applied now); ``.health()``;
  ``.sent`` (with record=True: {sequence index: Telemetry} of every frame put on the wire,
  uncorrupted); ``.stats`` (LoopStats).
- ``check_free(port)`` (ParameterError unless nothing, or a dead board's link, is there),
  ``link_pty(port) -> (master, slave, target)``, ``owns_link(port, target)``: the pty and link
  handling, also for the bench's floor of this node (bench/graph_floor.py).

Board behaviour (docs/protocols.md): 1 kHz telemetry; a motor command holds until the next one; the
motor stops at an end-stop switch and after `BOARD_HEARTBEAT_TIMEOUT` without a command or
heartbeat.
"""
import collections
import dataclasses
import errno
import hashlib
import logging
import os
import re
import shutil
import tempfile
import threading
import time
import tty
import uuid

from bellows_ros.config.hardware import actuator_board_config
from bellows_ros.errors import ParameterError
from bellows_ros.hardware import serial_protocol as sp
from bellows_ros.hardware.actuator_board import ActuatorSample
from bellows_ros.hardware.device import Device
from bellows_ros.hardware.faults import Faults
from bellows_ros.hardware.loop_timing import device_steps, LoopStats, LoopThread, PeriodicLoop
from bellows_ros.hardware.safety import into_end_stop

log = logging.getLogger(__name__)

# A USB link does not drop what a busy host is slow to read, and a pty takes only ~640 telemetry
# frames (20 kB): the board queues what the pty will not take yet (`_transmit`), up to TX_QUEUE_S
# of samples, the oldest going first (counted in tx_overflow). A host that has not spoken for that
# long (no driver has the port open) gets no backlog beyond what the pty holds, so a driver that
# opens the port late does not read seconds of old data.
TX_QUEUE_S = 5.0


@dataclasses.dataclass(frozen=True)
class ActuatorState:
    """
    What the plant callback returns.

    Chamber compression x_c (m), pressure p (Pa abs), spring compression x_s (m), spring force f
    (N).
    """

    x_c: float
    p: float
    x_s: float
    f: float


# The link a simulated board makes: its own open pty slave, through /proc.
_OWN_LINK = re.compile(r'/proc/(\d+)/fd/(\d+)')


def _stale_board_link(port):
    """Tell whether `port` is the link of a simulated board whose process is gone."""
    try:
        target = os.readlink(port)
    except OSError:
        return False
    match = _OWN_LINK.fullmatch(target)
    if match is None or int(match.group(1)) == os.getpid():
        return False
    try:
        os.kill(int(match.group(1)), 0)
    except ProcessLookupError:
        return True
    except PermissionError:  # a process of another user holds that pid: not our dead board
        return False
    return False


def port_serial(port):
    """Return the serial number of the simulated board on `port`: one path, one board."""
    digest = hashlib.sha256(os.path.abspath(port).encode()).digest()
    return int.from_bytes(digest[:8], 'little')


def check_free(port):
    """
    Raise ParameterError unless `port` names nothing yet, in an existing directory.

    The one exception: the link a simulated board left when its process died (`_stale_board_link`)
    is free to take over.
    """
    if os.path.islink(port) and _stale_board_link(port):
        return
    if os.path.lexists(port):
        kind = ('a directory' if os.path.isdir(port) else 'a link' if os.path.islink(port)
                else 'a device node' if not os.path.isfile(port) else 'a file')
        raise ParameterError(f'port {port}: {kind} exists there; the simulated board creates its '
                             'link only where nothing exists (choose a free path)')
    if not os.path.isdir(os.path.dirname(os.path.abspath(port))):
        raise ParameterError(f'port {port}: no such directory')


def link_pty(port):
    """
    Open a raw, non-blocking pty and point the link `port` at its slave in one atomic rename.

    Returns (master fd, slave fd, the link's target). The caller has made sure that `port` is free
    (`check_free`) or the link it made itself (`owns_link`).
    """
    master, slave = os.openpty()
    tty.setraw(slave)  # no echo or line editing: the driver sees the bytes the board sends
    os.set_blocking(master, False)
    # The slave as this process holds it: gone with the process, never another program's tty.
    target = f'/proc/{os.getpid()}/fd/{slave}'
    # A fresh name beside the port (symlink() never replaces), then one atomic rename.
    tmp_link = f'{port}.{os.getpid()}.{uuid.uuid4().hex[:8]}.new'
    os.symlink(target, tmp_link)
    os.replace(tmp_link, port)
    return master, slave, target


def owns_link(port, target):
    """Tell whether `port` is still the link to `target` that `link_pty` made."""
    try:
        return os.readlink(port) == target
    except OSError:  # gone, or not a link any more
        return False


class SimActuatorBoard(Device):
    name = 'actuator'

    def __init__(self, step, config=None, link_path=None, faults=None, period=1e-3, record=False,
                 serial=None):
        if config is None:
            config = actuator_board_config()
        self._step = step
        self.config = config
        self.faults = faults if faults is not None else Faults()
        self.period = period
        self.record = record
        self.sent = {}
        self.stats = LoopStats()
        self._tmpdir = None
        if link_path is None:
            self._tmpdir = tempfile.mkdtemp(prefix='sim_actuator_')
            link_path = os.path.join(self._tmpdir, 'actuator_board')
        self.port = str(link_path)
        check_free(self.port)
        self.serial = port_serial(self.port) if serial is None else int(serial)
        self._identity_due = 0.0  # time.monotonic() when the next IDENTITY goes out
        self._tty = None  # where the link this board made points; None while it has none
        self._fd_lock = threading.Lock()
        self._master = self._slave = None
        self._tx = collections.deque()  # frames the pty has not taken yet; guarded by _fd_lock
        self._tx_partial = False  # the head of _tx is half written
        self._host_seen = None  # time.monotonic() of the last message from a host; None: none
        self._tx_capacity = max(1, int(round(TX_QUEUE_S / period)))
        self._decoder = sp.FrameDecoder()
        self._thread = LoopThread(self._loop, 'sim-actuator-board', log,
                                  'simulated actuator board')
        self.duty = 0.0
        self._last_host = time.monotonic()
        self._last = None  # (time.monotonic(), index, Telemetry, plant state) of the last sample
        self._counts = {'sent': 0, 'dropped': 0, 'corrupted': 0, 'tx_overflow': 0,
                        'motor_commands': 0, 'heartbeats': 0, 'heartbeat_stops': 0}
        self.replug()

    # -- the pty and its symlink ------------------------------------------------------------
    # The board touches only the link it made: it creates the link where nothing exists (the
    # constructor refuses a path that is taken), repoints it only while it is still its own, and
    # removes it only then. A port named by mistake (a real device node, a file) is never deleted.
    def _owns_link(self):
        return self._tty is not None and owns_link(self.port, self._tty)

    def replug(self):
        """Open a fresh pty and point the symlink at it atomically."""
        if self._tty is not None and os.path.lexists(self.port) and not self._owns_link():
            raise ParameterError(f'{self.port}: replaced by something this simulated board did '
                                 'not make; left as it is')
        if self._tty is None:
            check_free(self.port)
        master, slave, name = link_pty(self.port)
        self._tty = name
        with self._fd_lock:
            self._master, self._slave = master, slave

    def unplug(self):
        """Make the device vanish: close the pty (the driver's reads fail), remove the symlink."""
        with self._fd_lock:
            master, slave, self._master, self._slave = self._master, self._slave, None, None
            self._tx.clear()  # a board that loses power loses what it had not sent
            self._tx_partial, self._host_seen = False, None
        if self._owns_link():
            os.unlink(self.port)
        self._tty = None
        for fd in (master, slave):
            if fd is not None:
                os.close(fd)

    # -- run ----------------------------------------------------------------------------------
    @property
    def link(self):
        return self.port

    def start(self):
        self._last_host = time.monotonic()
        self._thread.start()

    def stop(self):
        self._thread.stop()

    def close(self):
        self.stop()
        self.unplug()
        if self._tmpdir is not None:
            shutil.rmtree(self._tmpdir, ignore_errors=True)

    # -- the device's side of the contract: what it measured, what it was told ------------------
    def read(self):
        last = self._last
        if last is None or time.monotonic() - last[0] > 20 * self.period:
            return None  # stale once the loop has stopped
        t_receive, index, telemetry, state = last
        return ActuatorSample(
            t_receive=t_receive, t_device=telemetry.t_us * 1e-6, index=index,
            encoder_counts=telemetry.encoder_counts,
            x_c=telemetry.encoder_counts * self.config.metres_per_count, x_s=state.x_s,
            p=float(telemetry.pressure_pa), f=state.f, status=telemetry.status)

    def write(self, duty):
        """Take a motor duty as if a host had sent it; None while latched."""
        if self.latched:
            return None
        self._last_host = time.monotonic()
        # What a motor frame can carry: -1..1 in Q15 (a non-finite duty is 0: duty_to_q15).
        self.duty = sp.q15_to_duty(sp.duty_to_q15(duty))
        return self.duty

    def vent(self):
        self.latched = True
        self.duty = 0.0

    def release(self):
        self.latched = False

    @property
    def vented(self):
        return self.latched or time.monotonic() - self._last_host > sp.BOARD_HEARTBEAT_TIMEOUT

    def at_rest(self, tolerance):
        return self.duty == 0.0  # the gas is sealed: a still lead screw is the safe state

    def health(self):
        out = dict(self._counts)
        out.update(rx_crc_errors=self._decoder.crc_errors,
                   rx_framing_errors=self._decoder.framing_errors)
        return out

    def _loop(self, stop):
        t_us = 0
        seq = 0
        state = None
        for dt in PeriodicLoop(self.period, self.stats).ticks(stop):
            self._read_host()
            safety = self._apply_safety(state)
            # A late tick catches up sample by sample (`device_steps`): a late tick that stepped
            # the plant by the whole delay and sent one sample left 10-140 ms holes in records on
            # a busy machine, which the doctor refuses.
            for step in device_steps(dt, self.period):
                state = self._step(step, self.duty)
                t_us = (t_us + int(round(step * 1e6))) & 0xFFFFFFFF
                status = (safety | self._end_stops(state.x_c)
                          | (sp.MOTOR_ON if self.duty else 0))
                p = self.faults.sensor(state.p)
                telemetry = sp.Telemetry(
                    seq=seq & 0xFFFF, t_us=t_us,
                    encoder_counts=int(round(state.x_c / self.config.metres_per_count)),
                    pressure_pa=min(max(int(round(p)), 0), 0xFFFFFFFF),
                    spring_um=int(round(state.x_s * 1e6)), force_mn=int(round(state.f * 1e3)),
                    status=status)
                self._transmit(seq, telemetry)
                self._last = (time.monotonic(), seq, telemetry, state)  # `read` makes the sample
                seq += 1
            if time.monotonic() >= self._identity_due:
                self._identify((seq - 1) & 0xFFFF)

    def _identify(self, seq):
        """Send IDENTITY (the board's serial number) now; the next one within IDENTITY_PERIOD."""
        self._identity_due = time.monotonic() + sp.IDENTITY_PERIOD
        with self._fd_lock:
            if self._master is None:
                return
            self._tx.append(sp.encode(sp.Identity(seq, self.serial)))
            self._flush()

    def _end_stops(self, x_c):
        return ((sp.END_STOP_LOW if x_c <= self.config.x_c_min else 0)
                | (sp.END_STOP_HIGH if x_c >= self.config.x_c_max else 0))

    def _apply_safety(self, state):
        """Apply the firmware's limits before the plant sees the duty; return the status bits."""
        status = 0
        if self.latched:
            self.duty = 0.0
        if time.monotonic() - self._last_host > sp.BOARD_HEARTBEAT_TIMEOUT:
            status |= sp.HEARTBEAT_LOST
            if self.duty != 0.0:
                self._counts['heartbeat_stops'] += 1
                self.duty = 0.0
        if state is not None:
            stops = self._end_stops(state.x_c)
            if into_end_stop(self.duty, stops & sp.END_STOP_LOW, stops & sp.END_STOP_HIGH):
                self.duty = 0.0
        return status

    def _read_host(self):
        with self._fd_lock:
            if self._master is None:
                return
            try:
                data = os.read(self._master, 4096)
            except OSError as error:  # EAGAIN: nothing; EIO: no driver has the slave open
                if error.errno not in (errno.EAGAIN, errno.EIO):
                    raise
                return
        for message in self._decoder.feed(data):
            if self._host_seen is None or time.monotonic() - self._host_seen > sp.IDENTITY_PERIOD:
                self._identity_due = 0.0  # a host (again): it hears who this is at once
            self._last_host = self._host_seen = time.monotonic()
            if isinstance(message, sp.MotorCommand):
                self._counts['motor_commands'] += 1
                self.duty = sp.q15_to_duty(message.duty_q15)
            else:
                self._counts['heartbeats'] += 1

    def _transmit(self, seq, telemetry):
        if self.faults.drop():
            self._counts['dropped'] += 1
            return
        frame, corrupted = self.faults.corrupt(sp.encode(telemetry))
        self._counts['corrupted'] += corrupted
        if self.record and not corrupted:
            self.sent[seq] = telemetry
        with self._fd_lock:
            if self._master is None:
                return
            self._tx.append(frame)
            listened = (self._host_seen is not None
                        and time.monotonic() - self._host_seen <= TX_QUEUE_S)
            while len(self._tx) > (self._tx_capacity if listened else 1):
                del self._tx[1 if self._tx_partial else 0]  # the oldest whole frame goes
                self._counts['tx_overflow'] += 1
            self._flush()

    def _flush(self):
        """Write the queued frames the pty takes now, in order; keep the rest (under _fd_lock)."""
        while self._tx:
            try:
                written = os.write(self._master, self._tx[0])
            except OSError as error:  # the driver is not reading: the pty buffer is full
                if error.errno not in (errno.EAGAIN, errno.EIO):
                    raise
                return
            self._tx_partial = written < len(self._tx[0])
            if self._tx_partial:
                self._tx[0] = self._tx[0][written:]
                return
            self._tx.popleft()
            self._counts['sent'] += 1
