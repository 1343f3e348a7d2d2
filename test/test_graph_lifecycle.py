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
driver_node is a managed node, driven from outside with ROS 2's own `ros2 lifecycle`.

The driver is an rclpy LifecycleNode; its transitions must be rcl_lifecycle's, with nothing added
or left out, as a bare rclpy LifecycleNode lists them through the same command line. Then a
simulated arm and the driver run as node processes, this process floods pressure commands (4 bar on
both chambers of segment 1) and watches their pressures on `/joint_states` while `ros2 lifecycle
set` drives the driver: nothing is published unconfigured; inactive publishes samples and refuses
commands; active obeys them; deactivate vents; a transition the state does not have is refused by
the command line and changes neither the state nor the chambers; cleanup closes the devices and a
new configure opens them again; a `~/vent` survives deactivate/activate until `~/release`; shutdown
vents and waits for ambient, and says after how long. The end of the process does the same from
active. Every transition a state does not offer, in each of the four states, is refused and leaves
the chambers as they were; shutdown is taken from each state that offers it.

Each verb goes through the command line once (`test_lifecycle_from_the_command_line`); the
repeats and the matrix of refusals ask the driver's lifecycle services from this process, as
the command line does (lifecycle_msgs' ChangeState, GetState, GetAvailableTransitions): a call of
the command line costs 3-10 s here, a service call milliseconds.
"""
import math
import random
import re
import signal
import subprocess
import sys
import textwrap
import time

from node_processes import (free_domain, launch, logs, node_env, override, require_ros2_cli,
                            ros2_cli, stop_all)
from polling import wait_for
import probe
import pytest

from bellows_ros import interfaces
from bellows_ros.runtime.messages import message_class, msg

ChangeState = message_class('lifecycle_msgs/srv/ChangeState')
GetState = message_class('lifecycle_msgs/srv/GetState')
GetAvailableTransitions = message_class('lifecycle_msgs/srv/GetAvailableTransitions')

# node processes and ros2 CLI calls, ~60 s
pytestmark = [pytest.mark.slow, pytest.mark.realtime]

AMBIENT = 101325.0
COMMAND = 4.0e5
VENTED = AMBIENT + 0.05 * (COMMAND - AMBIENT)  # a chamber below this is vented
VENT_LINE = re.compile(r'shutdown: every device at rest \(chambers within \S+ Pa of ambient\) '
                       r'after ([0-9.]+) s')

# An rclpy LifecycleNode with nothing of ours: the reference state machine.
REFERENCE = textwrap.dedent("""
    import rclpy
    from rclpy.lifecycle import LifecycleNode
    rclpy.init()
    node = LifecycleNode('reference_lifecycle')
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
        pass
""")


def ros2(args, env):
    """Run the ros2 command line; its stdout."""
    result = ros2_cli(args, env)
    assert result.returncode == 0, result.stdout + result.stderr
    return result.stdout


def test_the_state_machine_is_rcl_lifecycles(tmp_path):
    """`ros2 lifecycle list -a` and `list` read the same from the driver as from rclpy's node."""
    env = node_env(ROS_DOMAIN_ID=free_domain())
    reference = subprocess.Popen([sys.executable, '-c', REFERENCE], env=env)
    driver = launch('driver_node', override('driver_node', 'autostart', 'false')
                    + override('driver_node', 'actuator.enabled', 'false'), env, tmp_path)
    try:
        # Both must be up and discovered first (a loaded host starts a node in seconds).
        assert wait_for(lambda: {'/driver_node', '/reference_lifecycle'} <= set(
            ros2(['lifecycle', 'nodes'], env).split()), timeout=60)
        ours = ros2(['lifecycle', 'list', '/driver_node', '-a'], env)
        theirs = ros2(['lifecycle', 'list', '/reference_lifecycle', '-a'], env)
        # rcl lists the graph in its own order: compare the 25 transitions as a set.
        assert ours.count('\n- ') + ours.startswith('- ') == 25, ours
        assert sorted(ours.split('- ')) == sorted(theirs.split('- ')), (ours, theirs)
        assert ros2(['lifecycle', 'list', '/driver_node'], env) == ros2(
            ['lifecycle', 'list', '/reference_lifecycle'], env)
        assert ros2(['lifecycle', 'get', '/driver_node'], env).strip() == 'unconfigured [1]'
    finally:
        stop_all([reference, driver], timeout=15)


@pytest.fixture
def rig(tmp_path, monkeypatch):
    """Start a simulated arm (one segment); yield a starter of the driver and the probe."""
    domain = free_domain()
    group = f'239.74.169.{random.randint(2, 250)}'
    monkeypatch.setenv('ROS_DOMAIN_ID', domain)
    env = node_env(ROS_DOMAIN_ID=domain)
    normal = [('realtime_priority', 0)]
    processes = [launch('sim_arm_node', sum((override('sim_arm_node', k, v) for k, v in
                                             [('can.channel', group), ('n_segments', 1)]
                                             + normal), []), env, tmp_path)]

    def start_driver(autostart):
        processes.append(launch('driver_node', sum((override('driver_node', k, v) for k, v in
                                                    [('arm.channel', group),
                                                     ('arm.n_segments', 1),
                                                     ('actuator.enabled', 'false'),
                                                     ('autostart', autostart)] + normal), []),
                                env, tmp_path))
        return processes[-1]

    probe.init()
    try:
        yield start_driver, Probe(), env, tmp_path
    finally:
        stop_all(processes, timeout=15)
        probe.shutdown()


class Probe:
    """Floods pressure commands, records the chamber pressures and the driver's diagnostics."""

    def __init__(self):
        self.node = probe.Node('lifecycle_probe')
        self.pressures, self.status, self.not_found = [], {}, 0
        self.node.create_subscription(
            msg.JointState, interfaces.JOINT_STATES.resolved(),
            lambda m: self.pressures.append((time.monotonic(), probe.highest_pressure(m))), 1000)
        self.node.create_subscription(
            msg.DiagnosticArray, '/diagnostics',
            lambda a: self.status.update({s.name: {kv.key: kv.value for kv in s.values}
                                          for s in a.status}), 50)
        self.commands = self.node.create_publisher(
            msg.JointState, interfaces.PRESSURE_COMMAND.resolved(), 10)
        self.command = msg.JointState(name=[interfaces.chain_chamber(1, 1),
                                            interfaces.chain_chamber(1, 2)],
                                      effort=[COMMAND, COMMAND])
        # The driver's lifecycle services, as `ros2 lifecycle` asks them.
        self.services = {kind: self.node.create_client(kind, f'/driver_node/{name}')
                         for kind, name in ((ChangeState, 'change_state'),
                                            (GetState, 'get_state'),
                                            (GetAvailableTransitions,
                                             'get_available_transitions'))}

    def flood(self, seconds=0.0, until=None):
        """Publish commands for `seconds`, or while the process `until` runs; its stdout."""
        end = time.monotonic() + seconds
        while time.monotonic() < end or (until is not None and until.poll() is None):
            self.commands.publish(self.command)
            probe.spin_once(self.node, timeout_sec=0.001)
        return until.communicate()[0] if until is not None else None

    def lifecycle(self, env, *args, status=0):
        """
        `ros2 lifecycle ARGS /driver_node` while the commands keep coming; its output.

        Its exit status must be `status` (1: the command line refused the request; None: any,
        while the driver may not be discovered yet). A command line that has not discovered the
        driver within its spin time says 'Node not found' and is run again, for up to 60 s
        (`ros2_cli`'s rule; the count is printed).
        """
        require_ros2_cli()
        end = time.monotonic() + 60
        while True:
            process = subprocess.Popen(['ros2', 'lifecycle', *args[:1], '/driver_node',
                                        *args[1:], '--no-daemon', '--spin-time', '2'],
                                       env=env, stdout=subprocess.PIPE,
                                       stderr=subprocess.STDOUT, text=True)
            output = self.flood(until=process)
            if status is None or 'Node not found' not in output or time.monotonic() > end:
                break
            self.not_found += 1
            print(f'ros2 lifecycle {" ".join(args)}: Node not found ({self.not_found})')
        assert status is None or process.returncode == status, (args, output)
        return output

    def call(self, kind, request, timeout=60.0):
        """Call the driver's lifecycle service `kind` while commands keep coming; its answer."""
        client = self.services[kind]
        end = time.monotonic() + timeout
        while not client.service_is_ready() and time.monotonic() < end:
            self.flood(0.05)
        future = client.call_async(request)
        while not future.done() and time.monotonic() < end:
            self.flood(0.01)
        assert future.done(), f'no answer from /driver_node within {timeout} s'
        return future.result()

    def state(self):
        """Return the driver's state, as `ros2 lifecycle get` prints it ('inactive [2]')."""
        state = self.call(GetState, GetState.Request()).current_state
        return f'{state.label} [{state.id}]'

    def change(self, transition):
        """Ask the driver for `transition` by its label; whether it was taken."""
        request = ChangeState.Request()
        request.transition.label = transition
        return self.call(ChangeState, request).success

    def refused_in_process(self, transition, state):
        """Ask for a `transition` that `state` lacks: not offered, refused, nothing changes."""
        offered = self.call(GetAvailableTransitions, GetAvailableTransitions.Request())
        assert transition not in {t.transition.label for t in offered.available_transitions}
        assert not self.change(transition), f'{transition} taken in {state}'
        assert self.state() == state

    def until_unconfigured(self, env, seconds=30.0):
        """Ask `ros2 lifecycle get` until a driver started unmanaged says it is unconfigured."""
        deadline = time.monotonic() + seconds
        while 'unconfigured' not in self.lifecycle(env, 'get', status=None) \
                and time.monotonic() < deadline:
            time.sleep(0.2)

    def refused(self, env, transition, state):
        """`ros2 lifecycle set` of a `transition` that `state` lacks: refused, nothing changes."""
        output = self.lifecycle(env, 'set', transition, status=1)
        assert 'Unknown transition requested' in output, output
        assert f'- {transition} [' not in output, output  # not among those offered
        assert self.lifecycle(env, 'get').strip() == state

    def since(self, start):
        return [p for t, p in self.pressures if t > start]

    def later(self, seconds, settle=1.0):
        """Flood for `seconds`; return the pressures seen once `settle` s had gone."""
        start = time.monotonic()
        self.flood(seconds)
        return self.since(start + settle)

    def watchdog_vents(self):
        """Return the driver's count of watchdog vents, from its next /diagnostics report."""
        self.status.pop('driver_node: arm', None)
        deadline = time.monotonic() + 10
        while 'driver_node: arm' not in self.status and time.monotonic() < deadline:
            self.flood(0.1)
        assert 'driver_node: arm' in self.status, 'no /diagnostics from the driver within 10 s'
        return int(self.status['driver_node: arm']['watchdog_vents'])

    def pressurise(self, log_dir):
        deadline = time.monotonic() + 40
        while (not self.pressures or self.pressures[-1][1] < 0.9 * COMMAND) \
                and time.monotonic() < deadline:
            self.flood(0.2)
        assert self.pressures[-1][1] > 0.9 * COMMAND, logs(log_dir)


def test_lifecycle_from_the_command_line(rig):
    start_driver, probe, env, log_dir = rig
    start_driver('false')
    probe.until_unconfigured(env)
    probe.flood(1.0)
    assert not probe.pressures, 'samples published while unconfigured'
    probe.refused(env, 'activate', 'unconfigured [1]')
    probe.flood(1.0)
    assert not probe.pressures, 'samples published after a refused activate'

    assert 'successful' in probe.lifecycle(env, 'set', 'configure'), logs(log_dir)
    assert probe.lifecycle(env, 'get').strip() == 'inactive [2]'
    inactive = probe.later(1.5, settle=0.0)
    assert inactive and max(inactive) < VENTED, 'commands obeyed while inactive'
    assert probe.status['driver_node: arm']['lifecycle'] == 'inactive'
    probe.refused_in_process('configure', 'inactive [2]')
    inactive = probe.later(1.5, settle=0.0)
    assert inactive and max(inactive) < VENTED, 'commands obeyed after a refused configure'

    assert 'successful' in probe.lifecycle(env, 'set', 'activate')
    assert probe.state() == 'active [3]'
    probe.pressurise(log_dir)
    vents = probe.watchdog_vents()
    probe.refused_in_process('cleanup', 'active [3]')
    active = probe.later(1.5, settle=0.0)
    assert active, 'no samples after a refused cleanup'
    if min(active) <= 0.9 * COMMAND:
        # A dip the transition did not cause: this process's flood paused past the driver's
        # command watchdog (once, in CI, on the shared host), the driver vented and counted it.
        # It still obeys: the commands take again.
        probe.pressurise(log_dir)
        assert probe.watchdog_vents() > vents, 'a refused cleanup stopped the commands'
    assert 'successful' in probe.lifecycle(env, 'set', 'deactivate')
    assert probe.state() == 'inactive [2]'
    assert max(probe.later(3.0, settle=1.5)) < VENTED, 'deactivate did not vent'

    # cleanup closes the devices (no samples), configure opens them again, vented
    assert 'successful' in probe.lifecycle(env, 'set', 'cleanup'), logs(log_dir)
    assert probe.state() == 'unconfigured [1]'
    assert not probe.later(2.0, settle=0.5), 'samples published after cleanup'
    assert probe.change('configure'), logs(log_dir)
    reconfigured = probe.later(1.5, settle=0.0)
    assert reconfigured and max(reconfigured) < VENTED, 'configured again: not vented'
    assert probe.change('activate')
    probe.pressurise(log_dir)

    # A latched vent outlives deactivate/activate: only ~/release ends it.
    ros2(['service', 'call', '/driver_node/vent', 'std_srvs/srv/Trigger'], env)
    assert probe.change('deactivate')
    assert probe.change('activate')
    assert max(probe.later(2.0)) < VENTED, 'activate released a latched vent'
    ros2(['service', 'call', '/driver_node/release', 'std_srvs/srv/Trigger'], env)
    probe.pressurise(log_dir)

    assert 'successful' in probe.lifecycle(env, 'set', 'shutdown')
    assert probe.state() == 'finalized [4]'
    log = (log_dir / 'driver_node.log').read_text()
    vent = VENT_LINE.search(log)
    assert vent, log[-2000:]
    assert float(vent.group(1)) > 0.0  # it was pressurised: venting takes time
    probe.refused_in_process('configure', 'finalized [4]')
    print(f'vent to ambient after shutdown: {float(vent.group(1)):.3f} s')


def test_the_end_of_the_process_vents_and_waits_for_ambient(rig):
    start_driver, probe, env, log_dir = rig
    driver = start_driver('true')
    probe.pressurise(log_dir)
    driver.send_signal(signal.SIGINT)
    while driver.poll() is None:
        probe.flood(0.05)
    assert driver.returncode == 0, logs(log_dir)
    log = (log_dir / 'driver_node.log').read_text()
    vent = VENT_LINE.search(log)
    assert vent, log[-2000:]
    assert float(vent.group(1)) > 0.0  # it was pressurised: venting takes time
    print(f'vent to ambient at SIGINT: {float(vent.group(1)):.3f} s')


# rcl_lifecycle's primary states and the transitions each offers; every other one is refused.
TRANSITIONS = ('configure', 'cleanup', 'activate', 'deactivate', 'shutdown')
OFFERED = {'unconfigured [1]': {'configure', 'shutdown'},
           'inactive [2]': {'cleanup', 'activate', 'shutdown'},
           'active [3]': {'deactivate', 'shutdown'},
           'finalized [4]': set()}


def test_every_transition_a_state_lacks_is_refused_while_commands_stream(rig):
    """
    Each state against each transition it does not offer: refused, state and chambers unchanged.

    The test above takes the offered ones (and one refusal per state); this one takes the rest,
    then shuts down from inactive (the test below: from unconfigured, the one above: from active).
    """
    start_driver, probe, env, log_dir = rig
    start_driver('false')
    assert probe.state() == 'unconfigured [1]'

    seen = []   # (state, refused transition, samples, lowest and highest chamber pressure)

    def refuse_the_rest(state, check):
        for transition in TRANSITIONS:
            if transition not in OFFERED[state]:
                probe.refused_in_process(transition, state)
                after = probe.later(1.0, settle=0.0)
                seen.append((state, transition, len(after), min(after, default=math.nan),
                             max(after, default=math.nan)))
                check(after, transition)

    def no_samples(seen, transition):
        assert not seen, f'samples published after a refused {transition}'

    def vented(seen, transition):
        assert seen and max(seen) < VENTED, f'commands obeyed after a refused {transition}'

    def obeyed(seen, transition):
        # At the command where the window ends: the flood itself can stall past the driver's
        # 0.1 s watchdog while a ros2 command line starts on the two cores, a dip that is not
        # the transition's.
        assert seen and seen[-1] > 0.9 * COMMAND, f'a refused {transition} stopped the commands'
        assert probe.status['driver_node: arm']['lifecycle'] == 'active'

    refuse_the_rest('unconfigured [1]', no_samples)
    assert probe.change('configure'), logs(log_dir)
    refuse_the_rest('inactive [2]', vented)
    assert probe.change('activate')
    probe.pressurise(log_dir)
    refuse_the_rest('active [3]', obeyed)
    assert probe.change('deactivate')
    assert max(probe.later(3.0, settle=1.5)) < VENTED, 'deactivate did not vent'
    assert probe.change('shutdown')
    assert probe.state() == 'finalized [4]'
    assert VENT_LINE.search((log_dir / 'driver_node.log').read_text()), logs(log_dir)
    refuse_the_rest('finalized [4]', no_samples)
    for state, transition, count, low, high in seen:
        print(f'{state:16} {transition:10} refused; {count:4} samples in the next 1 s, chambers '
              f'{low / 1e3:.1f}..{high / 1e3:.1f} kPa abs')


def test_shutdown_from_unconfigured_ends_finalized_with_nothing_driven(rig):
    start_driver, probe, env, log_dir = rig
    start_driver('false')
    assert probe.state() == 'unconfigured [1]'
    assert probe.change('shutdown'), logs(log_dir)
    assert probe.state() == 'finalized [4]'
    assert not probe.later(1.5, settle=0.0), 'samples published after shutdown'
    assert probe.status.get('driver_node: arm', {}).get('lifecycle') in (None, 'finalized')
    probe.refused_in_process('configure', 'finalized [4]')
