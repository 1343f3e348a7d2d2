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
The driver's side of each device (nodes/device_topics.py): samples to messages, commands in.

Each kind is made as driver_node makes it (`make(given, hardware_params, on_sample)`), on
python-can's in-process `virtual` bus or a port path that exists, and never started: the
conversions are fed known samples and their serialized messages read back (runtime/
joint_state_cdr.py). The arm's clock settings (`ARM_CLOCK`) are held to what the module says of
them, on `sample_delivery.DeviceClock`.
"""
import math
import os
from types import SimpleNamespace

import pytest

from bellows_ros import interfaces
from bellows_ros.config.hardware import arm_bus_config
from bellows_ros.errors import BellowsError
from bellows_ros.hardware.actuator_board import ActuatorBoard, ActuatorSample
from bellows_ros.hardware.arm_bus import ArmBus, ArmSample
from bellows_ros.hardware.sample_delivery import DeviceClock
from bellows_ros.nodes.device_topics import (ActuatorTopics, ARM_CLOCK, ArmTopics, KINDS,
                                             SampleClock)
from bellows_ros.runtime.joint_state_cdr import JointStateReader

MS = 1_000_000  # ns
NOW = 1_800_000_000_000_000_000  # ns on the node clock
P0 = arm_bus_config().pressure_min  # Pa abs: what vented chambers hold


def given(values):
    """Return driver_node's parameter values, as `declare_specs` gives them, with `values`."""
    return {'arm.interface': '', 'arm.channel': '', 'arm.n_segments': 0, 'actuator.port': '',
            'startup_timeout': 2.0, **values}


@pytest.fixture
def arm(request):
    """Yield ArmTopics made on a `virtual` CAN channel of this test's own, two segments."""
    topics = ArmTopics()
    channel = f'device-topics-{os.getpid()}-{request.node.name}'
    device = topics.make(given({'arm.interface': 'virtual', 'arm.channel': channel,
                                'arm.n_segments': 2}), None, None)
    yield topics, device
    device.close()


def read(serialized):
    return JointStateReader()(serialized)


def nan_at(values, indices):
    return all(math.isnan(values[k]) for k in indices)


def test_the_kinds_are_the_arm_then_the_actuator_each_on_its_own_sample_topic():
    assert [kind.name for kind in KINDS] == ['arm', 'actuator']
    assert ArmTopics.sample_topic is interfaces.JOINT_STATES
    assert ActuatorTopics.sample_topic is interfaces.ACTUATOR_JOINT_STATES
    assert (ArmTopics.command_topic, ActuatorTopics.command_topic) == (
        interfaces.PRESSURE_COMMAND, interfaces.MOTOR_COMMAND)
    # only the arm says on a latched topic when it is vented
    assert (ArmTopics.vented_topic, ActuatorTopics.vented_topic) == (interfaces.VENTED, None)


def test_a_gap_in_the_sample_index_counts_the_missed_samples_and_their_lateness():
    clock = SampleClock(1e-3)
    clock.tick(10, 0.0, 1e-5)
    clock.tick(11, 1e-3, 1e-5)
    clock.tick(14, 5e-3, 1e-5)    # samples 12 and 13 never came; 14 arrived 1 ms late
    summary = clock.stats.summary()
    assert (clock.stats.count, clock.stats.misses) == (2, 2)
    assert clock.frequency.count == 3
    assert summary['period_max'] == pytest.approx(4e-3)
    assert summary['lateness_max'] == pytest.approx(1e-3)
    assert summary['lateness_p50'] == pytest.approx(0.5e-3)  # the on-time one: 0


def test_the_arm_message_holds_angles_rates_and_pressures_on_the_arms_clock(arm):
    topics, device = arm
    assert isinstance(device, ArmBus) and device.link.startswith('virtual:')
    names = interfaces.arm_sample_names([1, 2])
    first = ArmSample(t_receive=1.0, index=7, t_device=7e-3, psi=(0.1, -0.2),
                      pressures=(2e5, 3e5, 4e5, 5e5))
    second = ArmSample(t_receive=1.001, index=8, t_device=8e-3, psi=(0.102, -0.203),
                       pressures=(2.1e5, 3e5, 4e5, 5e5))
    one, two = read(topics.message(first, NOW)), read(topics.message(second, NOW + MS))
    assert one.name == two.name == names
    # the first arrival anchors the arm's time on the node clock; the next is 1 ms of arm time on
    assert (one.stamp_ns, two.stamp_ns) == (NOW, NOW + MS)
    assert one.position[:2] == (0.1, -0.2) and nan_at(one.position, range(2, 6))
    assert one.effort[2:] == (2e5, 3e5, 4e5, 5e5) and nan_at(one.effort, range(2))
    # Ψ̇: none before the second sample, then the backward difference over the arm's time
    assert one.velocity[:2] == (0.0, 0.0) and nan_at(one.velocity, range(2, 6))
    assert two.velocity[:2] == pytest.approx((2.0, -3.0))


def test_an_arm_command_starts_vented_and_a_partial_one_keeps_the_other_set_points(arm):
    topics, _ = arm
    assert topics.chain_names == interfaces.arm_sample_names([1, 2])[2:]
    command = SimpleNamespace(name=['segment_2/chain_1', 'segment_9/chain_1', 'segment_1/chain_2'],
                              effort=[4e5, 6e5, 3e5])
    # the unknown chamber is ignored; the ones not named stay vented
    assert topics.command(command) == [P0, 3e5, 4e5, P0]
    command = SimpleNamespace(name=['segment_1/chain_1'], effort=[2e5])
    assert topics.command(command) == [2e5, 3e5, 4e5, P0]


def test_a_can_bus_that_cannot_be_opened_is_one_error_naming_it():
    # udp_multicast refuses a channel that is no multicast group before making any socket
    with pytest.raises(BellowsError, match=r'^driver_node: cannot open CAN bus '
                       r'udp_multicast:not-a-group \(.*multicast'):
        ArmTopics().make(given({'arm.interface': 'udp_multicast', 'arm.channel': 'not-a-group'}),
                         None, None)


def test_the_actuator_message_holds_compressions_force_and_pressure(tmp_path):
    port = tmp_path / 'board'
    port.touch()  # make() waits for the path only; the board is not started here
    topics = ActuatorTopics()
    device = topics.make(given({'actuator.port': str(port)}), None, None)
    try:
        assert isinstance(device, ActuatorBoard) and device.link == str(port)
        sample = ActuatorSample(t_receive=1.0, t_device=0.25, index=250, encoder_counts=0,
                                x_c=0.004, x_s=0.002, p=1.5e5, f=6.5, status=0)
        message = read(topics.message(sample, NOW))
        later = read(topics.message(
            ActuatorSample(1.002, 0.252, 252, 0, 0.0041, 0.002, 1.5e5, 6.5, 0), NOW + 2 * MS))
    finally:
        device.close()
    assert message.name == interfaces.actuator_sample_names() == (
        'air_chamber', 'spring', 'actuator')
    assert message.position[:2] == (0.004, 0.002) and math.isnan(message.position[2])
    assert message.velocity == ()  # no rates are sent
    assert message.effort[1:] == (6.5, 1.5e5) and math.isnan(message.effort[0])
    assert (message.stamp_ns, later.stamp_ns) == (NOW, NOW + 2 * MS)
    assert topics.command(SimpleNamespace(data=-0.3)) == -0.3  # a motor duty passes as sent


def test_an_actuator_port_still_absent_after_the_startup_timeout_is_an_error_naming_it(
        tmp_path):
    port = tmp_path / 'no_board'
    with pytest.raises(BellowsError) as refused:
        ActuatorTopics().make(given({'actuator.port': str(port), 'startup_timeout': 0.05}),
                              None, None)
    assert str(refused.value) == (f'driver_node: actuator board port {port} does not exist after '
                                  '0.05 s (device absent? set actuator.port)')


# --- the arm's clock (ARM_CLOCK) on sample_delivery.DeviceClock -----------------------------

def test_the_arms_clock_follows_an_oscillator_off_by_half_a_percent():
    """
    The arm's time is its sample count times 1 ms: its oscillator's error is drift on the host.

    On timed arrivals (`device_topics.ARM_CLOCK[True]`) samples from an arm whose clock is 0.5 %
    slow or fast keep ages under a millisecond over 5 minutes: with 100 ppm they grew past
    `max_sample_age` within a minute, and the arm controller took no sample.
    """
    ms = 1_000_000
    for error in (0.005, -0.005):
        clock = DeviceClock(**ARM_CLOCK[True])
        ages = []
        for k in range(0, 300_000, 10):
            arrival = round(k * ms * (1 + error)) + 2 * ms + (k % 7) * 20_000  # jitter 0-0.12 ms
            ages.append(arrival - clock.stamp(k * ms, arrival))
        assert max(ages[1000:]) < ms and min(ages) >= 0, (error, max(ages))


def test_the_untimed_arms_clock_takes_a_new_base_after_an_outage():
    """
    Without timestamps on the host clock (`ARM_CLOCK[False]`): an outage of over 256 ms.

    The 8-bit frame counter leaves the arm's time 256 ms behind: without a new base every later
    sample would look 256 ms old, and the arm would stay vented. After `settle` it is taken; a
    reader stalled for 1.5 s meanwhile (read times late, then a burst) keeps its base.
    """
    untimed = ARM_CLOCK[False]
    ms = 1_000_000
    clock = DeviceClock(**untimed)
    for k in range(1000):
        clock.stamp(k * ms, k * ms + 3 * ms)
    # a stall: 1.5 s of samples read at once, then on time again
    burst = [clock.stamp(k * ms, 2503 * ms + (k - 1000) * 20_000) for k in range(1000, 2500)]
    # their own times, so they are as old as they are (within the drift allowance of the
    # burst's last `resync`)
    assert max(abs(b - (k * ms + 3 * ms)) for k, b in zip(range(1000, 2500), burst)) <= (
        untimed['drift'] * untimed['resync'] * 1e9)
    for k in range(2500, 3000):
        assert clock.stamp(k * ms, k * ms + 3 * ms) == k * ms + 3 * ms
    # an outage of 300 ms counted as one instant: the arm's time 256 ms behind the truth
    late = [clock.stamp(k * ms, (k + 256) * ms + 3 * ms) for k in range(3000, 6000)]
    ages = [(k + 256) * ms + 3 * ms - s for k, s in zip(range(3000, 6000), late)]
    moved = ages.index(0)
    assert ages[0] == 256 * ms and moved == untimed['settle'] * 1000
    assert set(ages[moved:]) == {0}


def test_device_clock_on_timed_arrivals_follows_a_time_base_that_moved():
    """
    The arm's clock (`device_topics.ARM_CLOCK[True]`): arrivals timed by the bus, not the reader.

    An outage the arm's 8-bit frame counter could not count leaves its time base behind by the
    outage: the clock takes the new base after `settle`. A simulated arm that paused and sent its
    backlog at once keeps its base: those samples are as old as they are.
    """
    timed = ARM_CLOCK[True]
    ms, settle = 1_000_000, int(timed['settle'] * 1e9)
    clock = DeviceClock(**timed)
    assert [clock.stamp(k * ms, k * ms + 5 * ms) for k in range(100)][-1] == 104 * ms
    # 1.3 s without frames, counted as one instant: the device's time goes on from 100 ms.
    device = [(100 + k) * ms for k in range(2000)]
    arrivals = [(1400 + k) * ms + 5 * ms for k in range(2000)]
    stamps = [clock.stamp(d, a) for d, a in zip(device, arrivals)]
    # at first the old base (+ its drift allowance): these look 1.3 s old
    assert abs(stamps[0] - (device[0] + 5 * ms)) <= timed['drift'] * ms
    moved = next(k for k, (s, a) in enumerate(zip(stamps, arrivals)) if s == a)
    assert device[moved] - device[0] == settle  # after `settle` of device time, the new base
    assert stamps[moved:] == arrivals[moved:]
    # A pause of 0.5 s, then its 500 samples at once and on time again: the base does not move.
    clock = DeviceClock(**timed)
    for k in range(100):
        clock.stamp(k * ms, k * ms + 5 * ms)
    burst = [clock.stamp(k * ms, 605 * ms + k * 10_000) for k in range(100, 600)]
    after = [clock.stamp(k * ms, k * ms + 5 * ms) for k in range(600, 3000)]
    # (within the burst's last `resync` the offset may rise by its drift allowance: 0.5 ms)
    assert max(abs(a - (k * ms + 5 * ms)) for k, a in zip(range(100, 600), burst)) <= (
        timed['drift'] * timed['resync'] * 1e9)
    assert after == [k * ms + 5 * ms for k in range(600, 3000)]
