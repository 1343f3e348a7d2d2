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
The simulated arm (hardware/sim_arm_bus.py), heard and spoken to as a host on a virtual CAN bus.

What it adds to the device contract (test_hw_device.py): the frames it sends (one sample frame
per segment per instant with one counter, ARM_STATUS every 100 instants, values saturated at the
DBC's range), its fault switches as they show on the bus, the host frames it takes or refuses,
and its own vent when the host's heartbeat stops. Real 1 kHz threads: the tests count instants
and frames, and every wait is bounded.
"""
import math
import os
import time

import can
from polling import wait_for
import pytest

from bellows_ros.hardware import can_protocol as cp
from bellows_ros.hardware.faults import Faults
from bellows_ros.hardware.sim_arm_bus import SimArmBus

pytestmark = pytest.mark.realtime  # runs alone, after the others (scripts/test.sh)

DB = cp.load_dbc()
N = 4
SAMPLE_IDS = [DB.get_message_by_name(f'ARM_SEG{i + 1}_SAMPLE').frame_id for i in range(N)]
STATUS_ID = DB.get_message_by_name('ARM_STATUS').frame_id
VENT = 101325.0  # Pa abs: what vented valves hold (the segment's p0)


class Ramp:
    """
    Plant stand-in: call k (from 1) returns values made of k, on the DBC's 15 Pa grid.

    Segment i reads p1 = 150 kPa + 15 k + 3 kPa i, p2 = 120 kPa + 15 k + 3 kPa i, psi = 1e-3 k
    - 0.5 + 0.1 i (k mod 1000), so a frame tells which instant and segment it carries.
    """

    def __init__(self):
        self.calls = 0

    @staticmethod
    def values(k):
        k %= 1000
        return [(150000.0 + 15 * k + 3000 * i, 120000.0 + 15 * k + 3000 * i,
                 1e-3 * k - 0.5 + 0.1 * i) for i in range(N)]

    def __call__(self, dt, setpoints):
        self.calls += 1
        return self.values(self.calls)


@pytest.fixture
def rig(request):
    """Make started simulated arms and host buses on one virtual channel; close them after."""
    made, hosts = [], []
    channel = f'sim-arm-test-{os.getpid()}-{request.node.name}'

    def make(plant=None, faults=None):
        sim = SimArmBus(can.Bus(interface='virtual', channel=channel), plant or Ramp(), N,
                        faults)
        made.append(sim)
        sim.start()
        return sim

    def host():
        bus = can.Bus(interface='virtual', channel=channel)
        hosts.append(bus)
        return bus
    make.channel, make.host = channel, host
    yield make
    for sim in made:
        sim.close()
    for bus in hosts:
        bus.shutdown()


def run(rig, instants, faults=None, plant=None):
    """Run a simulated arm for at least `instants` plant steps; return (sim, plant, frames)."""
    plant = plant or Ramp()
    host = rig.host()        # listening before the arm sends its first frame
    sim = rig(plant, faults)
    assert wait_for(lambda: plant.calls >= instants, timeout=30.0)
    sim.stop()               # joins the loop: every step's frames are on the bus now
    frames = []
    while (frame := host.recv(timeout=0)) is not None:
        frames.append(frame)
    return sim, plant, frames


def decode(frame):
    message = DB.get_message_by_frame_id(frame.arbitration_id)
    return message.decode(bytes(frame.data), decode_choices=False)


def test_each_instant_is_one_frame_per_segment_sharing_one_counter(rig):
    sim, plant, frames = run(rig, 250)
    ticks = plant.calls
    samples = [f for f in frames if f.arbitration_id != STATUS_ID]
    status = [f for f in frames if f.arbitration_id == STATUS_ID]
    assert len(samples) == N * ticks
    # after the sample frames of instants 0, 100, 200, ...
    assert [i for i, f in enumerate(frames) if f.arbitration_id == STATUS_ID] == \
        [(100 * j + 1) * N + j for j in range(math.ceil(ticks / 100))]
    checker = cp.FrameChecker(DB)
    now = time.monotonic()
    assert all(checker.check(f.arbitration_id, bytes(f.data), now) for f in frames)
    assert checker.lost == checker.replayed == 0  # every counter one more than the last
    for k in range(ticks):
        instant = samples[N * k:N * (k + 1)]
        assert [f.arbitration_id for f in instant] == SAMPLE_IDS
        for i, (frame, (p1, p2, psi)) in enumerate(zip(instant, Ramp.values(k + 1))):
            values = decode(frame)
            assert values['Counter'] == k % 256
            assert (values['P1'], values['P2']) == (p1, p2)  # exact: on the 15 Pa grid
            assert values['Psi'] == pytest.approx(psi, abs=5e-5)
    # never heard a host: the status frames say so, numbered by their own counter
    assert [decode(f)['Counter'] for f in status] == list(range(len(status)))
    assert all(decode(f)['HeartbeatLost'] == 1 for f in status)
    assert sim.health()['sent'] == len(frames)


class Beyond(Ramp):
    """Every signal beyond its DBC range, both ways: a real sensor saturates."""

    @staticmethod
    def values(k):
        return [(2e6, -1e4, 5.0)] + [(-1.0, 1.5e6, -5.0)] * (N - 1)


def test_sensor_values_saturate_at_the_dbc_range(rig):
    _, _, frames = run(rig, 5, plant=Beyond())
    first = [decode(f) for f in frames if f.arbitration_id == SAMPLE_IDS[0]]
    other = [decode(f) for f in frames if f.arbitration_id == SAMPLE_IDS[1]]
    assert first and other
    assert all((v['P1'], v['P2'], v['Psi']) == (983025, 0, 3.2767) for v in first)
    assert all((v['P1'], v['P2'], v['Psi']) == (0, 983025, -3.2768) for v in other)


def test_a_silent_arm_sends_nothing_and_counts_every_frame_it_held_back(rig):
    sim, plant, frames = run(rig, 150, Faults(silent=True))
    assert frames == []
    counts = sim.health()
    assert counts['sent'] == 0
    assert counts['dropped'] == N * plant.calls + math.ceil(plant.calls / 100)


def test_corrupted_frames_all_fail_the_hosts_crc_check(rig):
    sim, _, frames = run(rig, 100, Faults(corrupt_rate=1.0, seed=5))
    checker = cp.FrameChecker(DB)
    now = time.monotonic()
    assert frames and not any(checker.check(f.arbitration_id, bytes(f.data), now)
                              for f in frames)
    # one byte changed: CRC-8 catches every single-byte error, the CRC byte's own included
    assert checker.crc_errors + checker.malformed == len(frames)
    assert sim.health()['corrupted'] == sim.health()['sent'] == len(frames)


def test_a_replayed_frame_is_the_previous_sample_frame_again(rig):
    sim, plant, frames = run(rig, 100, Faults(replay_rate=1.0, seed=5))
    samples = [f for f in frames if f.arbitration_id != STATUS_ID]
    originals, replays = samples[:1] + samples[1::2], samples[2::2]
    # sent F1, F2, F1, F3, F2, ...: after each sample frame but the first, the one before it
    assert [f.arbitration_id for f in originals] == SAMPLE_IDS * plant.calls
    for k, replay in enumerate(replays):
        assert (replay.arbitration_id, replay.data) == \
            (originals[k].arbitration_id, originals[k].data)
    checker = cp.FrameChecker(DB)
    now = time.monotonic()
    accepted = [f for f in frames if checker.check(f.arbitration_id, bytes(f.data), now)]
    assert checker.replayed == len(replays) == sim.health()['replayed'] == N * plant.calls - 1
    assert len(accepted) == len(frames) - len(replays) and checker.lost == 0


def test_stuck_freezes_segment_1_chain_1_pressure_only_while_set(rig):
    plant = Ramp()
    host = rig.host()
    sim = rig(plant, Faults(stuck=True))
    assert wait_for(lambda: plant.calls >= 100, timeout=30.0)
    sim.faults.stuck = False  # at run time, as a test or node does
    released = plant.calls
    assert wait_for(lambda: plant.calls >= released + 100, timeout=30.0)
    sim.stop()
    rows = []
    while (frame := host.recv(timeout=0)) is not None:
        if frame.arbitration_id in SAMPLE_IDS[:2]:
            rows.append(decode(frame))
    seg1, seg2 = rows[0::2], rows[1::2]
    held = Ramp.values(1)[0][0]
    # instants 1-99 were sent before the switch was cleared (the 100th may race with it)
    assert all(v['P1'] == held for v in seg1[:99])
    # the other channels follow the plant meanwhile, and chain 1 again once released
    assert [v['P2'] for v in seg1[:99]] == [Ramp.values(k)[0][1] for k in range(1, 100)]
    assert [v['P1'] for v in seg2[:99]] == [Ramp.values(k)[1][0] for k in range(1, 100)]
    assert [v['P1'] for v in seg1[-50:]] == \
        [Ramp.values(k)[0][0] for k in range(len(seg1) - 49, len(seg1) + 1)]


def host_frame(name, values, counter):
    message = DB.get_message_by_name(name)
    return can.Message(arbitration_id=message.frame_id, is_extended_id=False,
                       data=cp.encode_frame(message, values, counter))


def test_host_frames_are_checked_like_on_the_driver_side(rig):
    sim = rig()
    host = rig.host()
    chambers = ['S1_P1', 'S1_P2', 'S2_P1', 'S2_P2']
    good = host_frame('ARM_SETPOINT_A', dict.fromkeys(chambers, 2e5), 1)
    bad = host_frame('ARM_SETPOINT_A', dict.fromkeys(chambers, 3e5), 2)
    bad.data[0] ^= 0x01  # one bit: the CRC no longer matches
    host.send(good)
    host.send(bad)
    # a frame with one of the arm's own IDs is not the host's: not checked, not counted
    host.send(can.Message(arbitration_id=SAMPLE_IDS[0], is_extended_id=False, data=bytes(8)))
    host.send(can.Message(arbitration_id=0x7FF, is_extended_id=False, data=bytes(8)))
    assert wait_for(lambda: sim.health()['rx_unknown_ids'] == 1)  # read in order: the last
    calls = sim.stats.count
    assert wait_for(lambda: sim.stats.count > calls + 5)  # a few ticks after the refusal
    counts = sim.health()
    assert (counts['rx_accepted'], counts['rx_crc_errors'], counts['rx_malformed']) == (1, 1, 0)
    assert 3e5 not in sim.setpoints
    # without a heartbeat the good set-points never reach the valves either: vented
    assert sim.vented and sim.setpoints == (VENT,) * (2 * N)


def test_arm_vents_on_its_own_when_the_host_heartbeat_stops(rig):
    sim = rig()
    db = cp.load_dbc()
    setpoint = db.get_message_by_name('ARM_SETPOINT_A')
    heartbeat = db.get_message_by_name('ARM_HOST_HEARTBEAT')
    status = db.get_message_by_name('ARM_STATUS')
    host = can.Bus(interface='virtual', channel=rig.channel)
    try:
        host.send(can.Message(arbitration_id=heartbeat.frame_id, is_extended_id=False,
                              data=cp.encode_frame(heartbeat, {'Enable': 1}, 1)))
        host.send(can.Message(arbitration_id=setpoint.frame_id, is_extended_id=False,
                              data=cp.encode_frame(setpoint, dict.fromkeys(
                                  ['S1_P1', 'S1_P2', 'S2_P1', 'S2_P2'], 3e5), 1)))
        assert wait_for(lambda: sim.setpoints[:4] == (3e5,) * 4)
        assert wait_for(lambda: max(sim.setpoints) < 1.02e5)   # no heartbeat follows: vented
        assert sim.health()['heartbeat_vents'] == 1
        checker, reported = cp.FrameChecker(db), None
        end = time.monotonic() + 5.0
        while reported != 1 and time.monotonic() < end:  # earlier status frames may still say 0
            frame = host.recv(timeout=0.1)
            if frame is not None and frame.arbitration_id == status.frame_id:
                checked = checker.check(frame.arbitration_id, frame.data, time.monotonic())
                if checked is not None:
                    reported = checked[1]['HeartbeatLost']
        assert reported == 1
    finally:
        host.shutdown()


def test_write_takes_set_points_as_a_host_would(rig):
    sim = SimArmBus(can.Bus(interface='virtual', channel=rig.channel), Ramp(), N)
    try:
        assert sim.vented  # never heard a host: vented until one speaks
        with pytest.raises(ValueError, match=f'expected {2 * N} pressure set-points, got 3'):
            sim.write([2e5] * 3)
        taken = sim.write([3e5, 5e4, math.nan, math.inf, -math.inf, VENT, 2e5, 4e5])
        # below ambient and non-finite: vented (the valves exhaust to ambient)
        assert taken == (3e5, VENT, VENT, VENT, VENT, VENT, 2e5, 4e5)
        sim.vent()
        assert sim.write([3e5] * (2 * N)) is None and sim.setpoints == (VENT,) * (2 * N)
        sim.release()
        assert sim.write([3e5] * (2 * N)) == (3e5,) * (2 * N)
        # Above what a set-point frame carries (the DBC's S*_P* maximum), not the samples' P1
        # range, which reaches higher.
        assert sim.write([9e5] * (2 * N)) == (819000.0,) * (2 * N)
    finally:
        sim.close()


def test_vented_chambers_hold_the_vent_pressure_given(rig):
    sim = SimArmBus(can.Bus(interface='virtual', channel=rig.channel), Ramp(), N,
                    vent_pressure=9.5e4)
    try:
        assert sim.setpoints == (9.5e4,) * (2 * N)
        assert sim.write([5e4] * (2 * N)) == (9.5e4,) * (2 * N)
    finally:
        sim.close()
