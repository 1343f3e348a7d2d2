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
Launching under rclpy: `ros2 launch bellows_ros sim.launch.py`, `hw.launch.py`, launch_sim.sh.

The launch files run from an ament prefix made by hand (what colcon installs, without a colcon
build per test run: the package's share/ files as setup.py installs them, one executable per
console script in lib/bellows_ros). The shell launcher runs from a non-editable `pip install`
into a fresh venv. DDS stays on loopback, on this run's ROS_DOMAIN_ID.
"""
import csv
import os
from pathlib import Path
import re
import shutil
import signal
import subprocess
import sys
import threading
import time

from node_processes import free_domain, LOOPBACK_ENVIRONMENT, require_ros2_cli
import probe
import pytest
import yaml

ROOT = Path(__file__).resolve().parent.parent
GUARD = 300  # s; a hang guard for a whole launch, not a timing assertion

pytestmark = [pytest.mark.slow, pytest.mark.realtime]


def _ros_env(**extra):
    env = dict(os.environ)
    env.setdefault('ROS_DOMAIN_ID', '57')
    env.update(LOOPBACK_ENVIRONMENT)
    env['PYTHONUNBUFFERED'] = '1'
    env.update(extra)
    return env


@pytest.fixture(scope='module')
def ros():
    """
    Skip (with the reason) where the ros2 command line or launch_ros is not usable.

    Fail instead where it was installed for the run (node_processes.require_ros2_cli).
    """
    require_ros2_cli()
    result = subprocess.run([sys.executable, '-c', 'import launch_ros'], env=_ros_env(),
                            capture_output=True, text=True)
    if result.returncode != 0:
        reason = result.stderr.strip().splitlines()[-1]
        message = f'ros2 launch not usable: {reason} (source your ROS 2 setup.bash)'
        if os.environ.get('BELLOWS_REQUIRE_ROS2_CLI') == '1':
            pytest.fail(message + ' (BELLOWS_REQUIRE_ROS2_CLI=1: it was installed for this run)')
        pytest.skip(message)


@pytest.fixture(scope='module')
def prefix(ros, tmp_path_factory):
    """Make an ament prefix holding bellows_ros as colcon lays it out."""
    top = tmp_path_factory.mktemp('ament_prefix')
    index = top / 'share' / 'ament_index' / 'resource_index' / 'packages'
    index.mkdir(parents=True)
    (index / 'bellows_ros').touch()
    share = top / 'share' / 'bellows_ros'
    share.mkdir()
    shutil.copy(ROOT / 'package.xml', share / 'package.xml')
    shutil.copytree(ROOT / 'config', share / 'config')
    (share / 'launch').mkdir()
    for launch_file in (ROOT / 'launch').glob('*.launch.py'):
        shutil.copy(launch_file, share / 'launch')
    lib = top / 'lib' / 'bellows_ros'
    lib.mkdir(parents=True)
    scripts = re.findall(r"'(\w+) = (bellows_ros\.nodes\.\w+):main'",
                         (ROOT / 'setup.py').read_text())
    assert len(scripts) >= 6, scripts
    for name, module in scripts:
        exe = lib / name
        # As setuptools writes a console script: the guard keeps a spawned child (the stiffness
        # controller's live doctor) from starting the node again.
        exe.write_text(f'#!{sys.executable}\nimport sys\nfrom {module} import main\n'
                       "if __name__ == '__main__':\n    sys.exit(main())\n")
        exe.chmod(0o755)
    return top


def _prefix_env(prefix, **extra):
    return _ros_env(AMENT_PREFIX_PATH=f"{prefix}:{os.environ.get('AMENT_PREFIX_PATH', '')}",
                    **extra)


def _series_counts(csv_path):
    counts = {}
    with open(csv_path) as stream:
        for row in csv.DictReader(stream):
            counts[row['series']] = counts.get(row['series'], 0) + 1
    return counts


def test_sim_launch_runs_the_scenario_and_shuts_down(prefix, tmp_path):
    """`ros2 launch bellows_ros sim.launch.py`: the whole graph, the scenario, a clean exit 0."""
    out = tmp_path / 'scenario'
    run = subprocess.run(['ros2', 'launch', 'bellows_ros', 'sim.launch.py', 'duration:=12.0',
                          f'output_dir:={out}'], env=_prefix_env(prefix), capture_output=True,
                         text=True, timeout=GUARD)
    log = run.stdout + run.stderr
    assert run.returncode == 0, log[-3000:]
    for node in ('sim_arm_node', 'sim_actuator_node', 'driver_node', 'model_node',
                 'stiffness_controller_node', 'scenario_node'):
        assert f'[{node}-' in log, f'{node} was not started:\n{log[-3000:]}'
    assert re.search(r'\[scenario_node-\d+\] stiffness step', log), log[-3000:]
    assert re.search(r'\[scenario_node-\d+\] tau_drive: [1-9]\d* samples', log), log[-3000:]
    counts = _series_counts(out / 'scenario.csv')
    # Pressures and angles came through the driver, torques from the model, the estimated
    # stiffness from the controller: every node of the graph took part.
    for series in ('p1', 'psi', 'tau_drive', 'x_c', 'stiffness'):
        assert counts.get(series, 0) > 0, counts
    assert (out / 'scenario.png').stat().st_size > 0


def _read_until(process, patterns, guard=GUARD):
    """Lines of `process` until every regex in `patterns` matched one; (matches, lines)."""
    lines, found = [], {}
    done = threading.Event()

    def reader():
        for line in process.stdout:
            lines.append(line)
            for pattern in patterns:
                match = re.search(pattern, line)
                if match and pattern not in found:
                    found[pattern] = match
            if len(found) == len(patterns):
                done.set()
        done.set()
    thread = threading.Thread(target=reader, daemon=True)
    thread.start()
    done.wait(guard)
    return found, lines


def _session(pid):
    """Return the session id of process `pid` (/proc/<pid>/stat, field 6)."""
    with open(f'/proc/{pid}/stat') as stream:
        return int(stream.read().rsplit(')', 1)[1].split()[3])


def _stop(process):
    if process.poll() is None:
        process.send_signal(signal.SIGINT)  # as Ctrl-C: launch stops every node
        try:
            process.wait(30)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


ACTUATOR_LINE = r'\[sim_actuator_node\]: simulated actuator board on (\S+), effects: (.*)$'
ARM_LINE = r'\[sim_arm_node\]: simulated arm .* on udp_multicast:(\S+), effects: (.*)$'
DRIVER_LINE = r'\[driver_node\]: driving arm and actuator'


def test_sim_launch_arguments_override_the_parameter_file(prefix, tmp_path):
    """Ports, channels and effects given as launch arguments are the ones the nodes use."""
    sections = yaml.safe_load((ROOT / 'config' / 'nodes_sim.yaml').read_text())
    port = tmp_path / 'actuator_pty'
    channel = f'239.74.163.{(os.getpid() % 30) + 220}'
    yaml_port = sections['/**/sim_actuator_node']['ros__parameters']['port']
    yaml_channel = sections['/**/sim_arm_node']['ros__parameters']['can']['channel']
    assert (str(port), channel) != (yaml_port, yaml_channel)  # else the test proves nothing
    process = subprocess.Popen(
        ['ros2', 'launch', 'bellows_ros', 'sim.launch.py', 'scenario:=false',
         f'actuator_port:={port}', f'can_channel:={channel}',
         'actuator_effects:=[wall_bulging, air_leak]', 'arm_effects:=none'],
        env=_prefix_env(prefix), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        found, lines = _read_until(process, [ACTUATOR_LINE, ARM_LINE, DRIVER_LINE])
        pty_existed = port.exists()
        started = [int(pid) for pid in
                   re.findall(r'process started with pid \[(\d+)\]', ''.join(lines))]
        sessions = {pid: _session(pid) for pid in started}
    finally:
        _stop(process)
    log = ''.join(lines)
    assert len(found) == 3, log[-3000:]
    # Each node leads a session of its own (managed_launch.own_session): a scheduler autogroup
    # of its own, not one share for the whole graph.
    assert len(started) == 6 and all(sessions[pid] == pid for pid in started), sessions
    actuator, arm = found[ACTUATOR_LINE], found[ARM_LINE]
    assert actuator.group(1) == str(port)
    assert actuator.group(2).strip() == 'wall_bulging, air_leak'
    assert arm.group(1) == channel
    assert arm.group(2).strip() in ('', 'none')
    assert pty_existed  # the driver opened the board at the argument's path, not the file's


def test_hw_launch_port_argument_reaches_the_driver(prefix, tmp_path):
    """
    hw.launch.py: the driver opens the port given as argument; its absence ends the launch.

    The launch brings the managed driver to active: `configure` opens the port, fails, and the
    launch stops with an error rather than run a graph with an unconfigured driver.
    """
    port = tmp_path / 'no_such_board'
    run = subprocess.run(['ros2', 'launch', 'bellows_ros', 'hw.launch.py', 'arm:=false',
                          f'actuator_port:={port}'], env=_prefix_env(prefix),
                         capture_output=True, text=True, timeout=GUARD)
    log = run.stdout + run.stderr
    assert f'actuator board port {port} does not exist' in log, log[-3000:]
    assert run.returncode != 0, log[-3000:]
    assert 'driver_node could not be configured' in log, log[-3000:]


def test_shell_launcher_from_a_pip_install(ros, tmp_path):
    """
    scripts/launch_sim.sh as installed by a non-editable `pip install .` into a fresh venv.

    The package itself is installed (wheel built from this tree, no source tree on its path);
    its dependencies come from the running environment through a .pth file, so the test does not
    download or reinstall numpy, scipy, matplotlib and the ROS wheels.
    """
    venv = tmp_path / 'venv'
    subprocess.run([sys.executable, '-m', 'venv', '--without-pip', str(venv)], check=True)
    site = next((venv / 'lib').glob('python3*/site-packages'))
    # Plain path lines: the .pth files there (this checkout's editable install) are not run.
    deps = [p for p in sys.path if p.endswith('site-packages') and Path(p).is_dir()]
    (site / 'zz_test_deps.pth').write_text('\n'.join(deps) + '\n')
    python = venv / 'bin' / 'python'
    # Nothing of this checkout on the path (a PYTHONPATH set for the test run would shadow it).
    plain = {k: v for k, v in os.environ.items() if k != 'PYTHONPATH'}
    install = subprocess.run([str(python), '-m', 'pip', 'install', '--quiet', '--no-deps',
                              str(ROOT)], capture_output=True, text=True, timeout=GUARD,
                             env=plain)
    assert install.returncode == 0, install.stderr[-3000:]
    where = subprocess.run([str(python), '-c', 'import bellows_ros; print(bellows_ros.__file__)'],
                           cwd=tmp_path, capture_output=True, text=True, check=True,
                           env=plain).stdout.strip()
    assert where.startswith(str(venv)), where  # the installed copy, not this checkout
    launcher = venv / 'share' / 'bellows_ros' / 'scripts' / 'launch_sim.sh'
    assert launcher.is_file()
    out = tmp_path / 'out'
    # No checkout venv and no colcon install on PATH: the launcher must find its own prefix's bin/.
    path = ':'.join(p for p in os.environ['PATH'].split(':')
                    if not Path(p, 'driver_node').exists())
    env = _ros_env(PATH=path, AMENT_PREFIX_PATH=os.environ.get('AMENT_PREFIX_PATH', ''))
    env.pop('PYTHONPATH', None)
    env.pop('ROS_AUTOMATIC_DISCOVERY_RANGE')  # the launcher sets it for a simulation
    run = subprocess.run(['bash', str(launcher), '--duration', '12', '--output', str(out)],
                         cwd=tmp_path, env=env, capture_output=True, text=True, timeout=GUARD)
    log = run.stdout + run.stderr
    assert run.returncode == 0, log[-3000:]
    assert f'launch_sim: executables in {venv}/bin' in log
    assert 'stiffness step' in run.stdout
    counts = _series_counts(out / 'scenario.csv')
    for series in ('p1', 'psi', 'tau_drive', 'stiffness'):
        assert counts.get(series, 0) > 0, counts
    # The launcher's private pty path (node:name:=value) beat the file's sim_actuator_node port.
    board = (out / 'logs' / 'sim_actuator_node.log').read_text()
    assert re.search(r'simulated actuator board on \S+/bellows_sim_actuator\.\w+/board,', board), \
        board
    # The graph stops with the simulated devices last: the driver's vent at shutdown read
    # ambient on every chamber, rather than reporting that nothing answered.
    driver = (out / 'logs' / 'driver_node.log').read_text()
    assert 'shutdown: every device at rest' in driver, driver[-2000:]


def test_two_namespaced_graphs_run_side_by_side(prefix, tmp_path, monkeypatch):
    """
    `sim.launch.py namespace:=arm_a` beside `launch_sim.sh --namespace arm_b`, one domain.

    Graph b simulates two segments, graph a one: every sample on /arm_a/... names segment_1
    only, every one on /arm_b/... both, and nothing reaches the root namespace's topics.
    """
    from bellows_ros import interfaces
    from bellows_ros.runtime.messages import msg
    env = _prefix_env(prefix, ROS_DOMAIN_ID=free_domain())
    params = {}
    for graph, segments in (('a', 1), ('b', 2)):  # two light graphs on a 2-core machine
        config = yaml.safe_load((ROOT / 'config' / 'nodes_sim.yaml').read_text())
        # Normal scheduling: two graphs' SCHED_FIFO arms want more than two cores, and then
        # starve every node that is not one of them (once, an actuator silent for 60 s). This
        # test is about names; the arm's real-time path is the graph tests'.
        for section in config.values():
            if 'realtime_priority' in section['ros__parameters']:
                section['ros__parameters']['realtime_priority'] = 0
        config['/**/sim_arm_node']['ros__parameters']['n_segments'] = segments
        config['/**/driver_node']['ros__parameters']['arm']['n_segments'] = segments
        config['/**/model_node']['ros__parameters']['segments'] = list(range(1, segments + 1))
        params[graph] = tmp_path / f'nodes_{graph}.yaml'
        params[graph].write_text(yaml.safe_dump(config))
    params_b = params['b']
    graph_a = subprocess.Popen(['ros2', 'launch', 'bellows_ros', 'sim.launch.py',
                                'scenario:=false', 'namespace:=arm_a',
                                f"params_file:={params['a']}"], env=env,
                               stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
    graph_b = subprocess.Popen(['bash', str(ROOT / 'scripts' / 'launch_sim.sh'), '--no-scenario',
                                '--namespace', 'arm_b', '--params', str(params_b), '--output',
                                str(tmp_path / 'b')], env=env,
                               stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
    names = {'/arm_a': [], '/arm_b': [], '/': []}
    actuator_names = {'/arm_a': [], '/arm_b': [], '/': []}   # on the actuator's own topics
    actuator = {interfaces.actuator_sample_names()}
    arm_a = {interfaces.arm_sample_names([1])}
    arm_b = {interfaces.arm_sample_names([1, 2])}
    monkeypatch.setenv('ROS_DOMAIN_ID', env['ROS_DOMAIN_ID'])
    probe.init()
    try:
        watcher = probe.Node('namespace_probe')
        for namespace, seen in names.items():
            watcher.create_subscription(
                msg.JointState, interfaces.JOINT_STATES.resolved(namespace),
                lambda m, seen=seen: seen.append(tuple(m.name)), 1000)
            watcher.create_subscription(
                msg.JointState, interfaces.ACTUATOR_JOINT_STATES.resolved(namespace),
                lambda m, seen=actuator_names[namespace]: seen.append(tuple(m.name)), 1000)
        deadline = time.monotonic() + GUARD
        # Until each graph's arm speaks (its actuator may come up seconds earlier on a busy host)
        while not (set(names['/arm_a']) & arm_a and set(names['/arm_b']) & arm_b) \
                and time.monotonic() < deadline:
            probe.spin_once(watcher, timeout_sec=0.1)
        # Then until each arm has said over 100 things and each actuator something: this
        # process's rclpy probe takes in the two graphs' ~8000 messages/s far slower than they
        # come (41 in 3 s, on a loaded host), and an actuator starved by two graphs' SCHED_FIFO
        # arms may speak only after the arms have said their hundred.
        end = time.monotonic() + 60.0
        started = time.monotonic()
        while (min(len(names['/arm_a']), len(names['/arm_b'])) <= 100
               or not (actuator_names['/arm_a'] and actuator_names['/arm_b'])) \
                and time.monotonic() < end:
            probe.spin_once(watcher, timeout_sec=0.05)
        print(f"namespaces: {len(names['/arm_a'])} and {len(names['/arm_b'])} arm messages, "
              f"{len(actuator_names['/arm_a'])} and {len(actuator_names['/arm_b'])} actuator "
              f'messages taken in {time.monotonic() - started:.1f} s')
    finally:
        probe.shutdown()
        _stop(graph_a)
        _stop(graph_b)
    logs = '\n'.join(p.read_text()[-800:] for p in (tmp_path / 'b' / 'logs').glob('*.log'))
    assert len(names['/arm_a']) > 100 and len(names['/arm_b']) > 100, logs
    # The arm's topics carry the arm's samples only, the actuator's its own (#22 point 4).
    assert set(names['/arm_a']) <= arm_a and set(names['/arm_a']) & arm_a
    assert set(names['/arm_b']) <= arm_b and set(names['/arm_b']) & arm_b
    for namespace in ('/arm_a', '/arm_b'):
        assert actuator_names[namespace] and set(actuator_names[namespace]) <= actuator, logs
    assert names['/'] == [] and actuator_names['/'] == []


def test_shell_launchers_start_each_node_in_a_session_of_its_own(tmp_path):
    """
    scripts/node_processes.sh's start_node: the node leads a session (setsid), $! is the node.

    A session is a scheduler autogroup of its own (docs/nodes.md, "Timing"); stop_nodes still
    stops the node by its pid.
    """
    fake = tmp_path / 'bin' / 'fake_node'
    fake.parent.mkdir()
    fake.write_text('#!/bin/sh\nexec sleep 30\n')
    fake.chmod(0o755)
    script = f"""
        source {ROOT / 'scripts' / 'node_processes.sh'}
        bin={fake.parent}; common=(); extra=(); node_logs={tmp_path}
        start_node fake_node
        node=$!
        for _ in $(seq 50); do  # setsid runs in the child, a moment after the fork
          [ "$(awk '{{print $6}}' /proc/$node/stat)" = "$node" ] && break; sleep 0.1
        done
        echo "$node $(awk '{{print $6}}' /proc/$node/stat) $(awk '{{print $6}}' /proc/$$/stat)"
        stop_nodes
        kill -0 "$node" 2>/dev/null && echo alive || echo stopped
    """
    run = subprocess.run(['bash', '-c', script], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    ids, state = run.stdout.split('\n')[:2]
    node, session, launcher_session = ids.split()
    assert session == node != launcher_session, run.stdout
    assert state == 'stopped'
