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
Arm CAN driver against the simulated arm.

python-can `virtual` in-process, `udp_multicast` between two processes. Real 1 kHz threads on a
shared machine: counts and ratios only; every wait is bounded.
"""
import dataclasses
import json
import os
import random
import subprocess
import sys
import time

import can
from polling import wait_for
import pytest

from bellows_ros.config.hardware import arm_bus_config
from bellows_ros.hardware.arm_bus import ArmBus, open_bus, open_can
from bellows_ros.hardware.faults import Faults
from bellows_ros.hardware.sim_arm_bus import SimArmBus

pytestmark = pytest.mark.realtime  # runs alone, after the others (scripts/test.sh)

CONFIG = arm_bus_config()
N = CONFIG.n_segments


class Pattern:
    """
    Deterministic plant stand-in: instant k (mod 1000) is written into every signal.

    Each segment has a different offset, so a sample mixing instants or carrying a corrupted value
    is recognisable. Pressures sit on the DBC's 15 Pa grid, so they decode exactly.
    """

    def __init__(self):
        self.k = 0

    def __call__(self, dt, setpoints):
        self.k += 1    # one call per instant sent, as the frame counter
        k = self.k % 1000
        return [(150000 + 15 * k + 3000 * i, 120000 + 15 * k + 3000 * i, 1e-3 * k - 0.5 + 0.1 * i)
                for i in range(N)]


def pattern_k(sample):
    """Return the tick (mod 1000) a sample claims; None if its values are not one instant."""
    k = round((sample.psi[0] + 0.5) / 1e-3)
    for i in range(N):
        expected = (150000 + 15 * k + 3000 * i, 120000 + 15 * k + 3000 * i)
        if sample.pressures[2 * i:2 * i + 2] != expected or \
                abs(sample.psi[i] - (1e-3 * k - 0.5 + 0.1 * i)) > 5e-5:
            return None
    return k


def check_stream(received):
    """Count the wrong samples: inconsistent values, or a tick not matching the index step."""
    bad = [s for s in received if pattern_k(s) is None]
    for a, b in zip(received, received[1:]):
        ka, kb = pattern_k(a), pattern_k(b)
        if ka is not None and kb is not None and (kb - ka) % 1000 != (b.index - a.index) % 1000:
            bad.append((a, b))
    for item in bad[:5]:
        print('wrong:', item)
    return len(bad)


@pytest.fixture
def rig(request):
    made = []
    channel = f'arm-test-{os.getpid()}-{request.node.name}'

    def make(faults=None, on_sample=None, driver=True):
        sim = SimArmBus(can.Bus(interface='virtual', channel=channel), Pattern(), N, faults)
        sim.start()
        made.append(sim)
        if not driver:
            return sim, None
        arm = ArmBus(dataclasses.replace(CONFIG, interface='virtual', channel=channel),
                     on_sample=on_sample)
        made.append(arm)
        arm.start()
        assert wait_for(lambda: arm.read() is not None), 'no samples from the simulated arm'
        return sim, arm

    make.channel = channel
    yield make
    for thing in reversed(made):
        thing.close()


class StallingPattern(Pattern):
    """`Pattern` whose plant stalls the simulated arm once for `stall` s, at instant 200."""

    def __init__(self, stall):
        super().__init__()
        self.stall, self.dts = stall, []

    def __call__(self, dt, setpoints):
        self.dts.append(dt)
        if len(self.dts) == 200:
            time.sleep(self.stall)
        return super().__call__(dt, setpoints)


def test_a_stalled_arm_takes_every_sample_it_missed(rig):
    # A late tick that stepped the plant by the whole delay and sent one row squeezed the delay
    # into one sample period of the driver's time base (index x period).
    channel = rig.channel
    plant = StallingPattern(0.5)
    sim = SimArmBus(can.Bus(interface='virtual', channel=channel), plant, N)
    received = []
    arm = ArmBus(dataclasses.replace(CONFIG, interface='virtual', channel=channel),
                 on_sample=received.append)
    arm.start()
    sim.start()
    try:
        assert wait_for(lambda: len(plant.dts) > 1000, timeout=60.0)
    finally:
        sim.close()
        arm.close()
    assert max(plant.dts) < 1.5 * sim.period  # every plant step one sample period
    assert check_stream(received) == 0
    # The driver's index counts the instants: every one the plant stepped, less those in flight.
    assert received[-1].index - received[0].index >= 0.9 * len(plant.dts)


@pytest.mark.slow
def test_corrupt_and_replayed_frames_never_reach_the_user(rig):
    received = []
    sim, arm = rig(faults=Faults(corrupt_rate=0.005, replay_rate=0.01, seed=3),
                   on_sample=received.append)
    ticks_before = sim.stats.count
    received.clear()
    # 3000 instants, however long a loaded machine takes to send them
    assert wait_for(lambda: sim.stats.count - ticks_before >= 3000, timeout=60.0)
    sim.stop()
    sent = sim.stats.count - ticks_before   # instants the arm sent while we counted
    counts = arm.health()
    assert check_stream(received) == 0
    # One lost frame of four loses the instant: ~2 % of instants at 0.5 % corrupted frames.
    assert len(received) / sent >= 0.9
    assert counts['crc_errors'] > 0 and counts['replayed'] > 0
    assert counts['crc_errors'] + counts['malformed'] >= 0.5 * sim.health()['corrupted']


def test_pressure_setpoints_are_clamped_and_counted(rig):
    sim, arm = rig()
    command = [8e5, 5e4, float('nan'), 3e5, 2e5, 2e5, 2e5, 7.5e5][:2 * N]
    sent = arm.write(command)
    assert sent[:4] == [CONFIG.pressure_max, CONFIG.pressure_min, CONFIG.pressure_min, 3e5]
    counts = arm.health()
    assert counts['clamped_setpoints'] == 2 and counts['invalid_setpoints'] == 1
    # What the valves apply, through the DBC's 200 Pa resolution:
    assert wait_for(lambda: sim.setpoints[0] == CONFIG.pressure_max)
    assert max(sim.setpoints) <= CONFIG.pressure_max
    assert sim.setpoints[1] == pytest.approx(CONFIG.pressure_min, abs=100)
    assert sim.setpoints[3] == 3e5
    with pytest.raises(ValueError):
        arm.write([2e5] * 3)


def test_watchdog_vents_when_commands_stop(rig):
    sim, arm = rig()
    end = time.monotonic() + 0.3
    while time.monotonic() < end:
        arm.write([3e5] * (2 * N))
        time.sleep(0.01)
    assert wait_for(lambda: sim.setpoints == (3e5,) * (2 * N))
    assert arm.health()['watchdog_vents'] == 0
    assert wait_for(lambda: max(sim.setpoints) < 1.02e5)
    assert arm.health()['watchdog_vents'] == 1


def test_silent_arm_goes_stale_and_comes_back(rig):
    sim, arm = rig()
    sim.faults.silent = True
    assert wait_for(lambda: arm.stale)
    assert arm.read() is None
    sim.faults.silent = False
    assert wait_for(lambda: arm.read() is not None)


CHILD = r"""
import sys, time, json
from bellows_ros.hardware.arm_bus import open_can
from bellows_ros.hardware.sim_arm_bus import SimArmBus
sys.path.insert(0, sys.argv[4])
from test_hw_arm_bus import Pattern
group, port, instants = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
sim = SimArmBus(open_can('udp_multicast', group, port=port), Pattern())
sim.start()
end = time.monotonic() + 60.0   # however long a loaded machine takes, but bounded
while sim.stats.count < instants and time.monotonic() < end:
    time.sleep(0.05)
setpoints = sim.setpoints
sim.close()
print(json.dumps({'setpoints': setpoints, 'counters': sim.health(),
                  'ticks': sim.stats.count, 'misses': sim.stats.misses}), flush=True)
"""


@pytest.mark.slow
def test_four_segments_at_1khz_between_two_processes_over_udp_multicast():
    group, port = '239.74.163.2', 40000 + os.getpid() % 20000  # own port: parallel runs stay apart
    config = dataclasses.replace(CONFIG, interface='udp_multicast', channel=group)
    received = []
    arm = ArmBus(config, bus=open_bus(config, port=port), on_sample=received.append)
    arm.start()
    child = subprocess.Popen([sys.executable, '-c', CHILD, group, str(port), '3000',
                              os.path.dirname(__file__)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 90.0
        while child.poll() is None and time.monotonic() < deadline:
            arm.write([2e5] * (2 * N))
            time.sleep(0.005)
        out, err = child.communicate(timeout=10)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
        arm.close()
    assert child.returncode == 0, err
    report = json.loads(out.strip().splitlines()[-1])
    assert report['ticks'] >= 3000
    assert len(received) > 1000, f'only {len(received)} samples arrived'
    assert check_stream(received) == 0
    # The driver listened before the child started and until it ended: every instant counts.
    assert len(received) / report['ticks'] >= 0.98, (len(received), report, arm.health())
    assert report['setpoints'] == [2e5] * (2 * N)   # the other direction worked too
    assert report['counters']['rx_accepted'] > 0


def test_a_reader_that_falls_behind_knows_when_its_frames_arrived():
    """
    A sample read late from the socket carries the time its frames arrived, not when it was read.

    The driver stamps from it (`sample_delivery.arrival_ns`): stamped when read, a backlog of
    0.5-1.5 s behind a starved reader went out as fresh samples and the arm controller acted on
    them (bench_results/0.1.0/notebook.md, 2026-11-26).
    """
    port = 45000 + random.randint(0, 999)
    group = '239.74.166.13'
    read = []
    stall = 0.3

    def on_sample(sample):
        read.append((time.time(), sample))
        if len(read) == 200:
            time.sleep(stall)  # the reader is not scheduled: frames wait in the kernel's buffer
    sim = SimArmBus(open_can('udp_multicast', group, port=port), Pattern(), N)
    arm = ArmBus(dataclasses.replace(CONFIG, interface='udp_multicast', channel=group),
                 bus=open_can('udp_multicast', group, port=port), on_sample=on_sample)
    arm.start()
    sim.start()
    try:
        assert wait_for(lambda: len(read) > 600, timeout=60.0), f'{len(read)} samples'
    finally:
        sim.close()
        arm.close()
    assert all(s.t_arrival is not None for _, s in read)  # udp_multicast: kernel timestamps
    # Frames never arrive after they are read, and the first read after the stall waited the
    # stall in the socket (less the sample period it was taken in).
    assert all(s.t_arrival <= t for t, s in read)
    assert read[200][0] - read[200][1].t_arrival >= stall - 0.05, read[200]
    # The backlog waited in the socket: of the 100 samples read after the stall, at least half
    # had arrived 50 ms or more before they were read (at 1 kHz, 300 were sent during it).
    assert sum(t - s.t_arrival >= 0.05 for t, s in read[200:300]) >= 50
    assert check_stream([s for _, s in read]) == 0
