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
driver_node in the test's process: its parameters, its lifecycle, its safe state.

The node is built in an rclpy context of the test's own (on a domain of its own) and driven by
its own transition methods (`trigger_configure()`, ...), as rclpy's lifecycle services would;
commands are handed to its command callback. Its device is a simulated arm (`SimArmBus`) on
python-can's in-process `virtual` bus: what the arm's valves apply (`SimArmBus.setpoints`) says
whether a transition vented it. The arm's command watchdog is set to 30 s (hardware_params), so
that only the node's own venting can bring the chambers back to ambient while a test looks.
The same node as a process, under `ros2 lifecycle`, is test_graph_lifecycle.py's.
"""
import functools
import os

import can
from polling import wait_for
import pytest
from rclpy.lifecycle import TransitionCallbackReturn

from bellows_ros import interfaces
from bellows_ros.config.hardware import vent_pressure
from bellows_ros.errors import BellowsError, ParameterError
from bellows_ros.hardware.sim_arm_bus import SimArmBus
from bellows_ros.nodes import diagnostics
from bellows_ros.nodes.driver_node import DriverNode
from bellows_ros.runtime.messages import msg

SUCCESS, FAILURE = TransitionCallbackReturn.SUCCESS, TransitionCallbackReturn.FAILURE
AMBIENT = vent_pressure()  # Pa abs
CHAMBERS = list(interfaces.arm_sample_names([1])[1:])
# Pa: a set-point crosses the bus in the DBC's resolution
RESOLUTION = 500.0


@pytest.fixture
def driver(build_node):
    """Return `build(**parameters)`: a DriverNode (conftest's `build_node`)."""
    return functools.partial(build_node, DriverNode)


@pytest.fixture
def arm(request, tmp_path):
    """
    Yield (the simulated one-segment arm, the driver's parameters to drive it).

    A test takes it before `driver`: the driver then shuts down (and waits for the chambers at
    ambient) while the arm still answers.
    """
    channel = f'driver-node-{os.getpid()}-{request.node.name}'

    def plant(dt, setpoints):  # the chambers at their set-points at once
        return [(setpoints[0], setpoints[1], 1e-6 * (setpoints[0] - setpoints[1]))]
    sim = SimArmBus(can.Bus(interface='virtual', channel=channel), plant, n_segments=1)
    sim.start()
    hardware = tmp_path / 'hardware.yaml'
    hardware.write_text('/**:\n  ros__parameters:\n    hardware:\n      arm_bus:\n'
                        '        command_timeout: 30.0\n')
    yield sim, {'arm.enabled': True, 'arm.interface': 'virtual', 'arm.channel': channel,
                'arm.n_segments': 1, 'hardware_params': str(hardware),
                'shutdown_timeout': 2.0}
    sim.close()


def command(node, p1, p2):
    """Hand the node a pressure command for segment 1's chambers (Pa abs), as its topic would."""
    [topics] = node.devices
    node.on_command(topics, msg.JointState(name=CHAMBERS, effort=[p1, p2]))


def valves_at(sim, p1, p2):
    return all(abs(a - b) <= RESOLUTION for a, b in zip(sim.setpoints, (p1, p2)))


def lifecycle_status(node):
    return {s.name: s for s in node.diagnostics.force_update()}['lifecycle']


def test_a_driver_with_no_device_enabled_is_refused(driver):
    with pytest.raises(BellowsError, match='neither arm.enabled nor actuator.enabled is set'):
        driver()


def test_an_actuator_port_that_is_no_character_device_is_refused_naming_it(driver, tmp_path):
    regular = tmp_path / 'board'
    regular.touch()
    with pytest.raises(ParameterError, match=r"^driver_node: parameter 'actuator\.port' .*"
                       'not a character device'):
        driver(**{'actuator.enabled': True, 'actuator.port': str(regular)})
    # absent is allowed: a board may be plugged in before configure
    driver(**{'actuator.enabled': True, 'actuator.port': str(tmp_path / 'later')})


def test_a_parameter_the_driver_does_not_have_is_refused_naming_it(driver):
    with pytest.raises(ParameterError, match="^unknown parameter 'arm.bitrate' for node "
                       "'driver_node'"):
        driver(**{'arm.enabled': True, 'arm.bitrate': 500000})


def test_a_configure_without_the_device_fails_and_leaves_the_driver_unconfigured(
        driver, tmp_path):
    port = tmp_path / 'no_board'
    node = driver(**{'actuator.enabled': True, 'actuator.port': str(port),
                     'startup_timeout': 0.05})
    [topics] = node.devices
    node.on_command(topics, msg.Float64(data=0.5))
    assert node.refused == 1  # a command before configure is counted, nothing is open
    assert node.trigger_configure() == FAILURE
    assert node.state == 'unconfigured' and topics.device is None
    assert str(port) in node.failure and 'actuator.port' in node.failure
    status = lifecycle_status(node)
    assert status.level == diagnostics.ERROR
    assert status.message == f'configure failed: {node.failure}'


@pytest.mark.realtime
def test_the_transitions_open_vent_drive_and_close_the_arm(arm, driver):
    sim, parameters = arm
    node = driver(**parameters)
    [topics] = node.devices
    command(node, 3e5, 2e5)
    assert node.refused == 1 and topics.device is None

    assert node.trigger_configure() == SUCCESS and node.state == 'inactive'
    device = topics.device
    # inactive: samples flow, the chambers are held vented and say so on the vented topic
    assert wait_for(lambda: device.read() is not None)
    assert device.latched and topics.said_vented is True
    command(node, 3e5, 2e5)
    assert device.health()['refused_while_vented'] == 1

    assert node.trigger_activate() == SUCCESS and node.state == 'active'
    assert not device.latched
    assert wait_for(lambda: command(node, 3e5, 2e5) or valves_at(sim, 3e5, 2e5))
    assert wait_for(lambda: topics.said_vented is False)  # said after the next sample

    assert node.trigger_deactivate() == SUCCESS and node.state == 'inactive'
    assert device.latched and topics.said_vented is True
    assert wait_for(lambda: valves_at(sim, AMBIENT, AMBIENT)), sim.setpoints
    command(node, 3e5, 2e5)
    assert device.health()['refused_while_vented'] == 2

    assert node.trigger_cleanup() == SUCCESS and node.state == 'unconfigured'
    assert topics.device is None and 'arm' not in [
        s.name for s in node.diagnostics.force_update()]
    command(node, 3e5, 2e5)
    assert node.refused == 2


@pytest.mark.realtime
def test_the_end_of_the_process_vents_and_waits_until_the_chambers_read_ambient(arm, driver):
    sim, parameters = arm
    node = driver(**parameters)
    assert node.trigger_configure() == SUCCESS and node.trigger_activate() == SUCCESS
    assert wait_for(lambda: command(node, 4e5, 4e5) or valves_at(sim, 4e5, 4e5))
    node.close()  # what `run` calls at the end: shutdown from active
    assert node.state == 'finalized'
    # shutdown waited for every chamber at ambient (no command watchdog helped: 30 s)
    assert node.vent_time is not None
    assert valves_at(sim, AMBIENT, AMBIENT) and node.devices[0].device is None


@pytest.mark.realtime
def test_a_vent_latches_through_deactivate_and_activate_until_released(arm, driver):
    sim, parameters = arm
    node = driver(**parameters)
    assert node.trigger_configure() == SUCCESS and node.trigger_activate() == SUCCESS
    device = node.devices[0].device
    assert wait_for(lambda: command(node, 3e5, 3e5) or valves_at(sim, 3e5, 3e5))

    node.on_estop(msg.Bool(data=True))
    assert device.latched and node.vented
    assert wait_for(lambda: valves_at(sim, AMBIENT, AMBIENT))
    done, why = node.release()
    assert not done and interfaces.ESTOP.name in why  # refused while the stop is held
    node.on_estop(msg.Bool(data=False))  # no longer held, but still latched
    assert node.trigger_deactivate() == SUCCESS and node.trigger_activate() == SUCCESS
    assert device.latched
    assert lifecycle_status(node).level == diagnostics.WARN

    assert node.release()[0] and not device.latched
    assert wait_for(lambda: command(node, 2e5, 2e5) or valves_at(sim, 2e5, 2e5))
    assert lifecycle_status(node).level == diagnostics.OK
