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
scenario_node in the test's process: when the runs start, and what the comparison says.

Samples, vents and /diagnostics are handed to the node's own callbacks, stamped on its clock.
"""

import probe
import pytest
from rclpy.parameter import Parameter

from bellows_ros import interfaces
from bellows_ros.control import angle_trajectory
from bellows_ros.nodes.scenario_node import GAP, READY, READY_TOLERANCE, ScenarioNode

pytestmark = pytest.mark.realtime  # runs alone, after the others (scripts/test.sh)


@pytest.fixture
def scenario(monkeypatch, tmp_path):
    monkeypatch.setenv('ROS_DOMAIN_ID', '197')
    probe.init()
    yield probe.adopt(ScenarioNode(parameter_overrides=[
        Parameter('output_dir', value=str(tmp_path)),
        Parameter('trajectory_start', value=1.0)]))
    probe.shutdown()


def angle(node, t, psi):
    """Hand `node` a sample of segment_1 at angle `psi` rad, taken `t` s after the start."""
    stamp = node.start_ns + round(t * 1e9)
    node.on_joint_states(probe.as_received(probe.arm_sample(stamp, [psi], [0.0], [2e5, 2e5])))


def controller_source(node, source):
    """Hand `node` the arm controller's /diagnostics, following `source` for segment_1."""
    status = probe.msg.DiagnosticStatus(
        name=f'{interfaces.ARM_CONTROLLER_NODE}: segment_1',
        values=[probe.msg.KeyValue(key='source', value=source)])
    node.on_diagnostics(probe.msg.DiagnosticArray(status=[status]))


def test_the_first_run_waits_for_the_controller_and_a_held_unvented_arm(scenario):
    hold = scenario.hold
    for k in range(2001):  # 2 s at the first set-point, 1 kHz
        angle(scenario, k * 1e-3, hold)
    assert not scenario.ready(2.0)          # the controller does not follow the topic yet
    controller_source(scenario, 'topic')
    assert scenario.ready(2.0)
    assert not scenario.ready(0.5)          # not before trajectory_start
    scenario.on_vented(probe.msg.Bool(data=True))
    assert not scenario.ready(2.0)          # a vent starts the hold over
    angle(scenario, 2.5, hold + 0.5 * READY_TOLERANCE)
    assert not scenario.ready(2.5 + 0.9 * READY) and scenario.ready(2.5 + READY)
    angle(scenario, 4.0, hold + 2.0 * READY_TOLERANCE)   # the arm away from the set-point
    assert not scenario.ready(4.0 + READY)
    controller_source(scenario, 'hold')
    angle(scenario, 5.0, hold)
    assert not scenario.ready(5.0 + READY)  # the controller no longer follows


def test_the_runs_follow_each_other_with_the_switches_between(scenario):
    scenario.place_runs(7.0)
    span = angle_trajectory.duration(scenario.trajectory) + GAP
    assert [(mode, start) for _, mode, start in scenario.runs] == \
        [('paper_a', 7.0), ('none', 7.0 + span)]
    # feedback only half way through the gap, and the configured mode back after the last run
    assert scenario.switches == [(7.0 + span - GAP / 2, 'none'),
                                 (7.0 + 2 * span - GAP / 2, None)]


def test_the_summary_gives_each_runs_rms_and_their_ratio(scenario):
    scenario.place_runs(3.0)
    errors = {'paper_a': 0.002, 'none': 0.008}
    for _, mode, start in scenario.runs:
        for k in range(int(angle_trajectory.duration(scenario.trajectory) * 100) + 1):
            t = k * 0.01
            psi_d = angle_trajectory.setpoint(scenario.trajectory, t)[0]
            error = errors[mode] * (1 if k % 2 else -1)
            angle(scenario, start + t, psi_d - error)
    lines = scenario.tracking_summary()
    assert 'paper A feedforward' in lines[0] and 'RMS error 0.0020 rad' in lines[0], lines
    assert 'feedback only' in lines[1] and 'RMS error 0.0080 rad' in lines[1], lines
    assert lines[2].startswith('feedforward / feedback only: 0.25 '), lines
    scenario.vents.append(scenario.runs[1][2] + 1.0)  # a vent in the second run
    lines = scenario.tracking_summary()
    assert 'vented the arm 1 times' in lines[1] and 'not compared' in lines[2], lines


def test_a_scenario_whose_arm_never_got_ready_says_why(scenario):
    angle(scenario, 1.0, scenario.hold)
    lines = scenario.tracking_summary()
    assert len(lines) == 1 and 'no run' in lines[0], lines
    assert f'following {interfaces.PSI_SETPOINT.name}: no' in lines[0], lines
