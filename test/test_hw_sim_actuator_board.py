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
The simulated actuator board touches only the link it made.

It creates its pty link only where nothing exists, repoints and removes it only while it is its
own, and a port named by mistake (a file, a directory, a device node, someone else's link) is an
error at start and stays as it was. As root, `port:=/dev/ttyACM0` once removed the device node.
"""
import os
from pathlib import Path
import stat
import subprocess
import sys

from node_processes import free_domain, node_env
import pytest

from bellows_ros.errors import ParameterError
from bellows_ros.hardware.sim_actuator_board import ActuatorState, SimActuatorBoard

pytestmark = pytest.mark.realtime  # runs alone, after the others (scripts/test.sh)

BIN = Path(sys.executable).parent


def plant(dt, duty):
    return ActuatorState(x_c=0.0, p=101325.0, x_s=0.0, f=0.0)


def snapshot(path):
    """Return what a path is now: kind, target or contents, mode, inode (a change shows)."""
    info = os.lstat(path)
    if stat.S_ISLNK(info.st_mode):
        return ('link', os.readlink(path), info.st_ino)
    if stat.S_ISREG(info.st_mode):
        return ('file', Path(path).read_bytes(), info.st_ino, info.st_mode)
    return ('other', info.st_mode, info.st_rdev, info.st_ino)


@pytest.fixture
def taken(tmp_path, request):
    """Make a path that something other than the board holds: a file, dir, link or fifo."""
    path = tmp_path / 'port'
    kind = request.param
    if kind == 'file':
        path.write_bytes(b'a measurement\n')
    elif kind == 'directory':
        path.mkdir()
        (path / 'inside').write_text('keep')
    elif kind == 'link':
        os.symlink('/dev/null', path)
    elif kind == 'dangling link':
        os.symlink(tmp_path / 'nothing', path)
    elif kind == 'fifo':
        os.mkfifo(path)
    return path


KINDS = ['file', 'directory', 'link', 'dangling link', 'fifo']


@pytest.mark.parametrize('taken', KINDS, indirect=True)
def test_a_taken_port_is_refused_and_left_as_it_is(taken):
    before = snapshot(taken)
    with pytest.raises(ParameterError, match=f'port {taken}: .* exists there'):
        SimActuatorBoard(plant, link_path=taken)
    assert snapshot(taken) == before
    assert sorted(p.name for p in taken.parent.iterdir()) == ['port']  # nothing left beside it


def test_a_device_node_is_refused_and_left_as_it_is(tmp_path):
    device = tmp_path / 'ttyACM0'   # a character device of our own (as /dev/null's: 1, 3)
    try:
        os.mknod(device, stat.S_IFCHR | 0o600, os.makedev(1, 3))
    except PermissionError:
        pytest.skip('making a device node needs root')
    before = snapshot(device)
    with pytest.raises(ParameterError, match='a device node exists there'):
        SimActuatorBoard(plant, link_path=device)
    assert snapshot(device) == before


def test_the_board_removes_its_own_link_and_nothing_else(tmp_path):
    port = tmp_path / 'board'
    board = SimActuatorBoard(plant, link_path=port)
    # its own slave, through /proc: a link to nothing once the board is gone
    # (test_core_device_identity)
    assert os.readlink(port).startswith(f'/proc/{os.getpid()}/fd/')
    assert os.path.realpath(port).startswith('/dev/pts/')
    board.unplug()
    assert not os.path.lexists(port)
    board.replug()                       # the link comes back where it was free
    assert os.path.islink(port)
    board.close()
    assert list(tmp_path.iterdir()) == []


def test_a_link_replaced_by_someone_else_is_not_removed(tmp_path):
    port = tmp_path / 'board'
    board = SimActuatorBoard(plant, link_path=port)
    os.unlink(port)
    port.write_text('a file someone put here meanwhile')
    board.close()
    assert port.read_text() == 'a file someone put here meanwhile'
    with pytest.raises(ParameterError, match='exists there'):
        board.replug()


@pytest.mark.slow
@pytest.mark.parametrize('taken', ['file', 'directory', 'link'], indirect=True)
def test_the_node_given_a_taken_port_exits_2_and_leaves_it(taken, tmp_path):
    before = snapshot(taken)
    env = node_env(ROS_DOMAIN_ID=free_domain())
    result = subprocess.run([str(BIN / 'sim_actuator_node'), '--ros-args', '-p',
                             f'port:={taken}'], capture_output=True, text=True, timeout=60,
                            env=env, cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and f'port {taken}' in lines[0], result.stderr
    assert snapshot(taken) == before
