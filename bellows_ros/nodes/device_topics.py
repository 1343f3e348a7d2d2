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
The driver's side of each kind of device: its sample and command topics, and how it is made.

Each class says what a device's sample message is, what its command message carries, and how
the device is built from driver_node's parameters.

driver_node holds a list of these, one per enabled device, and treats them alike; the device
behind each is a `hardware.device.Device`. A kind of device is one class here with the members of
`DeviceTopics`: the arm on CAN (`ArmTopics`) and the actuator board on serial (`ActuatorTopics`).
"""
import dataclasses
import math
import os
import time

from bellows_ros import interfaces
from bellows_ros.config.hardware import actuator_board_config, arm_bus_config
from bellows_ros.errors import BellowsError
from bellows_ros.hardware import actuator_board, arm_bus
from bellows_ros.hardware.loop_timing import LoopStats
from bellows_ros.hardware.sample_delivery import arrival_ns, DeviceClock, on_host_clock
from bellows_ros.models.derivatives import rate
from bellows_ros.nodes import diagnostics
from bellows_ros.runtime.joint_state_cdr import JointStateWriter


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


class DeviceTopics:
    """
    One device as the driver publishes it and takes its commands.

    `make(given, hardware_params, on_sample)` builds the device (a `Device`, not yet started) from
    driver_node's parameters; `message(sample, now_ns)` is the serialized sample message, stamped
    on the node clock; `command(msg)` is the device command a command message carries (None: not
    for this device). `vented_topic`: a latched Bool that says when the device is held in its
    safe state, or None.
    """

    name = ''
    sample_topic = None
    command_topic = None
    vented_topic = None

    def __init__(self):
        self.device = None          # the Device, while the driver has it open
        self.publisher = None       # of sample_topic, and of vented_topic: the driver's
        self.vented_pub = None
        self.said_vented = None     # what vented_topic last said
        self.published = 0
        self.new_clock()

    def new_clock(self):
        """Time the samples afresh: the device is (re)opened."""
        self.clock = SampleClock(interfaces.SAMPLE_PERIOD)
        self.report = diagnostics.LoopReport(self.clock.stats)

    def make(self, given, hardware_params, on_sample):
        raise NotImplementedError

    def message(self, sample, now_ns):
        raise NotImplementedError

    def command(self, msg):
        raise NotImplementedError


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


class ArmTopics(DeviceTopics):
    """The arm on CAN: `/joint_states` out (Ψ, Ψ̇, chain pressures), pressure commands in."""

    name = 'arm'
    sample_topic = interfaces.JOINT_STATES
    command_topic = interfaces.PRESSURE_COMMAND
    vented_topic = interfaces.VENTED

    def make(self, given, hardware_params, on_sample):
        config = arm_bus_config(hardware_params)
        config = dataclasses.replace(config, interface=given['arm.interface'] or config.interface,
                                     channel=given['arm.channel'] or config.channel,
                                     n_segments=given['arm.n_segments'] or config.n_segments)
        names = interfaces.arm_sample_names(range(1, config.n_segments + 1))
        self.chain_names = names[config.n_segments:]  # the chambers, after the joints
        # The message's constant parts: its joints have no effort, its chambers no position or
        # rate (interfaces.py). Sent serialized (runtime/joint_state_cdr.py).
        self._nans = (math.nan,) * len(self.chain_names)
        self._no_effort = (math.nan,) * config.n_segments
        self.writer = JointStateWriter(names)
        self.stamps = None  # made at the first sample: does the bus time its arrivals?
        self._last = None
        self._psi_dot = [0.0] * config.n_segments
        self.setpoints = dict.fromkeys(self.chain_names, config.pressure_min)  # vented
        try:
            bus = arm_bus.open_bus(config)
        except Exception as exc:  # python-can raises OSError/CanError subclasses per interface
            raise BellowsError(f'driver_node: cannot open CAN bus {config.interface}:'
                               f'{config.channel} ({exc})') from None
        return arm_bus.ArmBus(config, bus=bus, on_sample=on_sample)

    def message(self, sample, now_ns):
        # The arm's clock mapped onto the node clock, from when each frame reached the host (the
        # bus's timestamp): stamped when this thread got to it, a backlog read 0.5-1.5 s late by
        # a starved reader went out as fresh samples, and the arm controller acted on them.
        arrival = arrival_ns(now_ns, sample.t_arrival)
        if self.stamps is None:
            self.stamps = DeviceClock(**ARM_CLOCK[on_host_clock(sample.t_arrival)])
        stamp = self.stamps.stamp(int(round(sample.t_device * 1e9)), arrival)
        previous = self._last
        if previous is not None:
            # The encoder-less arm has no Ψ̇ sensor: the project's rate estimator (derivatives).
            dt = sample.t_device - previous.t_device
            self._psi_dot = [rate(a, b, dt, held)
                             for a, b, held in zip(sample.psi, previous.psi, self._psi_dot)]
        self._last = sample
        return self.writer.serialize(
            stamp, position=(*sample.psi, *self._nans), velocity=(*self._psi_dot, *self._nans),
            effort=(*self._no_effort, *sample.pressures))

    def command(self, msg):
        # A command may name some chambers only; the others keep their last set-point.
        for name, value in zip(msg.name, msg.effort):
            if name in self.setpoints:
                self.setpoints[name] = value
        return [self.setpoints[name] for name in self.chain_names]


ACTUATOR_WRITER = JointStateWriter(interfaces.actuator_sample_names(), velocity=False)


class ActuatorTopics(DeviceTopics):
    """The actuator board on serial: `/actuator/joint_states` out, motor duties in."""

    name = 'actuator'
    sample_topic = interfaces.ACTUATOR_JOINT_STATES
    command_topic = interfaces.MOTOR_COMMAND

    def make(self, given, hardware_params, on_sample):
        config = actuator_board_config(hardware_params)
        if given['actuator.port']:
            config = dataclasses.replace(config, port=given['actuator.port'])
        # A port may appear a moment after the driver starts (a USB board being enumerated, a
        # simulated board started beside the driver by a launch file): wait for it as for the
        # first sample.
        timeout = given['startup_timeout']
        end = time.monotonic() + timeout
        while not os.path.exists(config.port) and time.monotonic() < end:
            time.sleep(0.01)
        if not os.path.exists(config.port):
            raise BellowsError(f'driver_node: actuator board port {config.port} does not exist '
                               f'after {timeout:g} s (device absent? set actuator.port)')
        self.stamps = DeviceClock()
        return actuator_board.ActuatorBoard(config, on_sample=on_sample)

    def message(self, sample, now_ns):
        stamp = self.stamps.stamp(int(round(sample.t_device * 1e9)), now_ns)
        # One message: air chamber and spring compressions, the load cell's spring force as the
        # spring's effort, the chamber pressure as the chamber's (interfaces.py).
        return ACTUATOR_WRITER.serialize(stamp, position=(sample.x_c, sample.x_s, math.nan),
                                         effort=(math.nan, sample.f, sample.p))

    def command(self, msg):
        return msg.data


KINDS = (ArmTopics, ActuatorTopics)  # enabled by `<name>.enabled`; opened in this order
