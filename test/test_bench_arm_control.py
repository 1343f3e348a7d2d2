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
`bellows bench --only 'arm_control*' --json`: its figures, their structure, and their order.

On the short deterministic run (the first three moves of the bench trajectory; simulated time).
"""
import json
import math

import numpy as np
import pytest

from bellows_ros.bench import arm_control
from bellows_ros.cli import main as bellows
from bellows_ros.control import angle_trajectory

NAMES = ['arm_control.rms.feedback_only', 'arm_control.rms.previous_model',
         'arm_control.rms.paper_a_model']
# `--only 'arm_control*'` also runs the drawn-device rows (bench/arm_control_devices.py),
# after these
DEVICE_NAMES = ['arm_control.devices.feedback_only', 'arm_control.devices.previous_model',
                'arm_control.devices.paper_a_model']


@pytest.mark.slow  # three closed-loop runs, and two identified devices with three each
def test_bench_figures_structure_and_order(capsys):
    assert bellows(['bench', '--only', 'arm_control*', '--json', '--quick']) == 0
    everything = json.loads(capsys.readouterr().out)['results']
    assert [r['name'] for r in everything] == NAMES + DEVICE_NAMES
    results, devices = everything[:3], everything[3:]
    for r in devices:
        assert r['unit'] == 'rad' and r['samples'] == 2  # --quick: two devices
        assert 0.0 < r['value'] <= r['extra']['worst_rms'] < 0.1
        assert r['extra']['median_command_variation'] > 0 and r['extra']['median_air_used'] > 0
    assert devices[2]['target'] == 0.5 and devices[2]['reference'] == DEVICE_NAMES[0]
    feedback, previous, paper_a = results
    steps = round(angle_trajectory.duration(arm_control.short_trajectory()) * 1000)
    for r in results:
        assert r['unit'] == 'rad' and r['samples'] == steps
        assert r['extra']['command_variation'] > 0 and r['extra']['air_used'] > 0
        assert 0 < r['extra']['hold_chatter'] <= r['extra']['hold_chatter_worst']
        assert math.isfinite(r['value']) and 0.0 < r['value'] < 0.1
        windows = [r['extra'][f'rms_{k}'] for k in ('holds', 'moves', 'reversals')]
        assert all(math.isfinite(w) and w > 0 for w in windows)
        # the total is the samples' mix of the three windows: inside their range
        assert min(windows) <= r['value'] <= max(windows)
    for r in (previous, paper_a):
        assert r['reference'] == feedback['name']
        assert r['ratio'] == r['value'] / feedback['value']
    assert paper_a['target'] == 0.5 * feedback['value']
    # the order (its 0.5 target is for the whole trajectory: docs/arm_control.md)
    assert paper_a['value'] < previous['value'] < feedback['value']
    # reversals are where the contact memory matters: paper A gains most there over (34)
    assert paper_a['extra']['rms_reversals'] < previous['extra']['rms_reversals']


def test_tracking_runs_are_deterministic():
    short = angle_trajectory.Trajectory(0.0, ((0.5, 1.0, 0.3),))
    first = arm_control.track('paper_a', short)
    again = arm_control.track('paper_a', short)
    assert np.array_equal(first.psi, again.psi) and np.array_equal(first.p1_cmd, again.p1_cmd)
    assert abs(first.psi[-1] - 0.5) < 0.05  # and it did track
