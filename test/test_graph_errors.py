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
Acceptance: a node given a missing device, bad YAML or unknown parameter exits with status 2.

It prints one line on stderr naming the problem (rcl may log a line of its own before it).
"""
from pathlib import Path
import random
import subprocess
import sys
import time

from node_processes import free_domain, node_env, stop_all
import pytest

# each test starts a node process (1-3 s)
pytestmark = [pytest.mark.slow, pytest.mark.realtime]

BIN = Path(sys.executable).parent
CONFIG = Path(__file__).resolve().parent.parent / 'config' / 'nodes_sim.yaml'


@pytest.fixture
def run(tmp_path):
    """Return a runner of `node` with `args`: its exit, in a domain of its own."""
    def run_node(node, args):
        env = node_env(ROS_DOMAIN_ID=free_domain())
        return subprocess.run([str(BIN / node), '--ros-args', *args], capture_output=True,
                              text=True, timeout=60, env=env, cwd=tmp_path)
    return run_node


def check(result, *fragments):
    """Exit status 2 and one error line with `fragments`; rcl may log its own line first."""
    assert result.returncode == 2, result.stderr
    lines = [line for line in result.stderr.strip().splitlines() if '] [rcl]: ' not in line]
    assert len(lines) == 1, result.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


def test_missing_serial_device(run, tmp_path):
    port = tmp_path / 'no_such_board'
    result = run('driver_node', ['-p', 'autostart:=true', '-p', 'actuator.enabled:=true',
                                 '-p', f'actuator.port:={port}'])
    check(result, 'driver_node: error:', f'actuator board port {port} does not exist')


def test_a_port_that_appears_within_startup_timeout_is_opened(tmp_path):
    """
    A board's port made a moment after the driver starts is waited for, not refused.

    A launch starts a simulated board beside the driver, a USB board enumerates: the driver waits
    up to `startup_timeout` for the port.
    """
    port = tmp_path / 'board'
    env = node_env(ROS_DOMAIN_ID=free_domain())
    driver = subprocess.Popen([str(BIN / 'driver_node'), '--ros-args', '-p', 'autostart:=true',
                               '-p', 'actuator.enabled:=true', '-p', f'actuator.port:={port}',
                               '-p', 'startup_timeout:=20.0'], env=env, cwd=tmp_path,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    board = None
    try:
        time.sleep(1.0)    # the driver is waiting for the port: it must not have exited
        assert driver.poll() is None, driver.stdout.read()
        board = subprocess.Popen([str(BIN / 'sim_actuator_node'), '--ros-args', '-p',
                                  f'port:={port}'], env=env, cwd=tmp_path,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        lines = []
        for line in driver.stdout:    # activate logs 'driving <devices>'; a refusal 'error'
            lines.append(line)
            if 'driving' in line or 'error' in line:
                break
        assert any('driving' in line for line in lines), ''.join(lines)
        assert driver.poll() is None, ''.join(lines)
    finally:
        stop_all([p for p in (driver, board) if p is not None], timeout=15.0)


def test_silent_can_bus(run):
    group = f'239.74.165.{random.randint(2, 250)}'  # nobody simulates an arm on this group
    result = run('driver_node', ['-p', 'autostart:=true', '-p', 'arm.enabled:=true',
                                 '-p', 'arm.interface:=udp_multicast',
                                 '-p', f'arm.channel:={group}', '-p', 'startup_timeout:=0.5'])
    check(result, f'no arm samples on udp_multicast:{group} within 0.5 s')


def test_bad_yaml_names_file_and_line(run, tmp_path):
    bad = tmp_path / 'bad.yaml'
    bad.write_text('model_node:\n  ros__parameters:\n    segments: [1, 2\n')
    # rcl's YAML parser names the file and the line (the unclosed list ends the file, line 3)
    check(run('model_node', ['--params-file', str(bad)]), 'model_node: error:', f'{bad}',
          'near line 3')


def test_unknown_parameter(run):
    check(run('model_node', ['--params-file', str(CONFIG), '-p', 'segmnets:=[1]']),
          "unknown parameter 'segmnets' for node 'model_node'")


def test_unknown_parameter_in_the_node_section(run, tmp_path):
    wrong = tmp_path / 'wrong.yaml'
    wrong.write_text('stiffness_controller_node:\n  ros__parameters:\n    pd:\n      kq: 1.0\n')
    check(run('stiffness_controller_node', ['--params-file', str(wrong)]),
          "unknown parameter 'pd.kq' for node 'stiffness_controller_node'")


def test_bad_identified_parameters_file(run, tmp_path):
    check(run('model_node', ['-p', f'params_file:={tmp_path / "missing.yaml"}']),
          'missing.yaml')


def test_realtime_priority_out_of_range(run):
    result = run('model_node', ['-p', 'realtime_priority:=120'])
    check(result, "'realtime_priority'", '0 (off) or 1..99', '120')


def test_cpu_latency_limit_out_of_range(run):
    result = run('model_node', ['-p', 'cpu_latency_limit:=5000.0'])
    check(result, "'cpu_latency_limit'", 'negative value (off) or 0..2000 s', '5000')


def test_arm_controller_bad_parameters(run):
    check(run('arm_controller_node', ['-p', 'feedforward:=paper_b']),
          "'feedforward'", "'paper_a', 'previous', 'none'", 'paper_b')
    check(run('arm_controller_node', ['-p', 'trajectory:=zigzag']),
          "parameter 'trajectory'", "'reversals', 'sweep'", "got 'zigzag'")
    check(run('arm_controller_node', ['-p', 'control_every:=100']),
          "parameter 'control_every'", 'expected 1..25', 'got 100')
    check(run('arm_controller_node', ['-p', 'pid.kp:=-1.0']), "parameter 'pid.kp'",
          'expected 0..10000')
