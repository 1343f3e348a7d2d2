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
The stop that latches, under load: `/bellows/estop` and `~/vent` vent the arm until `~/release`.

A simulated arm and the driver run as node processes; this process (a plain rclpy node) floods
pressure commands (4 bar on every chamber, 1 kHz) and watches the pressures on `/joint_states`.
Once the chambers are up, the README's stop (`ros2 topic pub` of True on `/bellows/estop`, latched,
left running) holds the stop while the commands keep coming, and Ctrl-C ends it. The chambers must
fall to ambient and stay there while the commands keep coming; `False` alone must not release them,
and `~/release` is refused while the stop is held. Then `~/vent` and `~/release` (std_srvs/Trigger,
called with the real `ros2 service call` of ROS 2) vent and release it. The driver's /diagnostics
say it is vented, and its `bellows/vented` says when it starts and stops holding the chambers
vented.
"""
from pathlib import Path
import random
import shlex
import signal
import subprocess
import time

from node_processes import (free_domain, launch, logs, node_env, override, require_ros2_cli,
                            ros2_cli)
import probe
import pytest

from bellows_ros import interfaces
from bellows_ros.runtime.messages import msg

# two node processes, ~15 s
pytestmark = [pytest.mark.slow, pytest.mark.realtime]

AMBIENT = 101325.0
COMMAND = 4.0e5


def readme_stop_command():
    """Return the README's stop as a command line: the code after "**Stop.**"."""
    readme = (Path(__file__).resolve().parents[1] / 'README.md').read_text()
    after = readme[readme.index('- **Stop.**'):]
    return shlex.split(' '.join(after.split('`')[1].split()))


def call(service, env):
    """`ros2 service call /driver_node/SERVICE std_srvs/srv/Trigger`: its output."""
    result = ros2_cli(['service', 'call', f'/driver_node/{service}', 'std_srvs/srv/Trigger'],
                      env)
    assert result.returncode == 0, result.stderr
    return result.stdout


def test_estop_vents_under_a_command_flood_and_false_does_not_release(tmp_path, monkeypatch):
    domain = free_domain()
    group = f'239.74.168.{random.randint(2, 250)}'
    monkeypatch.setenv('ROS_DOMAIN_ID', domain)
    env = node_env(ROS_DOMAIN_ID=domain)
    normal = [('realtime_priority', 0)]
    processes = [
        launch('sim_arm_node', sum((override('sim_arm_node', k, v) for k, v in
                                    [('can.channel', group), ('n_segments', 1)] + normal), []),
               env, tmp_path),
        launch('driver_node', sum((override('driver_node', k, v) for k, v in
                                   [('arm.channel', group), ('arm.n_segments', 1),
                                    ('actuator.enabled', 'false')] + normal), []),
               env, tmp_path)]
    probe.init()
    try:
        watcher = probe.Node('estop_probe')
        pressures, status, vented = [], {}, []
        watcher.create_subscription(msg.Bool, interfaces.VENTED.resolved(),
                                    lambda m: vented.append((time.monotonic(), m.data)),
                                    probe.LATCHED)
        watcher.create_subscription(
            msg.JointState, interfaces.JOINT_STATES.resolved(),
            lambda m: pressures.append((time.monotonic(), probe.highest_pressure(m))), 1000)
        watcher.create_subscription(
            msg.DiagnosticArray, '/diagnostics',
            lambda a: status.update({s.name: {kv.key: kv.value for kv in s.values}
                                     for s in a.status}), 50)
        commands = watcher.create_publisher(msg.JointState, interfaces.PRESSURE_COMMAND.resolved(),
                                            10)
        estop = watcher.create_publisher(msg.Bool, interfaces.ESTOP.resolved(), probe.LATCHED)
        command = msg.JointState(name=[interfaces.chain_chamber(1, 1),
                                       interfaces.chain_chamber(1, 2)],
                                 effort=[COMMAND, COMMAND])

        def flood(seconds):
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                commands.publish(command)
                probe.spin_once(watcher, timeout_sec=0.001)

        flood(0.5)
        deadline = time.monotonic() + 40
        while (not pressures or pressures[-1][1] < 0.9 * COMMAND) and time.monotonic() < deadline:
            flood(0.2)
        assert pressures and pressures[-1][1] > 0.9 * COMMAND, logs(tmp_path)
        assert vented[-1][1] is False, vented   # bellows/vented: the commands took
        # The stop from outside, the README's command, while the commands keep streaming.
        require_ros2_cli()
        stop = subprocess.Popen(readme_stop_command(), env=env, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, text=True)
        try:
            # The driver's own word that the stop holds (not the watchdog's vent: see below).
            deadline = time.monotonic() + 60
            while (status.get('driver_node: arm', {}).get('estop_held') != 'True'
                   and stop.poll() is None and time.monotonic() < deadline):
                flood(0.05)
            assert status['driver_node: arm']['estop_held'] == 'True', status
            stopped = time.monotonic()
            flood(3.0)
            assert stop.poll() is None, stop.stderr.read()   # held throughout, until Ctrl-C
        finally:
            stop.send_signal(signal.SIGINT)   # Ctrl-C: ends the holding, not the vent
            try:
                stop.wait(timeout=10)
            except subprocess.TimeoutExpired:
                stop.kill()
        after = [p for t, p in pressures if t > stopped + 1.5]
        assert after and max(after) < AMBIENT + 0.05 * (COMMAND - AMBIENT), logs(tmp_path)
        estop.publish(msg.Bool(data=False))
        flood(1.5)
        held = [p for t, p in pressures if t > stopped + 3.2]
        assert held and max(held) < AMBIENT + 0.05 * (COMMAND - AMBIENT)
        arm = status.get('driver_node: arm', {})
        assert arm.get('vented') == 'True' and int(arm['refused_while_vented']) > 100, arm
        # Held under the command flood: True since the stop, never False again. (Before it, while
        # the ros2 command line starts, the flood may stall past the driver's 0.1 s watchdog,
        # which vents and says so until the next command: the driver's watchdog, not the stop.)
        since = [value for t, value in vented if t > stopped]
        assert vented[-1][1] is True and all(since), \
            [(round(t - stopped, 3), value) for t, value in vented]   # s after the stop, said
        estop.publish(msg.Bool(data=True))
        flood(0.3)
        assert 'success=False' in call('release', env), 'released while the stop is held'
        estop.publish(msg.Bool(data=False))
        flood(0.3)
        assert 'success=True' in call('release', env)
        flood(3.0)
        assert max(p for t, p in pressures[-200:]) > 0.9 * COMMAND   # commands act again
        assert vented[-1][1] is False, vented
        assert 'success=True' in call('vent', env)
        vented_at = time.monotonic()
        flood(3.0)
        after = [p for t, p in pressures if t > vented_at + 1.5]
        assert after and max(after) < AMBIENT + 0.05 * (COMMAND - AMBIENT)
        assert vented[-1][1] is True, vented
    finally:
        for process in processes:
            if process.poll() is None:
                process.send_signal(2)
        for process in processes:
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()
        probe.shutdown()
