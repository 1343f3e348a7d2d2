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
The device contract: what the driver needs of a device, and all it may assume of one.

After ros2_control's hardware interface and python-can's `BusABC`: a device is built from its
configuration, `start()` starts its threads (samples flow, commands are taken), and an
implementation overrides the abstract members below. The driver (nodes/driver_node.py) holds a
list of devices and treats them all alike.

Implementations: the host's drivers, `arm_bus.ArmBus` (the arm on CAN) and
`actuator_board.ActuatorBoard` (the actuator board on serial), and their simulated twins at
protocol level seen from the device's side, `sim_arm_bus.SimArmBus` and
`sim_actuator_board.SimActuatorBoard` (what the device measured, what it was told). One
conformance test runs against each (test/test_hw_device.py).

Samples: `read()` gives the newest one that is not stale (the arm's `ArmSample`, the actuator's
`ActuatorSample`); a driver also hands every sample, as it arrives, to its `on_sample` callback.
Commands: `write(command)` never blocks (a link that can block is written from a thread of the
device's own) and returns what the device will apply after its safety limits, or None when it
refuses the command. The safe state: `vent()` puts the device there at once and holds it until
`release()` (`latched`); `vented` also counts a watchdog's vent (no command for too long).
"""
import abc


class Device(abc.ABC):
    """A device behind the driver: a sample stream in, commands out, a safe state."""

    #: Which device this is: the name of its diagnostics task and of its sample group.
    name = ''

    #: `vent()` holds the safe state until `release()`.
    latched = False

    @property
    @abc.abstractmethod
    def link(self):
        """Where the device is: a serial port, or a CAN interface and channel (str)."""

    @abc.abstractmethod
    def start(self):
        """Start talking to the device: its threads start, samples flow, commands are taken."""

    @abc.abstractmethod
    def read(self):
        """Return the newest sample, or None when there is none or it is stale."""

    @property
    def stale(self):
        """No sample newer than the device's stale timeout."""
        return self.read() is None

    @abc.abstractmethod
    def write(self, command):
        """
        Take a command (the arm: chamber pressures, Pa abs; the actuator: a motor duty, -1..1).

        Returns what the device will apply after its safety limits, or None when refused
        (latched). Never blocks.
        """

    @abc.abstractmethod
    def vent(self):
        """Go to the safe state now and hold it until `release()`; commands are refused."""

    @abc.abstractmethod
    def release(self):
        """Take commands again; the device stays in its safe state until the next one."""

    @property
    @abc.abstractmethod
    def vented(self):
        """In the safe state now: latched by `vent()`, or vented by a watchdog."""

    @abc.abstractmethod
    def at_rest(self, tolerance):
        """
        Tell whether the safe state has been reached physically, as far as the samples show.

        The arm: every chamber within `tolerance` Pa of ambient (False without a sample). The
        actuator's gas is sealed: a still lead screw is its safe state, reached when the motor
        stops.
        """

    @abc.abstractmethod
    def health(self):
        """Return the device's counters ({name: int}), for /diagnostics."""

    @abc.abstractmethod
    def close(self):
        """Go to the safe state, stop the threads, close the link. A second call does nothing."""
