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
Acceptance: the arm controller tracks an angle trajectory on the simulated arm over ROS 2.

Processes: sim_arm_node (paper A's full physics, sensor noise, valve lag; udp_multicast CAN),
driver_node (arm only), arm_controller_node (paper A feedforward, config/nodes_sim.yaml gains).
The test publishes /arm/psi_setpoint for segment_1 (the built-in `sweep`: ±0.7 rad moves with
holds, at 50 Hz, like the scenario) and records segment_1's measured angle from /joint_states.

Criteria: the segment really moves (a vented segment rests at Ψ ≈ 0; the sweep asks for ±0.7 rad),
the angle follows the set-point (RMS error over the sweep below 0.05 rad, the hold angles within
0.02 rad at their ends), the controller's /diagnostics report its tracking error and commands, and
the driver's watchdog vented the arm while it tracked only after a stall the controller measured
(the controller keeps publishing at its rate; a stall of the shared host is not the code's: such a
vent and the controller's move back after it are left out of the error, and may not take more than
30 % of the sweep).
"""
import math
import random
import time

from node_processes import free_domain, launch_arm, node_env, override, SIM_CONFIG, stop_all
import probe
import pytest

from bellows_ros import interfaces

from bellows_ros.config.hardware import arm_bus_config
from bellows_ros.control import angle_trajectory
from bellows_ros.io import params
from bellows_ros.runtime.messages import msg

pytestmark = pytest.mark.realtime  # runs alone, after the others (scripts/test.sh)


def interpolate(points, t):
    """Value of a (time, value) series at `t` (the last value at or before it)."""
    before = [v for s, v in points if s <= t]
    return before[-1] if before else math.nan


def after_vents(vented, angle, setpoints, resume_speed):
    """
    Return the (start, end) times of each vent and the controller's move back after it.

    `vented`: (time, bool) from bellows/vented. A vent lasts until a command takes again; the
    set-point then moves back from where the segment fell, in a half-cosine of peak speed
    `resume_speed` rad/s (arm_controller_node's `resume_speed`), and 0.5 s settles the gains.
    """
    spans, start = [], None
    for t, on in vented:
        if on and start is None:
            start = t
        elif not on and start is not None:
            offset = interpolate(angle, t) - interpolate(setpoints, t)
            spans.append((start, t + abs(offset) * math.pi / (2.0 * resume_speed) + 0.5))
            start = None
    if start is not None:
        spans.append((start, math.inf))
    return spans


@pytest.mark.slow
@pytest.mark.timeout(150)
def test_arm_controller_tracks_on_the_simulated_arm(tmp_path, monkeypatch):
    # A domain and CAN group of its own: the other graph tests and launch_sim.sh use 201-230 and
    # 239.74.163.x, and a second arm's /joint_states would be taken for this one's.
    domain = free_domain()
    group = f'239.74.171.{random.randint(2, 250)}'
    monkeypatch.setenv('ROS_DOMAIN_ID', domain)
    env = node_env(ROS_DOMAIN_ID=domain)
    trajectory = angle_trajectory.SWEEP
    processes = launch_arm(env, group, tmp_path,
                           override('arm_controller_node', 'feedforward', 'paper_a'))
    angle, setpoints, controller, driver, vented = [], [], [], [], []
    stopping = None  # the driver's last report may follow the controller's exit: not counted

    def on_diagnostics(array):
        for status in array.status:
            values = {kv.key: kv.value for kv in status.values}
            if status.name == 'arm_controller_node: segment_1':
                controller.append((time.monotonic(), values))
            elif status.name == 'driver_node: arm' and stopping is None:
                driver.append((time.monotonic(), values))
    try:
        probe.init()
        node = probe.Node('arm_control_acceptance')
        publisher = node.create_publisher(msg.JointState, '/arm/psi_setpoint', 10)
        node.create_subscription(
            msg.JointState, '/joint_states',
            lambda m: angle.append((m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec,
                                    m.position[m.name.index('segment_1')]))
            if 'segment_1' in m.name else None, 200)
        node.create_subscription(msg.DiagnosticArray, '/diagnostics', on_diagnostics, 50)
        node.create_subscription(msg.Bool, interfaces.VENTED.resolved(),
                                 lambda m: vented.append((time.time(), m.data)), 10)
        # Before the sweep: samples flowing, a driver report (so that a vent counted by then
        # belongs to the start-up), and the controller following this test's set-point. That the
        # publisher has matched the controller's reader is not enough: the reader may match the
        # writer later, and drops what comes before (once, in CI, the sweep's first second was
        # lost; the set-point then stepped from the held angle to mid-move, an overshoot to
        # 0.81 rad of the gains, not tracking). So the sweep's first set-point is sent until
        # /diagnostics says the controller follows the topic.
        psi_0, _, _ = angle_trajectory.setpoint(trajectory, 0.0)
        next_send = time.monotonic()
        end = next_send + 30
        while (len(angle) < 500 or not driver or not controller
               or controller[-1][1].get('source') != 'topic') and time.monotonic() < end:
            if time.monotonic() >= next_send:
                publisher.publish(msg.JointState(name=['segment_1'], position=[psi_0],
                                                 velocity=[0.0]))
                next_send = time.monotonic() + 0.02
            probe.spin_once(node, timeout_sec=0.02)
        assert angle, 'no /joint_states from the graph'
        assert publisher.get_subscription_count() == 1, 'the controller never subscribed'
        assert controller and controller[-1][1].get('source') == 'topic', \
            'the controller never followed the set-point topic'
        # Both series on the system clock: the angle at the driver's stamp (the instant the arm
        # sampled it), the set-point at its sending. This process's own delays (a garbage
        # collection of the test session, a backlog of /joint_states) then shift neither.
        start, first_setpoint = time.monotonic(), None
        total = angle_trajectory.duration(trajectory) + 1.0
        next_send = start
        while time.monotonic() < start + total:
            now = time.monotonic()
            if now >= next_send:
                psi_d, psi_dot_d, _ = angle_trajectory.setpoint(trajectory, now - start)
                publisher.publish(msg.JointState(name=['segment_1'], position=[psi_d],
                                                 velocity=[psi_dot_d]))
                setpoints.append((time.time(), psi_d))
                first_setpoint = first_setpoint or now
                next_send += 0.02
            probe.spin_once(node, timeout_sec=0.005)
    finally:
        stopping = time.monotonic()
        stop_all(processes)
        probe.shutdown()
    logs = '\n'.join(p.read_text()[-800:] for p in tmp_path.glob('*.log'))

    # No vent while tracking that the controller did not see coming: a vent is right when the
    # commands stop for longer than the watchdog, and on two shared cores a stall of the host can
    # do that. The controller measures such a stall (samples older than the watchdog when it acts,
    # or skipped as too old), and restarts from the measured angle after it.
    assert controller, 'no /diagnostics from arm_controller_node\n' + logs
    assert driver and driver[-1][0] >= first_setpoint, 'no driver report while tracking'
    watchdog = arm_bus_config().command_timeout
    before = [int(v['watchdog_vents']) for t, v in driver if t < first_setpoint]
    vents = int(driver[-1][1]['watchdog_vents']) - (before[-1] if before else 0)
    skipped = [int(c['stale_skipped']) for t, c in controller if t < first_setpoint] or [0]
    stalls = [c for t, c in controller if t >= first_setpoint
              and (float(c.get('sample_age_max_us', 0)) * 1e-6 >= watchdog
                   or int(c['stale_skipped']) > skipped[-1])]
    last = controller[-1][1]
    ages = [(c.get('sample_age_p99_us'), c.get('sample_age_max_us'), c['stale_skipped'])
            for t, c in controller if t >= first_setpoint]
    t0 = setpoints[0][0]  # the sweep's start, on the system clock
    during = [(t, psi) for t, psi in angle if t0 <= t <= setpoints[-1][0]]
    assert len(during) > 1000, (len(during), logs)
    # A vent that a measured stall caused, and the move back after it, are the host's, not the
    # tracking's: the error is scored outside them (once, in a CI run, a 0.1 s stall vented the
    # segment and the fall made the whole sweep's RMS 0.071 rad). They may not take the sweep.
    spans = after_vents([(t, on) for t, on in vented if t >= t0], angle, setpoints,
                        params.read_file(SIM_CONFIG, 'arm_controller_node')['resume_speed'])
    scored = [(t, psi) for t, psi in during if not any(a <= t <= b for a, b in spans)]
    errors = [interpolate(setpoints, t) - psi for t, psi in scored]
    rms = math.sqrt(sum(e * e for e in errors) / len(errors)) if errors else math.nan
    reached = (max(psi for _, psi in during), min(psi for _, psi in during))
    shown = [(round(a - t0, 2), round(b - t0, 2)) for a, b in spans]
    info = (f'RMS error {rms:.4f} rad over {len(scored)} of {len(during)} samples (vented and '
            f'moving back: {shown} s into the sweep), '
            f'angle range {reached[1]:.3f}..{reached[0]:.3f} rad, {vents} vent(s) while '
            f'tracking; sample age p99, max (us), stale skipped: {ages}')
    assert vents == 0 or (stalls and int(last['restarts']) >= vents), info + '\n' + logs
    assert len(scored) > 0.7 * len(during), info + '\n' + logs
    assert reached[0] > 0.6 and reached[1] < -0.6, info + '\n' + logs
    assert rms < 0.05, info + '\n' + logs
    # the end of every hold: settled on its angle
    t_end = t0
    for target, move, hold in trajectory.waypoints:
        t_end += move + hold
        if any(a <= t_end - 0.05 <= b for a, b in spans):
            continue
        psi = interpolate(angle, t_end - 0.05)
        assert abs(psi - target) < 0.02, f'hold at {target} rad ended at {psi:.4f}; ' + info
    assert int(last['commands']) > 1000 and last['source'] == 'topic'
    assert all(math.isfinite(float(c['error_rms'])) for _, c in controller[-5:])
    print(info)
