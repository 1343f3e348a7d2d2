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
bench/graph_actuator.py without its graph: the nodes it starts and the figures it makes.

`_measure` runs against a scripted stand-in for GraphRun (graph_run_stub.py): the start order
(every consumer before the driver), each node's command and device links, and the records made
of the /diagnostics reports (medians of the 1 s rates, scheduling, CPU per node). The graph over
real DDS is test_graph_bench.py's. No time is asserted.
"""
from pathlib import Path
import re
import sys

from graph_run_stub import StubGraphRun
import pytest

from bellows_ros.bench import graph_actuator
from bellows_ros.bench.graph import CAN_GROUPS, DOMAINS
from bellows_ros.io import params


def reports(model_hz, control_hz):
    return {'model_node: driving torque': {'rate_hz': model_hz, 'scheduling': 'SCHED_FIFO 60'},
            'stiffness_controller_node: control': {'rate_hz': control_hz,
                                                   'scheduling': 'SCHED_OTHER'}}


SCRIPT = {
    # Every consumer reporting, and the driver publishing both device groups' samples.
    'running': {**reports(1000.0, 200.0),
                'arm_controller_node: segment_1': {'scheduling': 'SCHED_FIFO 50'},
                'driver_node: arm': {'published': 10, 'scheduling': 'SCHED_FIFO 55'},
                'driver_node: actuator': {'published': 10}},
    'window': [reports(990.0, 190.0), reports(1005.0, 230.0), reports(1000.0, 200.0)],
    'stopped': {},
    'cpu': {name: 0.1 * (k + 1) for k, name in enumerate(graph_actuator.NODES)},
    'steal': 0.03,
}


@pytest.fixture
def measured(monkeypatch, tmp_path):
    """Run `_measure` over the script: (the stand-in, {name: Result})."""
    stub = StubGraphRun(SCRIPT, tmp_path)
    monkeypatch.setattr(graph_actuator, 'GraphRun', stub)
    results = graph_actuator._measure('graph_actuator', 3.0)
    return stub, {result.name: result for result in results}


def test_the_rate_is_the_median_of_the_model_nodes_reports_in_the_window(measured):
    _, results = measured
    rate = results['graph_actuator.rate']
    # Only the window's reports: the 1000 Hz reported while settling is not counted again.
    assert (rate.value, rate.unit, rate.samples, rate.target) == (1000.0, 'Hz', 3, 1000.0)
    assert rate.extra['stiffness_control_hz'] == 200.0 and rate.extra['steal'] == 0.03
    assert rate.extra_units == {'steal': '', 'stiffness_control_hz': 'Hz'}
    # The scheduling each node reported, by node.
    assert rate.extra['scheduling'] == {
        'model_node': 'SCHED_FIFO 60', 'stiffness_controller_node': 'SCHED_OTHER',
        'arm_controller_node': 'SCHED_FIFO 50', 'driver_node': 'SCHED_FIFO 55'}


def test_each_node_has_its_cpu_figure(measured):
    _, results = measured
    cpu = [f'graph_actuator.cpu.{name}' for name in graph_actuator.NODES]
    assert list(results) == ['graph_actuator.rate', *cpu]
    for name, core in SCRIPT['cpu'].items():
        figure = results[f'graph_actuator.cpu.{name}']
        assert (figure.value, figure.unit, figure.samples) == (core, 'core', 1)


def test_the_consumers_start_before_the_driver_on_one_bus_and_one_pty(measured):
    stub, _ = measured
    assert list(stub.started) == list(graph_actuator.NODES)
    assert list(stub.started)[-1] == 'driver_node'  # its consumers listen first
    assert {name.split(':')[0] for name in graph_actuator.CONSUMERS} < set(graph_actuator.NODES)
    low, high = DOMAINS['graph_actuator']
    assert low <= int(stub.domain) <= high
    binary = Path(sys.executable).parent
    given = {}
    for name, (command, env) in stub.started.items():
        assert command[:4] == [str(binary / name), '--ros-args', '--params-file',
                               str(graph_actuator.CONFIG)]
        assert set(command[4::2]) <= {'-p'}
        assert env['ROS_DOMAIN_ID'] == stub.domain
        given[name] = dict(re.fullmatch(rf'{name}:(.+):=(.*)', value).groups()
                           for value in command[5::2])
    # The simulated devices and the driver share this bench's CAN group and a pty in its logs.
    group = given['sim_arm_node']['can.channel']
    assert re.fullmatch(re.escape(CAN_GROUPS['graph_actuator']) + r'\.\d+', group)
    assert given['driver_node']['arm.channel'] == group
    assert given['sim_actuator_node']['port'] == given['driver_node']['actuator.port'] == \
        str(stub.logs / 'actuator')
    assert given['driver_node']['autostart'] == 'true'


def test_quick_measures_over_a_shorter_window(monkeypatch):
    windows = []
    monkeypatch.setattr(graph_actuator, '_measure',
                        lambda prefix, window: windows.append((prefix, window)) or [])
    graph_actuator.run(quick=True)
    graph_actuator.run()
    assert windows == [('graph_actuator', 3.0), ('graph_actuator', 10.0)]


def test_every_node_is_launch_sims_with_its_section_in_the_config():
    launch = (Path(__file__).resolve().parent.parent / 'scripts' / 'launch_sim.sh').read_text()
    started = set(re.findall(r'start (\w+_node)', launch))
    assert set(graph_actuator.NODES) <= started
    for name in graph_actuator.NODES:
        assert isinstance(params.read_file(graph_actuator.CONFIG, name), dict), name
