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
Test session set-up: DDS on loopback, and the `runtime` fixture that runs a test on both runtimes.

Every test keeps its DDS traffic on this machine: ROS 2's own switch
(`ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`, which rclpy and the DDS runtime both honour) plus a
Cyclone configuration bound to the loopback interface with multicast off. The simulated CAN bus
joins its multicast group on loopback by itself (hardware/arm_bus.py).

The pytest process itself never imports rclpy (it uses the DDS runtime for its probes: one Cyclone
DDS library per process). A test that takes the `runtime` fixture runs twice, `[dds]` and
`[rclpy]`, and starts its nodes with `BELLOWS_RUNTIME` set accordingly (runtimes.py).
"""
import os

import pytest
from runtimes import LOOPBACK_ENVIRONMENT, require_rclpy

os.environ.setdefault('MPLBACKEND', 'Agg')
os.environ.update(LOOPBACK_ENVIRONMENT)
os.environ['BELLOWS_RUNTIME'] = 'dds'  # in-process nodes and probes; children get their own


@pytest.fixture(params=['dds', 'rclpy'])
def runtime(request):
    """Give the runtime the test's nodes run on ('dds' or 'rclpy'), in the test's id."""
    if request.param == 'rclpy':
        require_rclpy()
    return request.param


def pytest_report_header(config):
    from runtimes import rclpy_unavailable
    reason = rclpy_unavailable()
    rclpy = 'rclpy' if not reason else f'rclpy skipped ({reason})'
    return f'bellows runtimes: dds (Cyclone DDS), {rclpy}'


def pytest_terminal_summary(terminalreporter):
    """How many tests ran on each runtime, and how they ended."""
    counts = {}
    for outcome in ('passed', 'failed', 'skipped', 'error'):
        for report in terminalreporter.stats.get(outcome, []):
            for runtime in ('dds', 'rclpy'):
                if f'[{runtime}' in report.nodeid or f'-{runtime}]' in report.nodeid:
                    key = (runtime, outcome)
                    counts[key] = counts.get(key, 0) + 1
    for runtime in ('dds', 'rclpy'):
        line = ', '.join(f'{counts[(runtime, o)]} {o}'
                         for o in ('passed', 'failed', 'skipped', 'error')
                         if (runtime, o) in counts)
        if line:
            terminalreporter.write_line(f'runtime {runtime}: {line}')
