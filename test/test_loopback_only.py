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
Loopback means loopback: the simulated CAN bus and a whole simulated launch send nothing off-host.

The launch's DDS is rclpy's (rmw_fastrtps_cpp): discovery and traffic kept on the host by
ROS 2's own ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, which the launcher sets itself.

Counted, not assumed: each case runs in a private network namespace that has a way off the machine
(a veth pair with the default route, netns_run.sh), and the packets that left through it are
counted. A control case shows the counter sees what python-can's own udp_multicast backend sends.
"""
from pathlib import Path
import random
import re
import socket
import subprocess
import sys

from node_processes import node_env
import pytest

from bellows_ros.errors import ParameterError
from bellows_ros.hardware.arm_bus import open_can

pytestmark = pytest.mark.realtime  # runs alone, after the others (scripts/test.sh)

HERE = Path(__file__).resolve().parent
NETNS_RUN = HERE / 'netns_run.sh'
LAUNCH_SIM = HERE.parent / 'scripts' / 'launch_sim.sh'

SEND_AND_RECEIVE = """
import sys
import can
from bellows_ros.hardware.arm_bus import open_can
group, port, backend = sys.argv[1], int(sys.argv[2]), sys.argv[3]
make = ((lambda: open_can('udp_multicast', group, port=port)) if backend == 'bellows'
        else (lambda: can.Bus(interface='udp_multicast', channel=group, port=port)))
sender, receiver = make(), make()
message = can.Message(arbitration_id=0x101, data=bytes(8), is_extended_id=False)
for _ in range(50):
    sender.send(message)
received = 0
while receiver.recv(timeout=0.3) is not None:
    received += 1
print('received', received)
sender.shutdown()
receiver.shutdown()
"""


def _netns_unavailable():
    try:
        probe = subprocess.run(['unshare', '-n', 'true'], capture_output=True, timeout=10)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return str(exc)
    return '' if probe.returncode == 0 else probe.stderr.decode().strip()


needs_netns = pytest.mark.skipif(bool(_netns_unavailable()),
                                 reason='no private network namespace here (needs root)')


def in_netns(command, env=None, timeout=120):
    """Run `command` in a private namespace; return (its output, packets that left the host)."""
    result = subprocess.run(['unshare', '-n', str(NETNS_RUN), *command], capture_output=True,
                            text=True, timeout=timeout, env=env)
    found = re.search(r'^off-machine packets: (\d+)$', result.stdout, re.MULTILINE)
    assert found, result.stdout + result.stderr
    return result, int(found.group(1))


@pytest.mark.parametrize('channel', ['localhost', 'example.invalid', '10.0.0.1', '127.0.0.1',
                                     '255.255.255.255', 'ff15::1', '239.74.163', '', 'can0'])
def test_a_channel_that_is_not_an_ipv4_multicast_address_is_refused_before_any_lookup(
        channel, monkeypatch):
    looked_up = []
    monkeypatch.setattr(socket, 'getaddrinfo', lambda *a, **k: looked_up.append(a) or [])
    monkeypatch.setattr(socket, 'socket', lambda *a, **k: looked_up.append(a))
    with pytest.raises(ParameterError, match='IPv4 multicast group'):
        open_can('udp_multicast', channel)
    assert looked_up == []


@needs_netns
def test_the_simulated_bus_sends_nothing_off_the_machine():
    group, port = f'239.74.172.{random.randint(2, 250)}', 45000 + random.randint(0, 999)
    result, sent = in_netns([sys.executable, '-c', SEND_AND_RECEIVE, group, str(port), 'bellows'])
    assert 'received 50' in result.stdout, result.stdout + result.stderr
    assert sent == 0
    # The control: python-can's own backend, in the same harness, is seen leaving the host.
    result, sent = in_netns([sys.executable, '-c', SEND_AND_RECEIVE, group, str(port), 'python'])
    assert sent >= 50, result.stdout + result.stderr


@needs_netns
@pytest.mark.slow
def test_a_whole_simulated_launch_sends_nothing_off_the_machine(tmp_path):
    """launch_sim.sh (every simulated device and node, and the scenario) in the namespace."""
    venv = Path(sys.executable).parent.parent
    # From a checkout the launcher first runs scripts/setup.sh, which reinstalls bellows_ros
    # (pip, editable, from this checkout) into BELLOWS_VENV when its stamp is older than
    # setup.py: in the namespace that is pip reaching for PyPI (packets off the machine, none of
    # the launch's), and out of it a venv shared with other checkouts re-pointed to this one.
    stamp = venv / '.bellows-installed'
    if not stamp.is_file() or (HERE.parent / 'setup.py').stat().st_mtime > stamp.stat().st_mtime:
        pytest.fail(f'{venv}: not set up for this checkout (scripts/setup.sh would reinstall '
                    'bellows_ros into it from inside the test): run scripts/setup.sh first')
    env = node_env(BELLOWS_VENV=str(venv))
    # What the launcher itself must set: nothing of the test session's loopback settings
    # (node_processes.LOOPBACK_ENVIRONMENT), not even the UDP-only transport.
    for name in ('ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_STATIC_PEERS', 'FASTDDS_BUILTIN_TRANSPORTS',
                 'ROS_LOCALHOST_ONLY'):
        env.pop(name, None)
    result, sent = in_netns(['bash', str(LAUNCH_SIM), '--duration', '5', '--output',
                             str(tmp_path)], env=env, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    assert (tmp_path / 'scenario.csv').is_file()
    assert sent == 0, result.stdout + result.stderr[-3000:]
    print(f'whole simulated launch on {env.get("RMW_IMPLEMENTATION") or "the default RMW"}: '
          f'{sent} packets off the machine')
