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
The device contract (hardware/device.py), run against every implementation.

The host's drivers (ArmBus over a virtual CAN bus, ActuatorBoard over a pty) each talk to their
simulated twin; the twins (SimArmBus, SimActuatorBoard) are also tested alone, as devices seen
from their own side. Each test holds one promise of the contract that the driver relies on.
"""
import dataclasses
import math
import os

import can
from polling import wait_for
import pytest

from bellows_ros.config.hardware import actuator_board_config, arm_bus_config
from bellows_ros.hardware.actuator_board import ActuatorBoard
from bellows_ros.hardware.arm_bus import ArmBus
from bellows_ros.hardware.device import Device
from bellows_ros.hardware.sim_actuator_board import ActuatorState, SimActuatorBoard
from bellows_ros.hardware.sim_arm_bus import SimArmBus

pytestmark = pytest.mark.realtime  # runs alone, after the others (scripts/test.sh)

ARM = arm_bus_config()
BOARD = actuator_board_config()
N = ARM.n_segments
TOLERANCE = 5000.0  # Pa, driver_node's ambient_tolerance


def arm_plant(dt, setpoints):
    """Chambers at their set-points at once; the angles follow the pressure difference."""
    return [(setpoints[2 * i], setpoints[2 * i + 1],
             max(-1.0, min(1.0, 1e-6 * (setpoints[2 * i] - setpoints[2 * i + 1]))))
            for i in range(N)]


class ActuatorPlant:
    """The chamber moves at 20 mm/s per unit duty from mid-travel; the pressure follows it."""

    def __init__(self):
        self.x_c = 0.5 * (BOARD.x_c_min + BOARD.x_c_max)

    def __call__(self, dt, duty):
        self.x_c += 0.02 * duty * dt
        return ActuatorState(x_c=self.x_c, p=101325.0 + 2e6 * self.x_c, x_s=0.004, f=6.0)


def arm_bus(channel, made):
    sim = SimArmBus(can.Bus(interface='virtual', channel=channel), arm_plant, N)
    made.append(sim)
    sim.start()
    return ArmBus(dataclasses.replace(ARM, interface='virtual', channel=channel))


def sim_arm_bus(channel, made):
    return SimArmBus(can.Bus(interface='virtual', channel=channel), arm_plant, N)


def actuator_board(channel, made):
    sim = SimActuatorBoard(ActuatorPlant(), config=BOARD)
    made.append(sim)
    sim.start()
    return ActuatorBoard(dataclasses.replace(BOARD, port=sim.port))


def sim_actuator_board(channel, made):
    return SimActuatorBoard(ActuatorPlant(), config=BOARD)


# The implementations, a command each takes (pressures, Pa abs, for the arm; a duty for the
# actuator) and one that is not finite.
IMPLEMENTATIONS = {
    'ArmBus': (arm_bus, [2.0e5] * (2 * N), [math.nan] * (2 * N)),
    'SimArmBus': (sim_arm_bus, [2.0e5] * (2 * N), [math.nan] * (2 * N)),
    'ActuatorBoard': (actuator_board, 0.1, math.nan),
    'SimActuatorBoard': (sim_actuator_board, 0.1, math.nan),
}


@pytest.fixture(params=sorted(IMPLEMENTATIONS))
def device(request):
    """Yield a device of each implementation, not yet started; close it and its peer after."""
    made = []
    build, command, nonfinite = IMPLEMENTATIONS[request.param]
    device = build(f'device-test-{os.getpid()}-{request.node.name}', made)
    device.command, device.nonfinite = command, nonfinite
    yield device
    device.close()
    for other in made:
        other.close()


def started(device):
    device.start()
    assert wait_for(lambda: device.read() is not None), f'no sample from {device.link}'
    return device


def test_a_device_names_itself_and_its_link(device):
    assert isinstance(device, Device)
    assert device.name in ('arm', 'actuator')
    assert isinstance(device.link, str) and device.link


def test_samples_flow_only_once_started(device):
    assert device.read() is None and device.stale
    started(device)
    first = device.read()
    assert wait_for(lambda: device.read().index > first.index)
    assert not device.stale


def test_health_is_counters(device):
    counts = started(device).health()
    assert counts and all(isinstance(k, str) and isinstance(v, int) for k, v in counts.items())


def test_a_released_device_takes_commands_and_leaves_its_safe_state(device):
    started(device).release()
    taken = device.write(device.command)
    assert taken is not None and taken == pytest.approx(device.command, abs=1e-4)  # Q15 duty
    assert wait_for(lambda: not device.vented)
    assert wait_for(lambda: not device.at_rest(TOLERANCE))


def test_vent_holds_the_safe_state_until_release(device):
    started(device).release()
    assert device.write(device.command) is not None
    device.vent()
    assert device.latched and device.vented
    assert device.write(device.command) is None          # refused while latched
    assert wait_for(lambda: device.at_rest(TOLERANCE))    # and reached physically
    device.release()
    assert not device.latched
    assert device.write(device.command) is not None


def test_close_twice_and_the_samples_go_stale(device):
    started(device).close()
    device.close()
    assert wait_for(lambda: device.read() is None)


def test_a_non_finite_command_never_leaves_the_safe_state(device):
    started(device).release()
    taken = device.write(device.nonfinite)
    assert all(math.isfinite(v) for v in (taken if isinstance(taken, (list, tuple)) else [taken]))
    assert wait_for(lambda: device.at_rest(TOLERANCE))
