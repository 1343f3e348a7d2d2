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
safety limits (clamping, end stops, watchdogs). The node holds a list of devices, one per enabled
group, and treats them alike: each is a `hardware.device.Device`, and `device_topics` says what
its topics are and how it is made.

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
import os
import stat
import threading
import time

from rclpy.duration import Duration
from rclpy.lifecycle import TransitionCallbackReturn

from bellows_ros import interfaces
from bellows_ros.errors import BellowsError
from bellows_ros.hardware.can_protocol import dbc_segments
from bellows_ros.nodes import diagnostics
from bellows_ros.nodes.device_topics import KINDS
from bellows_ros.runtime import LifecycleNode, realtime, run
from bellows_ros.runtime.parameters import Spec

_DISCOVERY_SETTLE = 0.5  # s, see DriverNode._wait_for_subscribers


def _port_problem(port):
    """Say what is wrong with a serial port: it must be a character device, or absent."""
    if port and os.path.exists(port) and not stat.S_ISCHR(os.stat(port).st_mode):
        return 'not a character device (a serial port is one, or absent)'
    return ''


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
        self.startup_timeout = self.given['startup_timeout']
        realtime.declare(self)  # SCHED_FIFO priority, CPU latency limit: run() applies them
        self.check_parameters()
        # One entry per enabled device (device_topics.py); each group on its own sample topic.
        self.devices = [kind() for kind in KINDS if self.given[f'{kind.name}.enabled']]
        if not self.devices:
            raise BellowsError('driver_node: neither arm.enabled nor actuator.enabled is set')
        self._publish_lock = threading.Lock()  # every device's reader thread publishes
        for topics in self.devices:
            topics.publisher = self.publisher(topics.sample_topic)
            if topics.vented_topic:
                topics.vented_pub = self.publisher(topics.vented_topic)
            self.subscription(topics.command_topic,
                              lambda msg, topics=topics: self.on_command(topics, msg))
        self.refused = 0              # commands that arrived while not configured
        self.estop_held = False       # /bellows/estop is True
        self.vent_requested = False   # ~/vent or the estop latched a vent: ~/release ends it
        self.failure = ''             # why the last configure failed
        self.vent_time = None         # s from shutdown to every device at rest
        self.state = 'unconfigured'  # the lifecycle state's label, as each transition ends
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

    def _opened(self):
        """Return the devices that are open (configured)."""
        return [topics.device for topics in self.devices if topics.device is not None]

    # --- lifecycle (rclpy.lifecycle): each returns SUCCESS or FAILURE, and keeps self.state ----
    def on_configure(self, previous):
        """Open the devices and wait for their first samples; they start vented, refusing."""
        given = self.given
        if given['wait_for_subscribers'] > 0:
            self._wait_for_subscribers(given['wait_for_subscribers'])
        try:
            for topics in self.devices:
                topics.new_clock()
                device = topics.make(given, given['hardware_params'] or None,
                                     lambda sample, topics=topics: self.on_sample(topics, sample))
                topics.device = device
                device.vent()  # vented and refusing from its first sample: nothing commanded
                device.start()
                self.diagnostics.add(
                    topics.name, lambda stat, topics=topics: self.diagnose_device(topics, stat))
            self._wait_for_samples()
        except BellowsError as error:
            self.failure = str(error)
            if not self.given['autostart']:  # else it is the start's one-line error
                self.get_logger().error(f'configure failed: {error}')
            self._close_devices()
            return FAILURE
        self._hold_vented()
        self.state = 'inactive'
        self.get_logger().info(f'configured: {self._names()} open, vented until activated')
        return SUCCESS

    def on_activate(self, previous):
        """Accept commands, unless a vent is latched (then from ~/release on)."""
        if not (self.vent_requested or self.estop_held):
            for device in self._opened():
                device.release()
        self.state = 'active'
        self.get_logger().info(f'driving {self._names()}'
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
        self._wait_for_rest()
        self._close_devices()
        self.state = 'finalized'
        return SUCCESS

    def on_error(self, previous):
        self._hold_vented()
        self._close_devices()
        self.state = 'unconfigured'  # the error handled: rcl_lifecycle's errorprocessing -> here
        return SUCCESS

    def _names(self):
        return ' and '.join(topics.name for topics in self.devices)

    def _hold_vented(self):
        """Put every device in its safe state (chambers vented, motor stopped); they refuse."""
        for device in self._opened():
            device.vent()
        for topics in self.devices:
            self._publish_vented(topics)

    def _publish_vented(self, topics):
        """Say on the device's vented topic (if any) when it starts or stops being vented."""
        if topics.vented_pub is None:
            return
        # Read under the lock: the reader thread (after each sample) and the executor (a vent)
        # both call this, and a state read before the other's publish would overwrite it.
        with self._publish_lock:
            device = topics.device
            vented = device is None or device.vented
            if vented != topics.said_vented:
                topics.said_vented = vented
                topics.vented_pub.publish(self.msg.Bool(data=vented))

    def _wait_for_rest(self):
        """Wait until every device is at rest (each chamber at ambient), or the timeout."""
        tolerance, timeout = self.given['ambient_tolerance'], self.given['shutdown_timeout']
        start = time.monotonic()
        while True:
            moving = [topics.name for topics in self.devices
                      if topics.device is not None and not topics.device.at_rest(tolerance)]
            waited = time.monotonic() - start
            if not moving:
                self.vent_time = waited
                self.get_logger().info(f'shutdown: every device at rest (chambers within '
                                       f'{tolerance:g} Pa of ambient) after {waited:.3f} s')
                return
            if waited >= timeout:
                self.get_logger().error(f'shutdown: {", ".join(moving)} not at rest after '
                                        f'{timeout:g} s: check the valves before touching it')
                return
            time.sleep(0.005)

    # --- devices -----------------------------------------------------------------------------
    def _wait_for_samples(self):
        end = time.monotonic() + self.startup_timeout
        waiting = list(self.devices)
        while waiting and time.monotonic() < end:
            waiting = [topics for topics in waiting if topics.device.read() is None]
            time.sleep(0.01)
        if waiting:
            raise BellowsError(f'driver_node: no {waiting[0].name} samples on '
                               f'{waiting[0].device.link} within {self.startup_timeout:g} s '
                               '(device absent or not powered)')

    def _wait_for_subscribers(self, timeout):
        end = time.monotonic() + timeout
        publishers = [topics.publisher for topics in self.devices]
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

    def close(self):
        """End of the process: shut down (vent, wait for rest) from wherever it is."""
        if self.state in ('inactive', 'active'):
            self.trigger_shutdown()
        self._close_devices()

    def _close_devices(self):
        opened = self._opened()
        for device in opened:
            device.close()
        if opened:
            self.stopped = True  # the closing counts, STALE: nothing is published after
            self.diagnostics.force_update()
            self.stopped = False
            # Samples still being repaired (a packet lost under load) must reach the readers
            # before the participant goes; bounded, so a reader that died cannot hold it up.
            end = time.monotonic() + 1.0
            for publisher in (*(t.publisher for t in self.devices), self.diagnostics.publisher):
                left = max(0.0, end - time.monotonic())
                publisher.wait_for_all_acked(Duration(seconds=left))
        for topics in self.devices:
            if topics.device is not None:
                self.diagnostics.removeByName(topics.name)
            topics.device = None

    # --- samples -> topics (called from the devices' reader threads) ----------------------------
    def on_sample(self, topics, sample):
        start = time.monotonic()
        state = topics.message(sample, self.get_clock().now().nanoseconds)
        with self._publish_lock:
            topics.publisher.publish(state)
            topics.published += 1
        self._publish_vented(topics)   # the watchdog and the first accepted command change it
        topics.clock.tick(sample.index, sample.t_receive, time.monotonic() - start)

    # --- commands (refused by the devices unless active and released) ---------------------------
    def on_command(self, topics, msg):
        device = topics.device
        if device is None:
            self.refused += 1
            return
        command = topics.command(msg)
        if command is not None:
            device.write(command)

    # --- the stop that latches (docs/protocols.md, "Safety states") ----------------------------
    @property
    def vented(self):
        return any(device.latched for device in self._opened())

    def vent(self, why):
        """Put every device in its safe state now; refuse commands until `release`."""
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
            for device in self._opened():
                device.release()
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
    def diagnose_device(self, topics, stat):
        """One device: its link (hardware_id), sample rate and timing, counters, safety state."""
        device = topics.device
        if device is None:  # closed between two reports
            stat.summary(diagnostics.STALE, 'device closed')
            return stat
        stat.hardware_id = device.link
        values, _, new_misses = topics.report.values()
        values.update(device.health())
        values['published'] = str(topics.published)
        values['stale'] = str(device.stale)
        values['lifecycle'] = self.state
        values['vented'] = str(device.latched)
        values['estop_held'] = str(self.estop_held)
        values['refused_unconfigured'] = str(self.refused)
        stat.update(values)
        topics.clock.frequency.run(stat)  # summary and keys of the sample rate against 1 kHz
        if self.stopped:
            stat.summary(diagnostics.STALE, 'driver stopped: these are the final counts')
        elif device.stale:
            stat.summary(diagnostics.ERROR, f'no data from {device.link} (link down or device '
                         'stopped)')
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
        stat.update({'lifecycle': state, 'devices': self._names() or 'none',
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
