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
The "ROS 2 installed, colcon workspace" path, once.

A sourced Jazzy (rclpy 7.1.3 on rmw_cyclonedds_cpp, without the EventsExecutor),
`scripts/setup.sh` using its rclpy, `colcon build`, `ros2 launch bellows_ros sim.launch.py`, and
the driving torque counted by a plain rclpy subscriber of that ROS.

The ROS is the prebuilt Jazzy of `../shared/ros2` beside the checkout (as on CI), installed into
/opt/ros/jazzy by its own install.sh; elsewhere the test is skipped, saying why.
"""
import os
from pathlib import Path
import signal
import subprocess
import textwrap

from node_processes import free_domain
import pytest

# A venv, colcon, the whole graph: a minute. Not `realtime`: it asserts that the torque flows on
# the fallback executor, no rate, so it runs in the parallel phase beside the other tests.
pytestmark = pytest.mark.slow

TOP = Path(__file__).resolve().parent.parent
SHARED_ROS = TOP.parent / 'shared' / 'ros2'
ENV_LOOPBACK = '/opt/ros/jazzy/share/ros-jazzy-minimal/env_loopback.sh'

COUNT = textwrap.dedent("""\
    import sys, time
    import rclpy
    from rclpy.node import Node
    from sensor_msgs.msg import JointState
    rclpy.init()
    node = Node('torque_counter')
    seen = []
    node.create_subscription(JointState, '/bellows/driving_torque',
                             lambda m: seen.append((time.monotonic(), len(m.effort))), 1000)
    end = time.monotonic() + float(sys.argv[1])
    while time.monotonic() < end and len(seen) < 500:
        rclpy.spin_once(node, timeout_sec=0.05)
    if len(seen) < 2:
        print('torque messages: 0')
    else:
        rate = (len(seen) - 1) / (seen[-1][0] - seen[0][0])
        segments = sorted({n for _, n in seen})
        print(f'torque messages: {len(seen)} at {rate:.0f} Hz, segments {segments}')
    try:
        from rclpy.experimental.events_executor import EventsExecutor
        print('EventsExecutor')
    except ImportError:
        print('no EventsExecutor')
""")


def _bash(script, cwd, timeout, **kwargs):
    """Run `script` in bash with the sourced ROS (loopback only); the finished process."""
    return subprocess.run(['bash', '-c', f'set -eo pipefail; source {ENV_LOOPBACK}\n{script}'],
                          cwd=cwd, capture_output=True, text=True, timeout=timeout, **kwargs)


def test_colcon_build_and_ros2_launch_on_a_sourced_jazzy(tmp_path):
    if not (SHARED_ROS / 'install.sh').is_file():
        pytest.skip(f'no sourced-ROS build beside the checkout ({SHARED_ROS})')
    if not os.access('/opt', os.W_OK):
        pytest.skip('installing ../shared/ros2 needs write access to /opt/ros')
    installed = subprocess.run(['bash', str(SHARED_ROS / 'install.sh')], capture_output=True,
                               text=True, timeout=600)
    assert installed.returncode == 0, installed.stderr[-2000:]
    venv = tmp_path / 'venv'
    setup = _bash(f"""
        BELLOWS_VENV={venv} bash {TOP}/scripts/setup.sh
        PYTHON={venv}/bin/python bash {SHARED_ROS}/install.sh --pip >/dev/null
        {venv}/bin/python -m pip install --quiet colcon-common-extensions
        source {venv}/bin/activate
        colcon build --base-paths {TOP} --build-base build --install-base install
        """, tmp_path, timeout=1200)
    assert setup.returncode == 0, setup.stdout[-2000:] + setup.stderr[-2000:]
    # setup.sh took the sourced ROS's rclpy: no ROS wheels from PyPI in this venv.
    assert 'using the sourced ROS 2 jazzy' in setup.stderr
    assert not list((venv / 'lib').glob('python3*/site-packages/rclpy'))
    env = dict(os.environ, ROS_DOMAIN_ID=free_domain())
    env.pop('RMW_IMPLEMENTATION', None)  # that ROS has rmw_cyclonedds_cpp only
    log = open(tmp_path / 'launch.log', 'w')
    launch = subprocess.Popen(
        ['bash', '-c', f'source {ENV_LOOPBACK}; source {venv}/bin/activate; '
         'source install/setup.bash; exec env --default-signal=INT,QUIT '
         'ros2 launch bellows_ros sim.launch.py scenario:=false'],
        cwd=tmp_path, env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        (tmp_path / 'count.py').write_text(COUNT)
        counted = _bash(f'source {venv}/bin/activate; python count.py 120', tmp_path,
                        timeout=300, env=env)
        launched = (tmp_path / 'launch.log').read_text()
        assert counted.returncode == 0, counted.stdout + counted.stderr[-2000:]
        assert 'no EventsExecutor' in counted.stdout  # rclpy 7.1.3: the fallback path ran
        assert 'segments [4]' in counted.stdout, counted.stdout + launched[-3000:]
        assert 'SingleThreadedExecutor' in launched  # each node said which executor it took
    finally:
        if launch.poll() is None:
            os.killpg(launch.pid, signal.SIGINT)
        try:
            launch.wait(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(launch.pid, signal.SIGKILL)
            launch.wait()
        log.close()
