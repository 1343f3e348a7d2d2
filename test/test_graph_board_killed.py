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
The board killed under a running driver: the driver says so, keeps the motor still, survives.

The simulated actuator board (a process) is killed with SIGKILL while the driver (a node
process) drives it. The driver must stay up, report the actuator ERROR (no data) on
/diagnostics, and send no motor duty to a board it cannot see; when a board comes back on the
same port, it reconnects and data flow again. SIGINT then ends the driver with status 0.
"""
import os
import signal
import time

from node_processes import free_domain, launch, logs, node_env, override
import probe
import pytest

from bellows_ros.nodes.diagnostics import ERROR, level_of
from bellows_ros.runtime import stamp_ns
from bellows_ros.runtime.messages import msg

# node processes, ~20 s
pytestmark = [pytest.mark.slow, pytest.mark.realtime]


def test_a_board_killed_under_the_driver_is_reported_and_survived(tmp_path, monkeypatch):
    domain = free_domain()
    monkeypatch.setenv('ROS_DOMAIN_ID', domain)
    env = node_env(ROS_DOMAIN_ID=domain)
    port = str(tmp_path / 'board')
    normal = [('realtime_priority', 0)]

    def board():
        return launch('sim_actuator_node', sum((override('sim_actuator_node', k, v) for k, v
                                                in [('port', port)] + normal), []), env,
                      tmp_path)
    sim = board()
    probe.init()
    driver = None
    try:
        deadline = time.monotonic() + 30
        while not os.path.islink(port) and time.monotonic() < deadline:
            time.sleep(0.05)
        driver = launch('driver_node', sum((override('driver_node', k, v) for k, v in
                                            [('actuator.port', port), ('arm.enabled', 'false')]
                                            + normal), []), env, tmp_path)
        watcher = probe.Node('board_probe')
        status, samples = {}, []
        watcher.create_subscription(
            msg.DiagnosticArray, '/diagnostics',
            lambda a: status.update({s.name: (level_of(s.level), s.message) for s in a.status}),
            50)
        # each sample by its stamp (the driver's clock: the system's), not by when this process
        # got round to it: on a loaded machine the probe works off a backlog
        watcher.create_subscription(msg.JointState, '/actuator/joint_states',
                                    lambda m: samples.append(stamp_ns(m.header.stamp) * 1e-9),
                                    1000)

        def spin_until(condition, seconds):
            end = time.monotonic() + seconds
            while not condition() and time.monotonic() < end:
                probe.spin_once(watcher, timeout_sec=0.05)
            return condition()

        assert spin_until(lambda: len(samples) > 500, 40), logs(tmp_path)
        sim.send_signal(signal.SIGKILL)
        sim.wait()
        killed = time.time()
        assert spin_until(lambda: status.get('driver_node: actuator', (0,))[0] == ERROR, 15), \
            (status, logs(tmp_path))
        spin_until(lambda: False, max(0.0, killed + 2.0 - time.time()))
        assert driver.poll() is None, logs(tmp_path)
        assert not [t for t in samples if t > killed + 1.0]          # no samples from nowhere
        # A board comes back on the same port: the dead one's link is gone from a fresh path.
        os.unlink(port)  # the killed simulator could not remove its link (SIGKILL): the test
        sim = board()    # made the path, and clears what the killed process left there
        back = time.time()
        assert spin_until(lambda: len([t for t in samples if t > back]) > 200, 40), \
            logs(tmp_path)
        driver.send_signal(signal.SIGINT)
        assert driver.wait(timeout=20) == 0, logs(tmp_path)
    finally:
        for process in (sim, driver):
            if process is not None and process.poll() is None:
                process.kill()
                process.wait()
        probe.shutdown()
