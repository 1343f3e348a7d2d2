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

"""The test session finds every process it started and left running (conftest.py's check)."""
import os
import signal
import subprocess
import time

from node_processes import session_processes


def test_a_process_left_behind_is_found_after_its_parent_ended():
    # The shell starts `sleep` in the background and exits: sleep is reparented to init, as a
    # node is when the launcher that started it was killed.
    shell = subprocess.run(['sh', '-c', 'sleep 60 >/dev/null 2>&1 & echo $!'],
                           capture_output=True, text=True, check=True)
    orphan = int(shell.stdout)
    try:
        # sh may exit while its child is still in execve, when /proc/<pid>/environ reads empty
        # (the new image's environment is not mapped yet): look again until it is.
        end = time.monotonic() + 10.0
        while orphan not in session_processes() and time.monotonic() < end:
            time.sleep(0.01)
        assert orphan in session_processes()
    finally:
        os.kill(orphan, signal.SIGKILL)
    end = time.monotonic() + 10.0   # the kill takes effect when the kernel next schedules it
    while orphan in session_processes() and time.monotonic() < end:
        time.sleep(0.01)
    assert orphan not in session_processes()


def test_a_process_started_outside_the_session_is_not_counted():
    environment = {k: v for k, v in os.environ.items() if k != 'BELLOWS_TEST_SESSION'}
    other = subprocess.Popen(['sleep', '60'], env=environment)
    try:
        assert other.pid not in session_processes()
    finally:
        other.kill()
        other.wait()
