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
Acceptance: stiffness step on the simulated actuator, and holding it against an air leak.

Processes: sim_actuator_node (pty; effects wall_bulging + air_leak + buckling), driver_node
(serial), stiffness_controller_node; the test publishes set-points and listens to
/actuator/stiffness (the controller's estimate from the measured pressure) and /diagnostics (the
plant's true chamber compression and gas amount, from which the true stiffness follows with paper
B's model).


Criteria (issue): after a step to 1900 N/m, within 2 % of the target in <= 1.2x the lead screw's
minimum travel time, overshoot <= 5 % of the step, end stops never hit; with air_leak on, held
within 2 % for 60 s (real time: the plant runs at wall-clock pace, ~85 s for this test).
The minimum travel time is taken at the duty limit the driver enforces (duty_max x the motor's
no-load speed): the fastest the lead screw is allowed to move.
The low set-point is 1400 N/m where the actuator model can reach it; with the present
config/actuator.yaml its range starts above 1400 N/m, so the step starts 1 % above the bottom of
the range instead (reported in the assertion messages).
"""
import time

from node_processes import free_domain, launch, node_env, override, stop_all
import probe
import pytest

from bellows_ros.config.actuator import load_actuator_params, load_actuator_plant_params
from bellows_ros.config.hardware import actuator_board_config
from bellows_ros.models.actuator import stiffness
from bellows_ros.models.stiffness_map import compression_for_stiffness, stiffness_range
from bellows_ros.runtime.messages import msg

pytestmark = pytest.mark.realtime  # runs alone, after the others (scripts/test.sh)

K_HIGH = 1900.0
HOLD = 60.0


@pytest.mark.slow
@pytest.mark.timeout(200)
def test_stiffness_step_and_leak_hold(tmp_path, monkeypatch):
    params = load_actuator_params()
    k_min, _ = stiffness_range(params)
    k_low = max(1400.0, 1.01 * k_min)
    x_low = compression_for_stiffness(params, k_low)
    x_high = compression_for_stiffness(params, K_HIGH)
    duty_max = actuator_board_config().duty_max
    travel_min = abs(x_high - x_low) / (duty_max * load_actuator_plant_params().drive.max_speed)

    domain = free_domain()
    monkeypatch.setenv('ROS_DOMAIN_ID', domain)
    env = node_env(ROS_DOMAIN_ID=domain)
    port = str(tmp_path / 'actuator')
    processes = [
        launch('sim_actuator_node', override('sim_actuator_node', 'port', port)
               + override('sim_actuator_node', 'x_c0', x_low)
               + override('sim_actuator_node', 'effects', '[wall_bulging, air_leak, buckling]'),
               env, tmp_path),
        launch('stiffness_controller_node',
               override('stiffness_controller_node', 'initial_stiffness', k_low), env, tmp_path),
    ]
    time.sleep(1.0)
    processes.append(launch('driver_node', override('driver_node', 'arm.enabled', 'false')
                            + override('driver_node', 'actuator.port', port), env, tmp_path))
    estimate, plant = [], []

    def on_diagnostics(array):
        for status in array.status:
            if status.name == 'sim_actuator_node: plant':
                values = {kv.key: float(kv.value) for kv in status.values
                          if kv.key in ('x_c', 'gas_p_ref', 'end_stop_hits')}
                plant.append((time.monotonic(), values))
    try:
        probe.init()
        node = probe.Node('stiffness_acceptance')
        setpoint = node.create_publisher(msg.Float64, '/actuator/stiffness_setpoint', 10)
        node.create_subscription(msg.Float64, '/actuator/stiffness',
                                 lambda m: estimate.append((time.monotonic(), m.data)), 100)
        node.create_subscription(msg.DiagnosticArray, '/diagnostics', on_diagnostics, 50)
        end = time.monotonic() + 20
        while len(estimate) < 50 and time.monotonic() < end:
            probe.spin_once(node, timeout_sec=0.05)
        assert estimate, 'no /actuator/stiffness from the graph'
        k_before = estimate[-1][1]
        t_step = time.monotonic()
        setpoint.publish(msg.Float64(data=K_HIGH))
        end = t_step + 1.3 * travel_min + HOLD + 3.0
        while time.monotonic() < end:
            probe.spin_once(node, timeout_sec=0.05)
    finally:
        stop_all(processes)
        probe.shutdown()
    logs = '\n'.join(p.read_text()[-800:] for p in tmp_path.glob('*.log'))
    assert abs(k_before - k_low) < 0.02 * k_low, (k_before, k_low, logs)

    after = [(t - t_step, k) for t, k in estimate if t > t_step]
    band = 0.02 * K_HIGH
    outside = [t for t, k in after if abs(k - K_HIGH) > band]
    settle = outside[-1] if outside else 0.0
    info = (f'k_low={k_low:.0f} N/m, x {x_low * 1e3:.1f} -> {x_high * 1e3:.1f} mm, '
            f'min travel {travel_min:.2f} s, settled after {settle:.2f} s')
    assert after[-1][0] > settle + HOLD, info  # the band held for at least HOLD s after settling
    assert settle <= 1.2 * travel_min, info
    overshoot = max(k for _, k in after) - K_HIGH
    assert overshoot <= 0.05 * (K_HIGH - k_low), f'overshoot {overshoot:.1f} N/m; ' + info

    # The plant's truth: true stiffness held within 2 % through the leak, no end stop touched.
    assert plant and plant[-1][1]['end_stop_hits'] == 0, logs
    held = [stiffness(params, v['x_c'], v['gas_p_ref']) for t, v in plant
            if t - t_step > settle + 1.0]
    assert len(held) >= HOLD - 5, (len(held), info)
    worst = max(abs(k - K_HIGH) for k in held)
    assert worst <= band, f'true stiffness off by {worst:.1f} N/m; ' + info
    gas = [v['gas_p_ref'] for _, v in plant]
    # Below atmospheric pressure (x_c < 20 mm) air leaks in: the amount changes either way.
    assert abs(gas[-1] - gas[0]) > 50.0, \
        f'the leak did not act: gas {gas[0]:.0f} -> {gas[-1]:.0f} Pa'
    print(info, f'overshoot {overshoot:.1f} N/m, worst true error {worst:.1f} N/m, '
                f'gas {gas[0]:.0f} -> {gas[-1]:.0f} Pa')
