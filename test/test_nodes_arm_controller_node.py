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
arm_controller_node in the test's process: it never commands from an old sample.

The samples are handed to the node's own callbacks, stamped in the past or now on the node's
clock; what it publishes is read back by a peer node.
"""
import math
import time

import probe
import pytest

from bellows_ros import interfaces
from bellows_ros.config.segment import load_segment_params
from bellows_ros.nodes import diagnostics
from bellows_ros.nodes.arm_controller_node import ArmControllerNode, ArmControllerTask

pytestmark = pytest.mark.realtime  # runs alone, after the others (scripts/test.sh)

MS = 1_000_000  # ns


@pytest.fixture
def controller(monkeypatch):
    monkeypatch.setenv('ROS_DOMAIN_ID', '196')
    probe.init()
    node = probe.adopt(ArmControllerNode())
    peer = probe.Node('peer')
    commands = []
    peer.create_subscription(probe.msg.JointState, interfaces.PRESSURE_COMMAND.resolved(),
                             commands.append, interfaces.COMMAND_DEPTH)
    yield node, peer, commands
    probe.shutdown()


def feed(node, stamps, psi=0.1):
    """
    Hand `node` one sample of segment 1 at angle `psi` rad per stamp (ns).

    A stamp of None is the node clock's present: a sample as young as it can be, however slowly a
    loaded machine runs this loop.
    """
    p0 = load_segment_params().p0
    for stamp in stamps:
        stamp = node.get_clock().now().nanoseconds if stamp is None else stamp
        node.control(probe.as_received(
            probe.arm_sample(stamp, [psi], [0.0], [p0 + 1e5, p0 + 1e5])))


def vent_and_resume(node, psi):
    """
    Hold 0.1 rad, let the driver vent, then resume on a segment fallen to `psi` rad.

    Young samples at 0.1 rad (the held angle: 4 commands), no command for longer than the
    command watchdog (the driver vents), then young samples at `psi`: the controller resumes.
    """
    # (a stall of this test process, on a shared machine, while it feeds is no vent)
    watchdog, node.watchdog_ns = node.watchdog_ns, 10 ** 12
    feed(node, [None] * 20)  # holds the first sample's angle, 0.1 rad
    node.watchdog_ns = watchdog
    assert node.counts['commands'] == 4 and node.loops[0].setpoint[0] == pytest.approx(0.1)
    time.sleep(1.5 * interfaces.COMMAND_WATCHDOG)  # no command: the driver vents, the arm falls
    feed(node, [None] * 5, psi=psi)
    assert node.counts['restarts'] == 1


def test_samples_older_than_max_sample_age_get_no_command_and_say_so(controller):
    node, peer, commands = controller
    task = ArmControllerTask(node)
    max_age = node.get_parameter('max_sample_age').value
    now = node.get_clock().now().nanoseconds
    # A backlog: 100 samples taken 1 s ago, 1 ms apart, handed over now.
    feed(node, [now - 1000 * MS + k * MS for k in range(100)])
    assert node.counts['commands'] == 0
    assert node.counts['stale_skipped'] == 100 // node.control_every
    [status] = task.statuses()
    assert status.level == diagnostics.ERROR, status.message
    assert 'too old to act on' in status.message and '20 skipped' in status.message
    assert float(status.get('sample_age_p50_us')) > 1e6 * max_age

    # Fresh samples are commanded from, and the peer gets those commands.
    feed(node, [None] * 20)
    assert node.counts['commands'] == 20 // node.control_every
    for _ in range(100):
        if len(commands) == node.counts['commands']:
            break
        probe.spin_once(peer, timeout_sec=0.05)
    assert len(commands) == node.counts['commands']
    [status] = task.statuses()
    assert status.level != diagnostics.ERROR, status.message


def test_after_a_vent_the_set_point_moves_back_from_where_the_segment_fell(controller):
    """
    The resumption is not a step: from the measured angle, a half-cosine at `resume_speed`.

    A step of 0.7 rad overshot by 0.37-0.73 rad on drawn segments, a move at 0.5 rad/s peak by
    0.006-0.034 rad (bench_results/0.1.0/notebook.md, 2026-11-26).
    """
    node, peer, commands = controller
    [loop] = node.loops
    speed = node.get_parameter('resume_speed').value
    vent_and_resume(node, psi=-0.3)
    assert loop.setpoint[0] == pytest.approx(-0.3, abs=1e-3)  # where it fell, not 0.4 rad away
    # The move back, on the samples' time (1 ms apart, or later if this loop runs slower: never
    # stale): each command's set-point is the half-cosine from -0.3 to 0.1 rad at its stamp.
    start, offset, duration = loop.resume
    assert offset == pytest.approx(-0.4, abs=1e-3)
    assert duration == pytest.approx(abs(offset) * math.pi / (2 * speed))
    # From here the move is timed on the samples' stamps: a stall of this (shared) test process
    # between two feeds must not count as another vent.
    node.watchdog_ns = 10 ** 12
    seen, stamp, k = [], round(start * 1e9), 0
    while stamp * 1e-9 < start + 1.2 * duration:
        k += 1
        stamp = max(node.get_clock().now().nanoseconds, round((start + k * 1e-3) * 1e9))
        before = node.counts['commands']
        feed(node, [stamp], psi=-0.3)
        if node.counts['commands'] > before:
            seen.append((stamp * 1e-9, loop.setpoint))
    for t, (psi_d, psi_dot_d, _) in seen:
        phase = math.pi * min(1.0, (t - start) / duration)
        assert psi_d == pytest.approx(0.1 + offset * 0.5 * (1 + math.cos(phase)), abs=1e-6)
        assert 0.0 <= psi_dot_d <= speed * (1 + 1e-9)
    assert max(v for _, (_, v, _) in seen) > 0.9 * speed  # the peak speed is reached ...
    assert seen[-1][1][:2] == (pytest.approx(0.1), 0.0)  # ... and done


def test_a_latched_vent_restarts_from_where_the_segment_fell_though_commands_never_stopped(
        controller):
    """
    The driver refuses commands while a vent is latched; this node keeps commanding (no gap).

    While the driver says `bellows/vented` True, every command starts from the measured angle
    with a fresh integral; released, the set-point moves back from there, not in a step.
    """
    node, peer, commands = controller
    [loop] = node.loops
    feed(node, [None] * 20)  # holds the first sample's angle, 0.1 rad
    node.on_vented(probe.msg.Bool(data=True))
    feed(node, [None] * 50, psi=-0.3)   # the segment falls while the vent lasts
    assert node.counts['restarts'] == 1 and node.counts['commands'] == 14
    assert loop.setpoint[0] == pytest.approx(-0.3, abs=1e-3)
    assert loop.tracker.integral == pytest.approx(0.0, abs=1e-9)
    node.on_vented(probe.msg.Bool(data=False))
    feed(node, [None] * 5, psi=-0.3)
    start, offset, duration = loop.resume
    assert offset == pytest.approx(-0.4, abs=1e-3) and node.counts['restarts'] == 1
    assert loop.setpoint[0] == pytest.approx(-0.3, abs=0.01)  # leaving -0.3 for 0.1, slowly


def test_a_joint_trajectory_taken_while_resuming_does_not_jump(controller):
    """A trajectory spliced in during the move back keeps the set-point continuous."""
    node, peer, commands = controller
    [loop] = node.loops
    vent_and_resume(node, psi=-0.3)
    assert loop.resume is not None
    before = loop.desired(node.last_stamp * 1e-9)[0]
    msg = probe.msg
    node.on_trajectory(msg.JointTrajectory(joint_names=['segment_1'], points=[
        msg.JointTrajectoryPoint(positions=[0.5], velocities=[0.0],
                                 time_from_start=msg.Duration(sec=2, nanosec=0))]))
    assert node.counts['trajectories'] == 1
    after = loop.desired(node.last_stamp * 1e-9)[0]
    assert after == pytest.approx(before, abs=1e-9)  # the set-point where it was, -0.3 rad
    assert before == pytest.approx(-0.3, abs=1e-3)
    # ... and the trajectory's end is still reached: offset faded, path at its last point.
    assert loop.desired(node.last_stamp * 1e-9 + 5.0)[0] == pytest.approx(0.5)
