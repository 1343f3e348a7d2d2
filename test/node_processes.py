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
Node processes in tests: their environment, starting and stopping them, the ROS 2 command line.

Every node process keeps its DDS traffic on this machine (LOOPBACK_ENVIRONMENT, conftest.py).
Tests that need the ROS 2 command line (`ros2 param`, `ros2 lifecycle`, `ros2 service`,
`ros2 launch`) skip where it is absent, saying why, unless `BELLOWS_REQUIRE_ROS2_CLI=1`
(scripts/test.sh sets it when it installed the command line): then they fail.
"""
from multiprocessing import resource_tracker
import os
from pathlib import Path
import random
import shutil
import signal
import subprocess
import sys
import time

import pytest

from bellows_ros.runtime.node import LOOPBACK_ENVIRONMENT  # noqa: F401 (conftest's)


def ros2_cli_missing():
    """Why the ROS 2 command line cannot run here ('' when it can)."""
    if shutil.which('ros2') is None:
        return 'no ros2 command on PATH (scripts/test.sh installs it from ../shared/ros2-pip)'
    return ''


def require_ros2_cli():
    """Skip (or, with BELLOWS_REQUIRE_ROS2_CLI=1, fail) the calling test where ros2 is absent."""
    reason = ros2_cli_missing()
    if not reason:
        return
    if os.environ.get('BELLOWS_REQUIRE_ROS2_CLI') == '1':
        pytest.fail(reason + ' (BELLOWS_REQUIRE_ROS2_CLI=1: it was installed for this run)')
    pytest.skip(reason)


def node_env(**extra):
    """Return the environment for a node process, with `extra` variables."""
    return dict(os.environ, **extra)


def override(node, name, value):
    """`-p node:name:=value`: wins over the node's own section of a params file (rcl's rule)."""
    return ['-p', f'{node}:{name}:={value}']


BIN = Path(sys.executable).parent
SIM_CONFIG = Path(__file__).resolve().parent.parent / 'config' / 'nodes_sim.yaml'


# The driver is a managed node: brought to active at start, as launch_sim.sh does.
AUTOSTART = {'driver_node': ['-p', 'driver_node:autostart:=true']}


def launch(name, args, env, log_dir):
    """Start node `name` with config/nodes_sim.yaml and `args`, its log in LOG_DIR/name.log."""
    log = open(log_dir / f'{name}.log', 'w')
    return subprocess.Popen([str(BIN / name), '--ros-args', '--params-file', str(SIM_CONFIG),
                             *AUTOSTART.get(name, []), *args], env=env, stdout=log,
                            stderr=subprocess.STDOUT)


def free_domain():
    """
    Return a ROS domain for one test's graph, drawn from 1-101.

    Not 102-214: Fast DDS's ports for those (7400 + 250 x domain and up) fall among Linux's
    ephemeral ports (32768-60999), where any socket may hold a participant's well-known port
    (ROS 2's documentation, "The ROS_DOMAIN_ID"). Not 0: a user's own graph. The benches use
    215-232 (bench/graph.py).
    """
    return str(random.randint(1, 101))


def launch_arm(env, group, log_dir, controller_args=()):
    """
    Start a one-segment simulated arm on CAN group `group`, the arm controller and the driver.

    The controller (with `controller_args`) starts before the driver, so it sees the first sample;
    returns the three processes.
    """
    sim = (override('sim_arm_node', 'can.channel', group)
           + override('sim_arm_node', 'n_segments', 1))
    driver = (override('driver_node', 'actuator.enabled', 'false')
              + override('driver_node', 'arm.channel', group)
              + override('driver_node', 'arm.n_segments', 1))
    processes = [launch('sim_arm_node', sim, env, log_dir),
                 launch('arm_controller_node', list(controller_args), env, log_dir)]
    time.sleep(1.0)
    processes.append(launch('driver_node', driver, env, log_dir))
    return processes


def logs(log_dir):
    """Return the end of every node log in `log_dir`, for an assertion's message."""
    return '\n'.join(f'--- {p.name}\n{p.read_text()[-1500:]}' for p in log_dir.glob('*.log'))


# Every process this test session starts carries it (conftest.py sets it; children inherit it),
# so one that outlives its parent (reparented to init) is still found as this session's.
SESSION = 'BELLOWS_TEST_SESSION'


def session_processes():
    """{pid: 'pid (name)'} of the processes this test session started that still run."""
    # multiprocessing's resource tracker (started by the first 'spawn' pool or worker, for the
    # life of this process) is the library's, not a test's.
    ours = {os.getpid(), getattr(resource_tracker._resource_tracker, '_pid', None)}
    marker = f'{SESSION}={os.getpid()}'.encode() + b'\0'
    found = {}
    for entry in os.scandir('/proc'):
        if entry.name.isdigit() and int(entry.name) not in ours:
            try:
                with open(f'/proc/{entry.name}/environ', 'rb') as environ:
                    if marker not in environ.read():
                        continue
                with open(f'/proc/{entry.name}/stat') as stat:
                    text = stat.read()
            except OSError:
                continue  # ended in between, or not ours to read
            if text.rsplit(')', 1)[1].split()[0] != 'Z':   # a zombie has ended already
                found[int(entry.name)] = text[:text.rindex(')') + 1]
    return found


def _cpu_seconds(pid):
    """Return utime + stime of a process, s (fields 14 and 15 of /proc/<pid>/stat)."""
    with open(f'/proc/{pid}/stat') as stream:
        fields = stream.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def process_states(processes):
    """
    One line per process: its program, whether it runs, its scheduling and the CPU it has used.

    For the message of a test whose process did not end in time: a process that used seconds of
    CPU was working, one that used next to none was starved or blocked.
    """
    lines = []
    for process in processes:
        program = Path(process.args[0]).name
        if process.poll() is not None:
            lines.append(f'{program}: ended, exit status {process.returncode}')
            continue
        try:
            # field 3 of /proc/<pid>/stat: R running, S sleeping, D waiting on I/O
            state = Path(f'/proc/{process.pid}/stat').read_text().rsplit(')', 1)[1].split()[0]
            cpu, policy = _cpu_seconds(process.pid), os.sched_getscheduler(process.pid)
        except OSError as exc:  # ended in between
            lines.append(f'{program}: {exc}')
            continue
        fifo = 'SCHED_FIFO' if policy == os.SCHED_FIFO else 'normal scheduling'
        lines.append(f'{program}: state {state}, {fifo}, {cpu:.1f} s of CPU')
    return '\n'.join(lines)


def wait_for(process, timeout, processes, log_dir):
    """
    Wait up to `timeout` s for `process` to end; its exit status.

    A process still running then fails the test with every process's state (`process_states`)
    and the node logs, instead of a bare TimeoutExpired.
    """
    try:
        return process.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        pytest.fail(f'{Path(process.args[0]).name} still running after {timeout:g} s\n'
                    f'{process_states(processes)}\n{logs(log_dir)}')


def stop_all(processes, timeout=10.0):
    """SIGINT every node process (as Ctrl-C or `ros2 launch` does), then wait; kill a hung one."""
    for process in processes:
        if process.poll() is None:
            process.send_signal(signal.SIGINT)
    for process in processes:
        try:
            process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def ros2_cli(args, env, timeout=60.0):
    """
    Run the ros2 command line (`ros2 ARGS`) without its daemon; the finished process.

    Without `--no-daemon` each call would leave a ros2 daemon running for the test's domain, and
    a later test drawing the same domain would ask that daemon's stale graph. Without a daemon
    each call discovers for itself (`--spin-time`), so a node not found yet is asked again, until
    `timeout` s.
    """
    require_ros2_cli()
    own_discovery = [] if args[:2] == ['service', 'call'] else ['--no-daemon', '--spin-time', '1']
    end = time.monotonic() + timeout
    while True:
        result = subprocess.run(['ros2', *args, *own_discovery], capture_output=True, text=True,
                                timeout=timeout, env=env)
        if 'Node not found' not in result.stdout + result.stderr or time.monotonic() > end:
            return result
