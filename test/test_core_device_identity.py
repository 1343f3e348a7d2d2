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
Devices are ours or nobody's (issue #30, class 4).

After the simulated board is killed its link must not lead to the tty the kernel hands the next
program under that number, and the driver must take only the board it had: a port that does not
name itself with the board's IDENTITY, or names another board, is closed without a byte written
to it. A restarted board takes over its own stale link, and the driver reconnects to it.
"""
import dataclasses
import logging
import os
from pathlib import Path
import signal
import subprocess
import sys
import time
import tty

from polling import wait_for
import pytest

from bellows_ros.config.hardware import actuator_board_config
from bellows_ros.errors import ParameterError
from bellows_ros.hardware import serial_protocol as sp
from bellows_ros.hardware.actuator_board import ActuatorBoard
from bellows_ros.hardware.sim_actuator_board import ActuatorState, SimActuatorBoard

pytestmark = pytest.mark.realtime  # runs alone, after the others (scripts/test.sh)

CONFIG = actuator_board_config()
BOARD = """
import sys
from bellows_ros.hardware.sim_actuator_board import ActuatorState, SimActuatorBoard
board = SimActuatorBoard(lambda dt, duty: ActuatorState(0.0, 1e5, 0.0, 0.0), link_path=sys.argv[1])
board.start()
print('ready', flush=True)
sys.stdin.readline()
board.close()
"""


def plant(dt, duty):
    return ActuatorState(x_c=0.0, p=1e5, x_s=0.0, f=0.0)


def start_board(port):
    child = subprocess.Popen([sys.executable, '-c', BOARD, str(port)], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == 'ready'
    return child


def kill(child):
    child.send_signal(signal.SIGKILL)
    child.wait(timeout=30)


def take_a_pty_like(number):
    """Open ptys until the kernel hands out /dev/pts/`number` again (another program's tty)."""
    held = []
    for _ in range(64):
        master, slave = os.openpty()
        held.append((master, slave))
        if os.ttyname(slave) == f'/dev/pts/{number}':
            return master, slave, held
    return None, None, held


@pytest.fixture
def closing():
    things = []
    yield things.append
    for thing in reversed(things):
        if isinstance(thing, subprocess.Popen):
            if thing.poll() is None:
                thing.kill()
                thing.wait(timeout=30)
        elif isinstance(thing, int):
            os.close(thing)
        else:
            thing.close()


def test_a_killed_boards_link_leads_nowhere_not_to_the_next_programs_tty(tmp_path, closing):
    port = tmp_path / 'board'
    child = start_board(port)
    closing(child)
    number = os.path.realpath(port).rsplit('/', 1)[-1]
    kill(child)
    assert os.path.islink(port)      # a SIGKILL removes nothing
    master, slave, held = take_a_pty_like(number)
    for pair in held:
        closing(pair[0])
        closing(pair[1])
    if master is None:
        pytest.skip(f'the kernel did not hand out /dev/pts/{number} again')
    assert not os.path.exists(port), f'{port} leads to {os.path.realpath(port)}'


def test_a_restarted_board_takes_over_its_own_stale_link_and_the_driver_reconnects(
        tmp_path, closing, caplog):
    caplog.set_level(logging.INFO, logger='bellows_ros.hardware.actuator_board')
    port = tmp_path / 'board'
    child = start_board(port)
    closing(child)
    board = ActuatorBoard(dataclasses.replace(CONFIG, port=str(port)))
    closing(board)
    board.start()
    assert wait_for(lambda: board.read() is not None)
    first = getattr(board, 'serial', None)
    kill(child)
    assert wait_for(lambda: not board.connected)
    sim = SimActuatorBoard(plant, config=CONFIG, link_path=port)   # was: "a link exists there"
    closing(sim)
    sim.start()
    assert wait_for(lambda: board.health()['reconnects'] == 1 and board.read() is not None)
    assert board.serial == first == sim.serial
    assert board.health()['identity_refusals'] == 0


def test_a_live_boards_link_is_not_taken_over(tmp_path, closing):
    port = tmp_path / 'board'
    child = start_board(port)
    closing(child)
    before = os.readlink(port)
    with pytest.raises(ParameterError, match='exists there'):
        SimActuatorBoard(plant, link_path=port)
    assert os.readlink(port) == before


def test_the_driver_refuses_a_tty_that_does_not_name_itself_and_writes_nothing_to_it(
        tmp_path, closing, caplog):
    """The trial's case: the link led to a tty the kernel had given to another program."""
    caplog.set_level(logging.INFO, logger='bellows_ros.hardware.actuator_board')
    master, slave = os.openpty()
    closing(master)
    closing(slave)
    os.set_blocking(master, False)
    # The other program has its tty raw, as a serial program does. A new pty echoes what it is
    # sent back to the master until someone makes it raw, and the driver may open it only after
    # the greeting below: the echo would read as bytes the driver wrote.
    tty.setraw(slave)
    port = tmp_path / 'board'
    os.symlink(os.ttyname(slave), port)
    board = ActuatorBoard(dataclasses.replace(CONFIG, port=str(port), reconnect_interval=0.05))
    closing(board)
    board.start()
    os.write(master, b'some other program\x00\x01\x02\x00' * 10)
    assert wait_for(lambda: board.health().get('identity_refusals', 0) >= 2, timeout=30.0)
    assert not board.connected and board.read() is None
    assert board.write(0.5) == 0.0
    time.sleep(0.1)
    try:
        written = os.read(master, 4096)
    except BlockingIOError:
        written = b''
    assert written == b'', f'the driver wrote {written!r} to a device it does not know'
    messages = [r.getMessage() for r in caplog.records]
    assert not any('opened' in m or 'reconnected' in m for m in messages), messages
    assert sum('IDENTITY' in m for m in messages) == 1, messages   # said once, not every retry


def test_the_driver_refuses_another_board_on_its_port(tmp_path, closing, caplog):
    caplog.set_level(logging.INFO, logger='bellows_ros.hardware.actuator_board')
    port = tmp_path / 'board'
    first = SimActuatorBoard(plant, config=CONFIG, link_path=port)
    closing(first)
    first.start()
    board = ActuatorBoard(dataclasses.replace(CONFIG, port=str(port), reconnect_interval=0.05))
    closing(board)
    board.start()
    assert wait_for(lambda: board.read() is not None)
    first.close()
    other = SimActuatorBoard(plant, config=CONFIG, link_path=port, serial=first.serial + 1)
    closing(other)
    other.start()
    # On a loaded machine the first refusal may be a late IDENTITY; the serial is named once read.
    assert wait_for(lambda: any('another board' in r.getMessage() for r in caplog.records),
                    timeout=30.0), [r.getMessage() for r in caplog.records]
    assert board.health()['identity_refusals'] >= 1
    assert not board.connected and board.health()['reconnects'] == 0
    assert other.health()['motor_commands'] == other.health()['heartbeats'] == 0


def test_identity_frames_round_trip_and_leave_the_telemetry_sequence_alone():
    frame = sp.encode(sp.Identity(7, 0x0123456789ABCDEF))
    assert sp.FrameDecoder().feed(frame) == [sp.Identity(7, 0x0123456789ABCDEF)]


def test_the_serial_number_is_the_ports(tmp_path):
    from bellows_ros.hardware.sim_actuator_board import port_serial
    assert port_serial(tmp_path / 'a') == port_serial(Path(tmp_path) / '.' / 'a')
    assert port_serial(tmp_path / 'a') != port_serial(tmp_path / 'b')
