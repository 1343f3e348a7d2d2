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
The model node's `model_health` on the simulated arm (#21 point 4): a load set mid-run is seen.

Processes: sim_arm_node (one segment, at rest: no controller), driver_node (arm only),
model_node with a short healthy window; the test listens to `model_node: model_health` on
/diagnostics. After the healthy window it watches HEALTHY s of the unloaded arm (no WARN allowed),
then `ros2 param set` puts LOAD N·m on the segment; a WARN naming segment_1 must follow within
DEADLINE s. The numbers (floor, ratios, the sample path's cost) are printed.
"""
import random
import time

from node_processes import free_domain, launch, logs, node_env, override, ros2_cli, stop_all
import probe
import pytest

from bellows_ros.nodes.diagnostics import level_of, STALE, WARN
from bellows_ros.runtime.messages import msg

# three node processes for ~40 s
pytestmark = [pytest.mark.slow, pytest.mark.realtime]

CALIBRATION = 5.0               # s: the model node's healthy window (model_health.calibration)
WINDOW = 2.0                    # s: model_health.window
HEALTHY = 10.0                  # s watched healthy after it
DEADLINE = 20.0                 # s from the load's setting to the WARN naming the segment
LOAD = '2.5'                    # N·m on the segment: its τ_ext noise is ~c_f (0.4 N·m)
STATUS = 'model_node: model_health'


@pytest.mark.timeout(240)
def test_a_load_set_mid_run_leaves_the_floor_and_no_warn_before(tmp_path, monkeypatch):
    domain = free_domain()
    group = f'239.74.165.{random.randint(2, 250)}'
    monkeypatch.setenv('ROS_DOMAIN_ID', domain)
    env = node_env(ROS_DOMAIN_ID=domain)
    model = [('segments', '[1]'), ('model_health.calibration', CALIBRATION),
             ('model_health.window', WINDOW), ('realtime_priority', 0)]
    driver = [('arm.enabled', 'true'), ('actuator.enabled', 'false'), ('arm.channel', group),
              ('arm.n_segments', 1), ('realtime_priority', 0)]
    processes = [
        launch('sim_arm_node', override('sim_arm_node', 'can.channel', group)
               + override('sim_arm_node', 'n_segments', 1)
               + override('sim_arm_node', 'realtime_priority', 0), env, tmp_path),
        launch('model_node', sum((override('model_node', k, v) for k, v in model), []), env,
               tmp_path)]
    time.sleep(1.0)
    processes.append(launch('driver_node', sum((override('driver_node', k, v)
                                                for k, v in driver), []), env, tmp_path))
    reports = []    # (monotonic time, level, message, {key: value})

    def on_diagnostics(array):
        for status in array.status:
            if status.name == STATUS:
                reports.append((time.monotonic(), level_of(status.level), status.message,
                                {kv.key: kv.value for kv in status.values}))
    try:
        probe.init()
        node = probe.Node('model_health_acceptance')
        node.create_subscription(msg.DiagnosticArray, '/diagnostics', on_diagnostics, 50)

        def spin_until(condition, seconds):
            end = time.monotonic() + seconds
            while not condition() and time.monotonic() < end:
                probe.spin_once(node, timeout_sec=0.05)
            return condition()

        def state():
            return reports[-1][3].get('state') if reports else None

        assert spin_until(lambda: state() == 'healthy', CALIBRATION + 60.0), \
            (reports[-2:], logs(tmp_path))
        healthy_from = time.monotonic()
        spin_until(lambda: False, HEALTHY)
        t_set = time.monotonic()
        answer = ros2_cli(['param', 'set', '/sim_arm_node', 'load_torque', LOAD], env)
        assert 'Set parameter successful' in answer.stdout, (answer, logs(tmp_path))

        def seen():
            return any(t > t_set and level == WARN and 'segment_1' in message
                       for t, level, message, _ in reports)
        found = spin_until(seen, DEADLINE + 5.0)
        assert all(p.poll() is None for p in processes), logs(tmp_path)
    finally:
        stop_all(processes)
        probe.shutdown()
    # Until the driver's first sample reaches it the node says STALE ("no samples evaluated"),
    # which is true and not about the model; from that sample on, nothing above OK until the load.
    first = next(t for t, level, _, _ in reports if level < STALE)
    before = [r for r in reports if first <= r[0] <= t_set]
    assert not [r[:3] for r in before if r[1] >= WARN], before[-3:]
    assert found, (reports[-3:], logs(tmp_path))
    warn = next(r for r in reports if r[0] > t_set and r[1] == WARN)
    healthy = [r[3] for r in before if r[0] > healthy_from]
    info = (f'healthy {t_set - healthy_from:.0f} s without WARN (floor '
            f"{healthy[-1]['noise_floor_segment_1']} N·m, ratio "
            f"{max(float(v['ratio_segment_1']) for v in healthy):.2f} at most, limit "
            f"{healthy[-1]['limit_segment_1']}); out {warn[0] - t_set:.1f} s after the load: "
            f"{warn[2]!r}; cost per sample {warn[3]['cost_per_sample_us']} us (max "
            f"{warn[3]['cost_per_sample_max_us']} us), update {warn[3]['update_ms']} ms")
    assert warn[0] - t_set <= DEADLINE, info
    print(info)
