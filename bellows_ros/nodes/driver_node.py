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
driver_node: the arm on CAN and/or the actuator on serial, wired to the topic contract.

One message per device sample, each group on a topic of its own (docs/interfaces.md): the arm on
`/joint_states` (segment angles and rates, chain pressures), the actuator on
`/actuator/joint_states` (compressions, the load cell's spring force, the chamber pressure), so
that no 1 kHz node decodes the other group's samples. The devices' 1 kHz sampling is the clock:
messages go out from the drivers' reader threads as each sample arrives, stamped with the time the
device took it: the device's clock mapped onto the node clock (`sample_delivery.DeviceClock`), so a
burst read after a stall keeps its 1 ms spacing. For the arm the arrival that anchors that mapping
is the bus's receive timestamp (`sample_delivery.arrival_ns`), so samples a starved reader takes
late from the socket carry their true age; there is no ROS timer at 1 kHz.
Commands (`/bellows/pressure_command`, `/actuator/motor_command`) pass through the hardware layer's
safety limits (clamping, end stops, watchdogs).

A managed (lifecycle) node, as ros2_control's hardware is (rclpy.lifecycle, docs/protocols.md
"Safety states"): `configure` opens the devices and waits for their first samples (inactive: the
samples are published, the chambers are vented, commands are refused and counted); `activate`
accepts commands; `deactivate` vents and refuses them; `cleanup` closes the devices; `shutdown`
(and the end of the process) vents and waits until every chamber reads ambient, or says that it
did not within `shutdown_timeout`. `~/vent` and `/bellows/estop` vent and latch in any state.

Parameters (config/nodes_*.yaml, section `driver_node`):
  arm.enabled, actuator.enabled (bool): which device groups to run.
  hardware_params (str): a hardware YAML laid over config/hardware.yaml ('' = defaults).
  actuator.port (str): serial port ('' = hardware.actuator_board.port).
  arm.interface, arm.channel (str): python-can bus ('' = hardware.arm_bus.*).
  arm.n_segments (int): segments on the bus (0 = hardware.arm_bus.n_segments).
  startup_timeout (s): a device whose port is still absent, or that sent no sample, by then
      fails `configure` (with autostart: exit status 2).
  autostart (bool): configure and activate at start, as launch_sim.sh asks; false = wait in
      `unconfigured` for `ros2 lifecycle set` (the launch files send the transitions).
  shutdown_timeout (s), ambient_tolerance (Pa): shutdown waits up to shutdown_timeout for every
      chamber to read within ambient_tolerance of ambient (the segment's p0).
  wait_for_subscribers (s): before opening the devices, wait up to this long for the sample
      topic of every enabled group (`/joint_states` for the arm, `/actuator/joint_states` for
      the actuator) to have a subscriber (like `ros2 topic pub --wait-matching-subscriptions`),
      so that a consumer started first sees every sample; 0 = no wait (the default: a robot's
      driver publishes whoever listens).
  realtime_priority (int): SCHED_FIFO priority for the node's threads, 1-99; 0 = normal
      scheduling (runtime/realtime.py).
  cpu_latency_limit (s): CPU wake-up latency held while the node runs, 0 = idle CPUs poll;
      negative = off (runtime/realtime.py).
"""
import dataclasses
import math
import os
import stat
import threading
import time

from rclpy.duration import Duration
from rclpy.lifecycle import TransitionCallbackReturn

from bellows_ros import interfaces
from bellows_ros.config.hardware import actuator_board_config, arm_bus_config
from bellows_ros.errors import BellowsError
from bellows_ros.hardware import actuator_board, arm_bus
from bellows_ros.hardware.can_protocol import dbc_segments
from bellows_ros.hardware.loop_timing import LoopStats
from bellows_ros.hardware.sample_delivery import arrival_ns, DeviceClock, on_host_clock
from bellows_ros.models.derivatives import rate
from bellows_ros.nodes import diagnostics
from bellows_ros.runtime import LifecycleNode, realtime, run
from bellows_ros.runtime.joint_state_cdr import JointStateWriter
from bellows_ros.runtime.parameters import Spec

_DISCOVERY_SETTLE = 0.5  # s, see DriverNode._wait_for_subscribers
ACTUATOR_NAMES = interfaces.actuator_sample_names()
ACTUATOR_WRITER = JointStateWriter(ACTUATOR_NAMES, velocity=False)  # no rates (interfaces.py)


class SampleClock:
    """Timing of a device's sample stream, for /diagnostics: the samples are the loop ticks."""

    def __init__(self, period):
        self.period = period
        self.stats = LoopStats()
        # The sample rate against the device's own (diagnostic_updater's check and keys).
        self.frequency = diagnostics.FrequencyStatus(1.0 / period, 1.0 / period, tolerance=0.1,
                                                     window_size=5, name='sample rate')
        self._last_time = None
        self._last_index = None

    def tick(self, index, arrival, compute):
        self.frequency.tick()
        if self._last_time is not None:
            gap = index - self._last_index
            if gap > 1:
                self.stats.add_misses(gap - 1)
            interval = arrival - self._last_time
            self.stats.record(interval, max(0.0, interval - self.period * max(gap, 1)), compute)
        self._last_time, self._last_index = arrival, index


class NewestWriter:
    """
    Call `send(value)` from a thread of its own with the newest value `put`, never blocking `put`.

    A value not yet sent when a newer one arrives is replaced (a motor duty: only the latest
    counts).
    """

    def __init__(self, send, name):
        self._send = send
        self._value = None
        self._stop = False
        self._ready = threading.Condition()
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def put(self, value):
        with self._ready:
            self._value = value
            self._ready.notify()

    def close(self):
        """Stop the thread (values not yet sent are dropped); waits up to 1 s for a send."""
        with self._ready:
            self._stop = True
            self._ready.notify()
        self._thread.join(timeout=1.0)

    def _run(self):
        while True:
            with self._ready:
                while self._value is None and not self._stop:
                    self._ready.wait()
                if self._stop:
                    return
                value, self._value = self._value, None
            self._send(value)


def _port_problem(port):
    """Say what is wrong with a serial port: it must be a character device, or absent."""
    if port and os.path.exists(port) and not stat.S_ISCHR(os.stat(port).st_mode):
        return 'not a character device (a serial port is one, or absent)'
    return ''


# The arm's clock (`DeviceClock`), by whether the bus times the frames' arrivals on the system
# clock (`sample_delivery.on_host_clock`). An outage longer than the 8-bit frame counter can count
# leaves the arm's time base behind by multiples of 256 ms; without a new base every later sample
# would look too old to act on, and the arm would stay vented.
# - Timed (kernel timestamps: no reader delay, jitter far under 50 ms): arrivals 50 ms later than
#   the base predicts for a second of samples mean the base moved; a simulated arm that paused and
#   then sent its backlog is back on time within its pause. The offset may rise by 1 % of device
#   time: the arm's time is its sample count times the nominal period, so its oscillator's error
#   (and a host clock being slewed) shows as drift, and 100 ppm would let its samples age past
#   `max_sample_age` (20 ms) within minutes; with timed arrivals a delayed frame cannot raise it.
# - Untimed (read times): a reader stalled for up to 2 s keeps the base and its backlog its age;
#   a base 250 ms or more behind for longer is taken as moved.
ARM_CLOCK = {True: {'drift': 1e-2, 'resync': 0.05, 'settle': 1.0},
             False: {'drift': 1e-4, 'resync': 0.25, 'settle': 2.0}}

PARAMETERS = (
    Spec('arm.enabled', False, 'drive the arm on CAN'),
    Spec('actuator.enabled', False, 'drive the actuator board on serial'),
    Spec('hardware_params', '', "YAML laid over config/hardware.yaml ('' = defaults)"),
    Spec('actuator.port', '', "serial port of the actuator board ('' = hardware.yaml's)",
         check=_port_problem),
    Spec('arm.interface', '', "python-can interface ('' = hardware.yaml's)"),
    Spec('arm.channel', '', "python-can channel ('' = hardware.yaml's)"),
    Spec('arm.n_segments', 0, "segments on the bus, as the DBC defines them (0 = hardware.yaml's)",
         low=0, high=dbc_segments()),
    Spec('startup_timeout', 2.0, 'a device whose port is absent or that sent no sample by then '
         'is an error, s', low=0.01, high=600.0),
    Spec('wait_for_subscribers', 0.0, 'wait this long for a subscriber before opening the '
         'devices, s (0 = no wait)', low=0.0, high=600.0),
    Spec('autostart', False, 'configure and activate at start (false: wait for ros2 lifecycle)'),
    Spec('shutdown_timeout', 5.0, 'shutdown waits this long for the chambers to read ambient, s',
         low=0.0, high=600.0),
    # Above a pressure sensor's noise (a few hundred Pa), far below what moves a bellows: 0.05
    # bar gauge holds a 7.5 bar segment within a percent of its range.
    Spec('ambient_tolerance', 5000.0, 'a chamber this close to ambient reads ambient, Pa',
         low=1.0, high=1e5),
)


SUCCESS, FAILURE = TransitionCallbackReturn.SUCCESS, TransitionCallbackReturn.FAILURE


class DriverNode(LifecycleNode):

    def __init__(self, **kwargs):
        super().__init__('driver_node', **kwargs)
        self.given = self.declare_specs(PARAMETERS)
        self.use_arm = self.given['arm.enabled']
        self.use_actuator = self.given['actuator.enabled']
        self.startup_timeout = self.given['startup_timeout']
        realtime.declare(self)  # SCHED_FIFO priority, CPU latency limit: run() applies them
        self.check_parameters()
        if not (self.use_arm or self.use_actuator):
            raise BellowsError('driver_node: neither arm.enabled nor actuator.enabled is set')

        # Each device group on its own sample topics: only the enabled groups' are advertised.
        self.state_pub = self.actuator_state_pub = None
        if self.use_arm:
            self.state_pub = self.publisher(interfaces.JOINT_STATES)
            self.vented_pub = self.publisher(interfaces.VENTED)
        if self.use_actuator:
            self.actuator_state_pub = self.publisher(interfaces.ACTUATOR_JOINT_STATES)
        self._publish_lock = threading.Lock()  # both reader threads publish
        self.arm = self.actuator = None
        self.reports = {}
        self.published = {'arm': 0, 'actuator': 0}
        self.arm_vented = None        # the state bellows/vented last said
        self.refused = 0              # commands that arrived while not active
        self.estop_held = False       # /bellows/estop is True
        self.vent_requested = False   # ~/vent or the estop latched a vent: ~/release ends it
        self.failure = ''             # why the last configure failed
        self.vent_time = None         # s from shutdown to every chamber at ambient
        self.state = 'unconfigured'  # the lifecycle state's label, as each transition ends
        self.subscription(interfaces.PRESSURE_COMMAND, self.on_pressure_command)
        self.subscription(interfaces.MOTOR_COMMAND, self.on_motor_command)
        self.subscription(interfaces.ESTOP, self.on_estop)
        self.create_service(self.srv.Trigger, '~/vent', self.on_vent)
        self.create_service(self.srv.Trigger, '~/release', self.on_release)
        self.stopped = False          # the devices closed: the last report says so
        self.diagnostics = diagnostics.Updater(self)
        self.diagnostics.setHardwareID('none')  # the devices' tasks name their port or bus
        self.diagnostics.add('lifecycle', self.diagnose_lifecycle)
        if self.given['autostart']:
            # A device that does not answer is then a start error (one line, exit status 2).
            if self.trigger_configure() != SUCCESS:
                raise BellowsError(self.failure or 'driver_node: configure failed')
            self.trigger_activate()

    @property
    def active(self):
        return self.state == 'active'

    # --- lifecycle (rclpy.lifecycle): each returns SUCCESS or FAILURE, and keeps self.state ----
    def on_configure(self, previous):
        """Open the devices and wait for their first samples; they start vented, refusing."""
        given = self.given
        if given['wait_for_subscribers'] > 0:
            self._wait_for_subscribers(given['wait_for_subscribers'])
        hardware_params = given['hardware_params'] or None
        try:
            if self.use_actuator:
                self._open_actuator(actuator_board_config(hardware_params), given['actuator.port'])
            if self.use_arm:
                self._open_arm(arm_bus_config(hardware_params), given['arm.interface'],
                               given['arm.channel'], given['arm.n_segments'])
            self._wait_for_samples()
        except BellowsError as error:
            self.failure = str(error)
            if not self.given['autostart']:  # else it is the start's one-line error
                self.get_logger().error(f'configure failed: {error}')
            self._close_devices()
            return FAILURE
        self._hold_vented()
        self.state = 'inactive'
        self.get_logger().info(f'configured: {self._devices()} open, vented until activated')
        return SUCCESS

    def on_activate(self, previous):
        """Accept commands, unless a vent is latched (then from ~/release on)."""
        if not (self.vent_requested or self.estop_held):
            self._release_devices()
        self.state = 'active'
        self.get_logger().info(f'driving {self._devices()}'
                               + (' (vented until ~/release)' if self.vented else ''))
        return SUCCESS

    def on_deactivate(self, previous):
        self._hold_vented()
        self.state = 'inactive'
        self.get_logger().info('deactivated: vented, commands refused')
        return SUCCESS

    def on_cleanup(self, previous):
        self._close_devices()
        self.state = 'unconfigured'
        return SUCCESS

    def on_shutdown(self, previous):
        self._hold_vented()
        self._wait_for_ambient()
        self._close_devices()
        self.state = 'finalized'
        return SUCCESS

    def on_error(self, previous):
        self._hold_vented()
        self._close_devices()
        self.state = 'unconfigured'  # the error handled: rcl_lifecycle's errorprocessing -> here
        return SUCCESS

    def _devices(self):
        return ' and '.join(name for name, on in (('arm', self.use_arm),
                                                  ('actuator', self.use_actuator)) if on)

    def _hold_vented(self):
        """Vent every chamber and stop the motor at the devices: they refuse commands."""
        if self.arm is not None:
            self.arm.vent()
        if self.actuator is not None:
            self.actuator.stop()
        self._publish_vented()

    def _release_devices(self):
        for device in (self.arm, self.actuator):
            if device is not None:
                device.release()

    def _publish_vented(self):
        """Say on bellows/vented when the arm's chambers start or stop being held vented."""
        if not self.use_arm:
            return
        # Read under the lock: the reader thread (after each sample) and the executor (a vent)
        # both call this, and a state read before the other's publish would overwrite it.
        with self._publish_lock:
            arm = self.arm
            vented = arm is None or arm.vented
            if vented != self.arm_vented:
                self.arm_vented = vented
                self.vented_pub.publish(self.msg.Bool(data=vented))

    def _wait_for_ambient(self):
        """Wait until every arm chamber reads ambient (the vent pressure p0), or the timeout."""
        if self.arm is None:
            return  # the actuator's gas is sealed: a still lead screw is its safe state
        ambient, tolerance = self.arm.config.pressure_min, self.given['ambient_tolerance']
        timeout = self.given['shutdown_timeout']
        start = time.monotonic()
        while True:
            sample = self.arm.latest()
            worst = None if sample is None else max(abs(p - ambient) for p in sample.pressures)
            waited = time.monotonic() - start
            if worst is not None and worst <= tolerance:
                self.vent_time = waited
                self.get_logger().info(f'shutdown: every chamber within {tolerance:g} Pa of '
                                       f'ambient after {waited:.3f} s')
                return
            if waited >= timeout:
                reading = 'no samples' if worst is None else f'{worst:.0f} Pa from ambient'
                self.get_logger().error(f'shutdown: chambers not at ambient after {timeout:g} s '
                                        f'({reading}): check the valves before touching the arm')
                return
            time.sleep(0.005)

    # --- devices
    # -----------------------------------------------------------------------------------
    def _open_actuator(self, config, port):
        if port:
            config = dataclasses.replace(config, port=port)
        # A port may appear a moment after the driver starts (a USB board being enumerated, a
        # simulated board started beside the driver by a launch file): wait for it as for the
        # first sample.
        end = time.monotonic() + self.startup_timeout
        while not os.path.exists(config.port) and time.monotonic() < end:
            time.sleep(0.01)
        if not os.path.exists(config.port):
            raise BellowsError(f'driver_node: actuator board port {config.port} does not exist '
                               f'after {self.startup_timeout:g} s (device absent? set '
                               'actuator.port)')
        self.actuator_clock = SampleClock(interfaces.SAMPLE_PERIOD)
        self.actuator_stamps = DeviceClock()
        self.reports['actuator'] = diagnostics.LoopReport(self.actuator_clock.stats)
        self.diagnostics.add('actuator', lambda stat: self.diagnose_device('actuator', stat))
        self.actuator = actuator_board.ActuatorBoard(config, on_sample=self.on_actuator_sample)
        self.actuator_port = config.port
        # A write to the board's serial port can block for up to its write timeout (a board, or
        # a simulated one, that does not read for a while); the arm's pressure commands share
        # the callback thread, and the arm's watchdog vents after 0.1 s without one.
        self.duty_writer = NewestWriter(self.actuator.send_duty, 'motor-commands')

    def _open_arm(self, config, interface, channel, n_segments):
        config = dataclasses.replace(config, interface=interface or config.interface,
                                     channel=channel or config.channel,
                                     n_segments=n_segments or config.n_segments)
        segments = range(1, config.n_segments + 1)
        self.arm_names = interfaces.arm_sample_names(segments)
        self.chain_names = self.arm_names[config.n_segments:]  # the chambers, after the joints
        # The sample message's constant parts: its joints have no effort, its chambers no
        # position or rate (interfaces.py). Sent serialized (runtime/joint_state_cdr.py).
        self._arm_nans = (math.nan,) * len(self.chain_names)
        self._arm_no_effort = (math.nan,) * config.n_segments
        self.arm_writer = JointStateWriter(self.arm_names)
        self.arm_clock = SampleClock(interfaces.SAMPLE_PERIOD)
        self.arm_stamps = None  # made at the first sample: does the bus time its arrivals?
        self.reports['arm'] = diagnostics.LoopReport(self.arm_clock.stats)
        self.diagnostics.add('arm', lambda stat: self.diagnose_device('arm', stat))
        self._last_arm = None
        self._psi_dot = [0.0] * config.n_segments
        self.setpoints = dict.fromkeys(self.chain_names, config.pressure_min)  # vented
        try:
            bus = arm_bus.open_bus(config)
        except Exception as exc:  # python-can raises OSError/CanError subclasses per interface
            raise BellowsError(f'driver_node: cannot open CAN bus {config.interface}:'
                               f'{config.channel} ({exc})') from None
        self.arm = arm_bus.ArmBus(config, bus=bus, on_sample=self.on_arm_sample)
        self.arm_link = f'{config.interface}:{config.channel}'

    def _wait_for_samples(self):
        end = time.monotonic() + self.startup_timeout
        waiting = [(name, device) for name, device in (('actuator', self.actuator),
                                                       ('arm', self.arm)) if device]
        while waiting and time.monotonic() < end:
            waiting = [(name, device) for name, device in waiting if device.latest() is None]
            time.sleep(0.01)
        if waiting:
            name = waiting[0][0]
            where = self.actuator_port if name == 'actuator' else self.arm_link
            raise BellowsError(f'driver_node: no {name} samples on {where} within '
                               f'{self.startup_timeout:g} s (device absent or not powered)')

    def _wait_for_subscribers(self, timeout):
        end = time.monotonic() + timeout
        publishers = self._sample_publishers()
        while not all(p.get_subscription_count() for p in publishers):
            if time.monotonic() > end:
                alone = ', '.join(p.topic_name for p in publishers
                                  if not p.get_subscription_count())
                self.get_logger().warn(f'no subscriber on {alone} after {timeout:g} s: '
                                       'publishing anyway')
                return
            time.sleep(0.01)
        # Our writers have matched the readers; each reader matches our writers only when it has
        # processed our announcement, and drops what arrives before (seen: the first 8-17 samples
        # lost, half of some, under load). Give the other side the same chance.
        time.sleep(_DISCOVERY_SETTLE)

    def _sample_publishers(self):
        """Return the enabled groups' sample publishers."""
        return [p for p in (self.state_pub, self.actuator_state_pub) if p is not None]

    def close(self):
        """End of the process: shut down (vent, wait for ambient) from wherever it is."""
        if self.state in ('inactive', 'active'):
            self.trigger_shutdown()
        self._close_devices()

    def _close_devices(self):
        if getattr(self, 'duty_writer', None) is not None:
            self.duty_writer.close()
            self.duty_writer = None
        devices = [(n, d) for n, d in (('actuator', self.actuator), ('arm', self.arm)) if d]
        for _, device in devices:
            device.close()
        if devices and self.reports:
            self.stopped = True  # the closing counts, STALE: nothing is published after
            self.diagnostics.force_update()
            self.stopped = False
            # Samples still being repaired (a packet lost under load) must reach the readers
            # before the participant goes; bounded, so a reader that died cannot hold it up.
            end = time.monotonic() + 1.0
            for publisher in (*self._sample_publishers(), self.diagnostics.publisher):
                left = max(0.0, end - time.monotonic())
                publisher.wait_for_all_acked(Duration(seconds=left))
        self.actuator = self.arm = None
        for name in self.reports:
            self.diagnostics.removeByName(name)
        self.reports = {}

    # --- samples -> topics (called from the drivers' reader threads) ----------------------------
    def on_actuator_sample(self, sample):
        start = time.monotonic()
        stamp = self.actuator_stamps.stamp(int(round(sample.t_device * 1e9)),
                                           self.get_clock().now().nanoseconds)
        # One message: air chamber and spring compressions, the load cell's spring force as the
        # spring's effort, the chamber pressure as the chamber's (interfaces.py).
        state = ACTUATOR_WRITER.serialize(stamp, position=(sample.x_c, sample.x_s, math.nan),
                                          effort=(math.nan, sample.f, sample.p))
        with self._publish_lock:
            self.actuator_state_pub.publish(state)
            self.published['actuator'] += 1
        self.actuator_clock.tick(sample.index, sample.t_receive, time.monotonic() - start)

    def on_arm_sample(self, sample):
        start = time.monotonic()
        # The arm's clock mapped onto the node clock, from when each frame reached the host (the
        # bus's timestamp): stamped when this thread got to it, a backlog read 0.5-1.5 s late by
        # a starved reader went out as fresh samples, and the arm controller acted on them.
        arrival = arrival_ns(self.get_clock().now().nanoseconds, sample.t_arrival)
        if self.arm_stamps is None:
            self.arm_stamps = DeviceClock(**ARM_CLOCK[on_host_clock(sample.t_arrival)])
        stamp = self.arm_stamps.stamp(int(round(sample.t_device * 1e9)), arrival)
        previous = self._last_arm
        if previous is not None:
            # The encoder-less arm has no Ψ̇ sensor: the project's rate estimator (derivatives).
            dt = sample.t_device - previous.t_device
            self._psi_dot = [rate(a, b, dt, held)
                             for a, b, held in zip(sample.psi, previous.psi, self._psi_dot)]
        self._last_arm = sample
        state = self.arm_writer.serialize(
            stamp, position=(*sample.psi, *self._arm_nans),
            velocity=(*self._psi_dot, *self._arm_nans),
            effort=(*self._arm_no_effort, *sample.pressures))
        with self._publish_lock:
            self.state_pub.publish(state)
            self.published['arm'] += 1
        self._publish_vented()   # the watchdog and the first accepted command change it
        self.arm_clock.tick(sample.index, sample.t_receive, time.monotonic() - start)

    # --- commands (refused by the devices unless active and released) ---------------------------
    def on_pressure_command(self, msg):
        if self.arm is None:
            self.refused += 1
            return
        # A command may name some chambers only; the others keep their last set-point.
        for name, value in zip(msg.name, msg.effort):
            if name in self.setpoints:
                self.setpoints[name] = value
        self.arm.send_pressures([self.setpoints[name] for name in self.chain_names])

    def on_motor_command(self, msg):
        if self.actuator is None:
            self.refused += 1
            return
        self.duty_writer.put(msg.data)

    # --- the stop that latches (docs/protocols.md, "Safety states") ----------------------------
    @property
    def vented(self):
        return any(device.latched for device in (self.arm, self.actuator) if device is not None)

    def vent(self, why):
        """Vent every chamber and stop the motor now; refuse commands until `release`."""
        self.vent_requested = True
        self._hold_vented()
        self.get_logger().warn(f'vented ({why}): commands refused until released')

    def release(self):
        """End a latched vent, unless the emergency stop is held; returns (done, why)."""
        if self.estop_held:
            return False, f'{interfaces.ESTOP.name} is held (True): release it first'
        self.vent_requested = False
        if not self.active:
            why = f'released: commands accepted once active (now {self.state})'
        else:
            self._release_devices()
            why = 'released: commands accepted again (vented until the next set-point)'
        self.get_logger().info(why)
        return True, why

    def on_vent(self, request, response):
        self.vent('~/vent called')
        response.success, response.message = True, 'vented: commands refused until ~/release'
        return response

    def on_release(self, request, response):
        response.success, response.message = self.release()
        return response

    def on_estop(self, msg):
        # True vents and latches; False only stops holding it: a release is a decision of its own.
        if msg.data and not self.estop_held:
            self.vent(f'{interfaces.ESTOP.name}')
        self.estop_held = bool(msg.data)

    # --- diagnostics -----------------------------------------------------------------------------
    def diagnose_device(self, name, stat):
        """One device: its link (hardware_id), sample rate and timing, counters, safety state."""
        device = self.actuator if name == 'actuator' else self.arm
        if device is None:  # closed between two reports
            stat.summary(diagnostics.STALE, 'device closed')
            return stat
        link = self.actuator_port if name == 'actuator' else self.arm_link
        clock = self.actuator_clock if name == 'actuator' else self.arm_clock
        stat.hardware_id = link
        values, _, new_misses = self.reports[name].values()
        values.update(device.counters())
        values['published'] = str(self.published[name])
        values['stale'] = str(device.stale)
        values['lifecycle'] = self.state
        values['vented'] = str(device.latched)
        values['estop_held'] = str(self.estop_held)
        values['refused_unconfigured'] = str(self.refused)
        stat.update(values)
        clock.frequency.run(stat)  # summary and keys of the sample rate against 1 kHz
        if self.stopped:
            stat.summary(diagnostics.STALE, 'driver stopped: these are the final counts')
        elif device.stale:
            stat.summary(diagnostics.ERROR, f'no data from {link} (link down or device stopped)')
        else:
            if new_misses:
                stat.mergeSummary(diagnostics.WARN, f'{new_misses} samples missed')
            if self.estop_held:
                stat.mergeSummary(diagnostics.WARN, 'vented by the emergency stop')
            elif self.vent_requested:
                stat.mergeSummary(diagnostics.WARN, 'vented until released (~/release)')
            elif not self.active:
                stat.mergeSummary(diagnostics.OK, f'{self.state}: vented, commands '
                                  'refused')
        return stat

    def diagnose_lifecycle(self, stat):
        """Report the node's state: lifecycle, emergency stop, vent latch, refused commands."""
        state = self.state
        stat.update({'lifecycle': state, 'devices': self._devices() or 'none',
                     'estop_held': str(self.estop_held),
                     'vent_requested': str(self.vent_requested),
                     'refused_unconfigured': str(self.refused),
                     'last_failure': self.failure or 'none'})
        if self.stopped:
            stat.summary(diagnostics.STALE, 'driver stopped')
        elif self.estop_held:
            stat.summary(diagnostics.WARN, f'vented by the emergency stop ({interfaces.ESTOP.name}'
                         ' True)')
        elif self.vent_requested:
            stat.summary(diagnostics.WARN, 'vented until released (~/release)')
        elif state == 'active':
            stat.summary(diagnostics.OK, 'active: commands accepted')
        elif state == 'unconfigured' and self.failure:
            stat.summary(diagnostics.ERROR, f'configure failed: {self.failure}')
        else:
            stat.summary(diagnostics.OK, f'{state}: vented, commands refused')
        return stat


def main(args=None):
    return run(DriverNode, args)


if __name__ == '__main__':
    raise SystemExit(main())
