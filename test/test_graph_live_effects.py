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
A leak switched on mid-run with `ros2 param set` (#20 point 3, #21 point 4).

A running sim_actuator_node (a node process, its chamber compressed so the gas is above
ambient) is sealed: the gas amount its /diagnostics report holds still. `ros2 param set` of
`effect.air_leak.conductance` switches the leak on; the gas amount then falls in the reports
that show the plant stepping with it. A conductance
outside its physical range is refused with the Spec's words and changes nothing; 0 switches the
leak off again and the gas amount holds where the leak left it. The same for a running
sim_arm_node's pressure friction: refused out of range, else taken by the running plants.
"""
import os
import random
import time

from node_processes import free_domain, launch, logs, node_env, override, ros2_cli, stop_all
import probe
import pytest

from bellows_ros.runtime.messages import msg

# a node process and ~8 ros2 CLI calls
pytestmark = [pytest.mark.slow, pytest.mark.realtime]

NODE = 'sim_actuator_node'
LEAK = 'effect.air_leak.conductance'


def ros2_param(env, *args):
    result = ros2_cli(['param', *args], env)
    return result.stdout + result.stderr


def test_a_leak_set_mid_run_drains_the_gas_and_a_bad_one_is_refused(
        tmp_path, monkeypatch):
    domain = free_domain()
    monkeypatch.setenv('ROS_DOMAIN_ID', domain)
    env = node_env(ROS_DOMAIN_ID=domain)
    port = str(tmp_path / 'board')
    given = [('port', port), ('realtime_priority', 0), ('x_c0', 0.04), ('effects', "['']")]
    sim = launch(NODE, sum((override(NODE, k, v) for k, v in given), []), env, tmp_path)
    probe.init()
    reports = []  # the plant's /diagnostics values, in order
    try:
        watcher = probe.Node('live_effect_probe')
        watcher.create_subscription(
            msg.DiagnosticArray, '/diagnostics',
            lambda a: reports.extend({kv.key: kv.value for kv in s.values} for s in a.status
                                     if s.name == f'{NODE}: plant'), 50)

        def spin_until(condition, seconds):
            end = time.monotonic() + seconds
            while not condition() and time.monotonic() < end:
                probe.spin_once(watcher, timeout_sec=0.05)
            return condition()

        def gas(leak):
            """Gas amounts (p_ref, Pa) reported since the plant last stepped with another leak."""
            run = []
            for report in reports:
                run = run + [float(report['gas_p_ref'])] if report[LEAK] == leak else []
            return run

        assert spin_until(lambda: len(gas('0')) >= 2 and os.path.islink(port), 40), \
            logs(tmp_path)
        sealed = gas('0')
        assert sealed[-1] == sealed[-2], sealed  # no leak: the gas holds still
        assert float(reports[-1]['pressure']) > 110e3, reports[-1]  # compressed: above ambient
        assert ros2_param(env, 'get', f'/{NODE}', LEAK).strip() == 'Double value is: nan'

        # Out of its physical range (config/ranges.py): refused with the Spec's words.
        for bad in ('2.0e-06', '1.0e-03'):
            answer = ros2_param(env, 'set', f'/{NODE}', LEAK, bad)
            assert 'Setting parameter failed' in answer and '0..1e-06' in answer, answer
        assert ros2_param(env, 'get', f'/{NODE}', LEAK).strip() == 'Double value is: nan'

        answer = ros2_param(env, 'set', f'/{NODE}', LEAK, '2.0e-10')
        assert 'Set parameter successful' in answer, (answer, logs(tmp_path))
        assert ros2_param(env, 'get', f'/{NODE}', LEAK).strip() == 'Double value is: 2e-10'
        # The plant steps with the leak: the gas drains, each report lower than the last.
        assert spin_until(lambda: len(gas('2e-10')) >= 3, 15), (reports[-3:], logs(tmp_path))
        falling = gas('2e-10')
        assert sealed[-1] > falling[0] > falling[1] > falling[2], (sealed, falling)

        answer = ros2_param(env, 'set', f'/{NODE}', LEAK, '0.0')  # off again
        assert 'Set parameter successful' in answer, answer
        assert spin_until(lambda: len(gas('0')) >= 3, 15), (reports[-3:], logs(tmp_path))
        held = gas('0')[1:]  # the first may straddle the change
        assert held[0] == held[1] < falling[-1], (held, falling)
        assert sim.poll() is None, logs(tmp_path)
    finally:
        stop_all([sim])
        probe.shutdown()


def test_a_segment_effect_set_mid_run_is_taken_and_a_bad_one_is_refused(
        tmp_path, monkeypatch):
    """sim_arm_node: the strength reaches the running plants (their /diagnostics say so)."""
    domain = free_domain()
    monkeypatch.setenv('ROS_DOMAIN_ID', domain)
    env = node_env(ROS_DOMAIN_ID=domain)
    arm, friction = 'sim_arm_node', 'effect.pressure_friction.c_fp'
    given = [('can.channel', f'239.74.172.{random.randint(2, 250)}'), ('n_segments', 2),
             ('realtime_priority', 0), ('effects', '[contact_hysteresis]')]
    sim = launch(arm, sum((override(arm, k, v) for k, v in given), []), env, tmp_path)
    probe.init()
    reports = []
    try:
        watcher = probe.Node('live_segment_effect_probe')
        watcher.create_subscription(
            msg.DiagnosticArray, '/diagnostics',
            lambda a: reports.extend({kv.key: kv.value for kv in s.values} for s in a.status
                                     if s.name == f'{arm}: plant'), 50)

        def reported(value):
            return bool(reports) and reports[-1].get(friction) == value

        def spin_until(condition, seconds):
            end = time.monotonic() + seconds
            while not condition() and time.monotonic() < end:
                probe.spin_once(watcher, timeout_sec=0.05)
            return condition()

        assert spin_until(lambda: reported('0'), 40), (reports[-1:], logs(tmp_path))
        answer = ros2_param(env, 'set', f'/{arm}', friction, '20000.0')
        assert 'Setting parameter failed' in answer and '0..10000' in answer, answer
        answer = ros2_param(env, 'set', f'/{arm}', friction, '2.5')
        assert 'Set parameter successful' in answer, (answer, logs(tmp_path))
        assert spin_until(lambda: reported('2.5'), 15), (reports[-1:], logs(tmp_path))
        assert ros2_param(env, 'get', f'/{arm}', friction).strip() == 'Double value is: 2.5'
        assert sim.poll() is None, logs(tmp_path)
    finally:
        stop_all([sim])
        probe.shutdown()
