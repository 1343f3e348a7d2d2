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
Acceptance: the arm controller follows a trajectory_msgs/JointTrajectory on the simulated arm.

Processes: sim_arm_node (one segment, paper A's physics, udp_multicast CAN),
driver_node (arm only), arm_controller_node (config/nodes_sim.yaml). The test sends, on
`/arm_controller_node/joint_trajectory`: a trajectory for an unknown joint (refused, logged), a
trajectory A up to +0.7 rad, and while A runs a trajectory B to −0.4 rad that replaces it.

Criteria: the segment moves up under A (it really followed it), ends at B's end point (B replaced
the rest of A), the refusal names the joint in the log and in /diagnostics, and
`/arm_controller_node/state` carries joint `segment_1` with a reference that ends at B's end and a
feedback that is the measured angle. Where control_msgs is not installed (ROS 2 from PyPI: no
wheel) the controller says once that it does not publish `~/state`, and nobody publishes it.
"""
import math
import random
import time

from node_processes import free_domain, launch_arm, logs, node_env, stop_all
import probe
import pytest

from bellows_ros import interfaces
from bellows_ros.runtime.messages import msg

pytestmark = pytest.mark.realtime  # runs alone, after the others (scripts/test.sh)

END = -0.4  # rad, trajectory B's last point


def trajectory(names, points):
    """Build a JointTrajectory starting now (stamp 0) from [(time_from_start s, [Ψ], [Ψ̇])]."""
    return msg.JointTrajectory(joint_names=names, points=[
        msg.JointTrajectoryPoint(positions=positions, velocities=velocities,
                                 time_from_start=msg.Duration(sec=int(t),
                                                              nanosec=round(t % 1 * 1e9)))
        for t, positions, velocities in points])


@pytest.mark.slow
@pytest.mark.timeout(150)
def test_arm_controller_follows_a_joint_trajectory(tmp_path, monkeypatch):
    # A domain and CAN group of their own (test_graph_arm_control uses 101-140, 239.74.171.x).
    domain = free_domain()
    group = f'239.74.172.{random.randint(2, 250)}'
    monkeypatch.setenv('ROS_DOMAIN_ID', domain)
    env = node_env(ROS_DOMAIN_ID=domain)
    processes = launch_arm(env, group, tmp_path)
    angle, states, controller = [], [], []

    def on_diagnostics(array):
        for status in array.status:
            if status.name == 'arm_controller_node: segment_1':
                controller.append({kv.key: kv.value for kv in status.values})
    try:
        probe.init()
        node = probe.Node('joint_trajectory_acceptance')
        publisher = node.create_publisher(msg.JointTrajectory,
                                          interfaces.JOINT_TRAJECTORY.resolved(), 10)
        node.create_subscription(
            msg.JointState, interfaces.JOINT_STATES.resolved(),
            lambda m: angle.append((time.monotonic(), m.position[m.name.index('segment_1')]))
            if 'segment_1' in m.name else None, 200)
        with_state = msg.JointTrajectoryControllerState is not None  # control_msgs installed
        if with_state:
            node.create_subscription(msg.JointTrajectoryControllerState,
                                     interfaces.TRAJECTORY_STATE.resolved(),
                                     lambda m: states.append((time.monotonic(), m)), 50)
        node.create_subscription(msg.DiagnosticArray, '/diagnostics', on_diagnostics, 50)

        def spin(seconds, until=lambda: False):
            end = time.monotonic() + seconds
            while time.monotonic() < end and not until():
                probe.spin_once(node, timeout_sec=0.01)
        # The controller commands from paired samples (its /diagnostics count the commands):
        # a trajectory before then would be refused, the angles being unknown.
        spin(30, lambda: len(angle) >= 500 and (states or not with_state)
             and publisher.get_subscription_count()
             and controller and int(controller[-1].get('commands', '0')) > 0)
        assert angle, 'no /joint_states from the graph\n' + logs(tmp_path)
        assert publisher.get_subscription_count(), 'the controller does not subscribe\n' + logs(
            tmp_path)
        publisher.publish(trajectory(['segment_1', 'elbow'], [(1.0, [0.5, 0.5], [])]))
        sent_a = time.monotonic()
        publisher.publish(trajectory(['segment_1'], [(1.0, [0.3], []), (3.0, [0.7], [0.0])]))
        spin(2.0)
        sent_b = time.monotonic()
        publisher.publish(trajectory(['segment_1'], [(2.0, [END], [0.0])]))
        spin(2.0 + 2.0)
        spin(5.0, lambda: controller and controller[-1].get('rejected_trajectories') == '1')
        state_writers = node.get_publishers_info_by_topic(interfaces.TRAJECTORY_STATE.resolved())
    finally:
        stop_all(processes)
        probe.shutdown()
    log = logs(tmp_path)

    under_a = [psi for t, psi in angle if sent_a + 1.0 <= t <= sent_b]
    assert under_a and max(under_a) > 0.25, (max(under_a, default=None), log)
    final = [psi for t, psi in angle if t >= sent_b + 3.5]
    assert final, log
    settled = sum(final) / len(final)
    assert abs(settled - END) < 0.03, (settled, log)  # B's end, not A's 0.7 rad
    assert "joint trajectory refused: unknown joint 'elbow'" in log
    assert controller and controller[-1]['rejected_trajectories'] == '1', controller[-1:]
    assert controller[-1]['trajectories'] == '2'
    assert controller[-1]['source'] == 'joint_trajectory'

    if not with_state:
        assert 'control_msgs is not installed: ~/state is not published' in log, log
        assert state_writers == [], state_writers
        print(f'settled at {settled:.4f} rad (target {END}); no ~/state (no control_msgs)')
        return
    assert states, 'no ~/state\n' + log
    last = states[-1][1]
    assert list(last.joint_names) == ['segment_1']
    assert last.reference.positions[0] == pytest.approx(END, abs=1e-9)
    assert abs(last.feedback.positions[0] - settled) < 0.03
    assert last.error.positions[0] == pytest.approx(
        last.reference.positions[0] - last.feedback.positions[0])
    assert math.isfinite(last.output.effort[0])
    during_b = [m.reference.time_from_start for t, m in states if sent_b + 0.5 < t < sent_b + 1.5]
    assert during_b and all(0.3 < d.sec + d.nanosec * 1e-9 < 1.7 for d in during_b), during_b
    print(f'settled at {settled:.4f} rad (target {END}), {len(states)} states')
