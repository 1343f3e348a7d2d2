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
The doctor live on the simulated rig (#21 point 4): a leak set mid-run is named, none before it.

Processes: sim_actuator_node (pty; wall_bulging and buckling on: the controller model's own
physics), driver_node, stiffness_controller_node; the test steps the stiffness set-point between
two values every few seconds (the chamber moves, as in use) and listens to the controller's
`model_health` on /diagnostics. After the controller's healthy window (its noise floors) it
watches HEALTHY s of the healthy rig (no WARN allowed: a shorter watch than the issue's 10 min,
which bench_results/0.1.0/notebook.md records once by hand), then `ros2 param set` switches the
plant's leak on; a WARN `model_health` naming air_leak must follow within DEADLINE s.
"""
import os
import time

from node_processes import free_domain, launch, logs, node_env, override, ros2_cli, stop_all
import probe
import pytest

from bellows_ros.config.actuator import load_actuator_params
from bellows_ros.models.stiffness_map import compression_for_stiffness
from bellows_ros.nodes.diagnostics import level_of, STALE, WARN
from bellows_ros.runtime.messages import msg

# three node processes for ~2 min
pytestmark = [pytest.mark.slow, pytest.mark.realtime]

SETPOINTS = (2100.0, 2300.0)    # N/m: 2.5-6.5 kPa above ambient, the gas leaks out
SWITCH = 4.0                    # s between set-point changes
CALIBRATION = 20.0              # s: the controller's healthy window (model_health.calibration)
# s watched healthy after it; BELLOWS_LIVE_DOCTOR_HEALTHY=600 for the 10 min, by hand
HEALTHY = float(os.environ.get('BELLOWS_LIVE_DOCTOR_HEALTHY', '30'))
DEADLINE = 60.0                 # s from the leak's switch-on to the WARN naming it
LEAK = '1.0e-11'                # m³/(s·Pa), config/actuator.yaml's leak
STATUS = 'stiffness_controller_node: model_health'


@pytest.mark.timeout(370 + HEALTHY)
def test_a_leak_set_mid_run_is_named_within_a_minute_and_no_warn_before(
        tmp_path, monkeypatch):
    params = load_actuator_params()
    domain = free_domain()
    monkeypatch.setenv('ROS_DOMAIN_ID', domain)
    env = node_env(ROS_DOMAIN_ID=domain)
    port = str(tmp_path / 'actuator')
    sim = [('port', port), ('x_c0', compression_for_stiffness(params, SETPOINTS[0])),
           ('effects', '[wall_bulging, buckling]'), ('realtime_priority', 0)]
    controller = [('initial_stiffness', SETPOINTS[0]), ('realtime_priority', 0),
                  ('model_health.calibration', CALIBRATION)]
    processes = [
        launch('sim_actuator_node',
               sum((override('sim_actuator_node', k, v) for k, v in sim), []), env, tmp_path),
        launch('stiffness_controller_node',
               sum((override('stiffness_controller_node', k, v) for k, v in controller), []),
               env, tmp_path)]
    time.sleep(1.0)
    processes.append(launch('driver_node', override('driver_node', 'arm.enabled', 'false')
                            + override('driver_node', 'actuator.port', port)
                            + override('driver_node', 'realtime_priority', 0), env, tmp_path))
    reports = []    # (monotonic time, level, message, {key: value})

    def on_diagnostics(array):
        for status in array.status:
            if status.name == STATUS:
                reports.append((time.monotonic(), level_of(status.level), status.message,
                                {kv.key: kv.value for kv in status.values}))
    try:
        probe.init()
        node = probe.Node('live_doctor_acceptance')
        setpoint = node.create_publisher(msg.Float64, '/actuator/stiffness_setpoint', 10)
        node.create_subscription(msg.DiagnosticArray, '/diagnostics', on_diagnostics, 50)
        step = [0, time.monotonic()]

        def spin_until(condition, seconds):
            end = time.monotonic() + seconds
            while not condition() and time.monotonic() < end:
                if time.monotonic() - step[1] > SWITCH:
                    step[0], step[1] = 1 - step[0], time.monotonic()
                    setpoint.publish(msg.Float64(data=SETPOINTS[step[0]]))
                probe.spin_once(node, timeout_sec=0.05)
            return condition()

        def state():
            return reports[-1][3].get('state') if reports else None

        assert spin_until(lambda: state() == 'healthy', CALIBRATION + 60.0), \
            (reports[-2:], logs(tmp_path))
        healthy_from = time.monotonic()
        spin_until(lambda: False, HEALTHY)
        t_set = time.monotonic()
        answer = ros2_cli(['param', 'set', '/sim_actuator_node', 'effect.air_leak.conductance',
                           LEAK], env)
        assert 'Set parameter successful' in answer.stdout, (answer, logs(tmp_path))

        def named():
            return any(t > t_set and level == WARN and 'air_leak' in message
                       for t, level, message, _ in reports)
        found = spin_until(named, DEADLINE + 5.0)
    finally:
        stop_all(processes)
        probe.shutdown()
    # Until the driver's first sample reaches it the controller says STALE ("no samples ..."),
    # which is true and not about the model; from that sample on, nothing above OK until the leak.
    first_sample = next(t for t, level, _, _ in reports if level < STALE)
    before = [r for r in reports if first_sample <= r[0] <= t_set]
    false_warns = [r[:3] for r in before if r[1] >= WARN]
    watched = t_set - healthy_from
    assert not false_warns, (false_warns, f'watched {watched:.0f} s healthy')
    assert found, (reports[-3:], logs(tmp_path))
    first = min(t for t, level, message, _ in reports
                if t > t_set and level == WARN and 'air_leak' in message)
    warn = next(r for r in reports if r[0] == first)
    left = min(t for t, level, _, _ in reports if t > t_set and level == WARN)
    info = (f'healthy {watched:.0f} s without WARN; residual out of the floor '
            f'{left - t_set:.1f} s and air_leak named {first - t_set:.1f} s after the leak was '
            f'set: {warn[2]!r}; cost per sample {warn[3]["cost_per_sample_us"]} us (max '
            f'{warn[3]["cost_per_sample_max_us"]} us), diagnosis {warn[3]["diagnosis_s"]} s, '
            f'update {warn[3]["update_ms"]} ms')
    assert first - t_set <= DEADLINE, info
    print(info)
