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
bench/graph.py's parts that run no node graph: the grid, the figures, GraphRun's bookkeeping.

What `_measure` makes of a graph's /diagnostics reports (medians, the fraction evaluated, the
late fraction, the latency ratio to its in-process reference, the nodes' commands) is held
against a scripted stand-in for GraphRun (graph_run_stub.py). GraphRun itself is entered with
plain short-lived processes, not nodes. The whole bench over real DDS is test_graph_bench.py's.
No time is asserted (shared machine).
"""
import math
import os
from pathlib import Path
import sys
import time

from graph_run_stub import StubGraphRun
from node_processes import free_domain
import pytest

from bellows_ros.bench import graph, Result
from bellows_ros.errors import BellowsError
from bellows_ros.runtime import realtime
from bellows_ros.runtime.node import LOOPBACK_ENVIRONMENT


def latency_requests_held():
    """Return this process's open file descriptors on the PM QoS device (its requests)."""
    fds = Path('/proc/self/fd')
    return [fd for fd in fds.iterdir()
            if os.path.realpath(fd) == os.path.realpath(realtime.CPU_LATENCY_DEVICE)]


@pytest.mark.realtime  # a 1 kHz loop for 1 s: runs alone, after the others (scripts/test.sh)
def test_the_wakeup_reference_measures_a_lone_1khz_loop():
    """
    What the bench controls: its own PM QoS request, in force while it runs, withdrawn after.

    The limit in force is the least of every process's request on the host: ours can only be
    lowered by others, never raised, so the run saw at most what it asked for.
    """
    start = time.perf_counter()
    result = graph._wakeup_reference('reference', 1.0, priority=50, latency_limit=123e-6)
    elapsed = time.perf_counter() - start
    assert result.extra['cpu_latency_requested'] == 123e-6
    if os.access(realtime.CPU_LATENCY_DEVICE, os.W_OK):
        assert result.extra['cpu_latency_limit'] <= 123e-6   # held while it ran
    assert latency_requests_held() == []                      # and withdrawn after
    ticks, slots = result.samples, result.extra['slots']
    # Every 1 ms slot the loop lived through either ticked or was counted missed; how many slots
    # that is depends on how long the (shared) machine took, so the bound is the time measured
    # here.
    assert 1 <= ticks <= slots <= math.floor(elapsed / 1e-3) + 1
    assert result.extra['slots_missed'] == (slots - ticks) / slots
    assert 0.0 <= result.extra['p50'] <= result.value <= result.extra['max']
    assert result.extra['scheduling'] in ('SCHED_FIFO 50', 'SCHED_OTHER')
    if os.access('/proc/stat', os.R_OK):  # where the kernel tells, steal is a fraction
        assert 0.0 <= result.extra['steal'] <= 1.0
    else:
        assert math.isnan(result.extra['steal'])


def test_the_quick_run_covers_the_grid():
    """`--quick` measures a few variants of the grid that take every value of each dimension."""
    grid, quick = graph.variants(), graph.variants(quick=True)
    assert set(quick) <= set(grid) and len(quick) < len(grid)
    for dimension in (1, 2, 3):  # privilege, composed, segments
        assert {v[dimension] for v in quick} == {v[dimension] for v in grid}, dimension


def test_each_variant_is_named_by_its_marks():
    # graph[.user][.composed][.1seg]: a mark for each value off the default (root, separate, 4).
    assert {prefix: rest for prefix, *rest in graph.variants()} == {
        'graph': ['root', False, 4], 'graph.1seg': ['root', False, 1],
        'graph.composed': ['root', True, 4], 'graph.composed.1seg': ['root', True, 1],
        'graph.user': ['user', False, 4], 'graph.user.1seg': ['user', False, 1],
        'graph.user.composed': ['user', True, 4], 'graph.user.composed.1seg': ['user', True, 1]}
    assert [prefix for prefix, *_ in graph.variants(quick=True)] == list(graph.QUICK_VARIANTS)


def test_the_benches_domains_are_apart_from_each_other_and_the_tests():
    # The tests draw from 1-101; Fast DDS's ports of 102-214 fall among the ephemeral ports.
    taken = [set(range(low, high + 1)) for low, high in graph.DOMAINS.values()]
    assert all(domains <= set(range(215, 233)) for domains in taken)
    assert sum(map(len, taken)) == len(set().union(*taken))
    assert len(set(graph.CAN_GROUPS.values())) == len(graph.CAN_GROUPS) == len(graph.DOMAINS)


def test_a_node_process_runs_on_its_domain_on_loopback(monkeypatch):
    monkeypatch.setenv('ROS_DOMAIN_ID', '7')
    env = graph.node_environment('216', PYTHONFAULTHANDLER='1')
    assert env['ROS_DOMAIN_ID'] == '216' and env['PYTHONFAULTHANDLER'] == '1'
    assert LOOPBACK_ENVIRONMENT.items() <= env.items()
    assert env['PATH'] == os.environ['PATH']  # the rest of the bench's environment


def test_steal_is_the_share_of_all_cpu_time_between_two_readings():
    # /proc/stat's first line: user nice system idle iowait irq softirq steal (jiffies).
    before = [100, 0, 50, 800, 0, 0, 0, 10]
    after = [200, 0, 100, 1000, 0, 0, 0, 60]
    assert graph._steal_fraction(before, after) == 50 / 400
    assert math.isnan(graph._steal_fraction(None, after))       # /proc/stat not readable
    assert math.isnan(graph._steal_fraction(before, after[:7]))  # a kernel without steal
    assert math.isnan(graph._steal_fraction(before, before))     # no time passed
    assert graph._hold_latency_limit(-1.0) is None               # negative: no request


# What a graph's nodes report on /diagnostics (values are strings, as in a KeyValue).
FIFO = {'sim_arm_node': 'SCHED_FIFO 60', 'model_node': 'SCHED_FIFO 60',
        'driver_node': 'SCHED_FIFO 55'}


def model_window(rate, p50_us, p99_us, late, evaluated):
    return {'model_node: driving torque': {
        'rate_hz': rate, 'latency_p50_us': p50_us, 'latency_p99_us': p99_us, 'late': late,
        'evaluated': evaluated, 'rejected': 2, 'unmatched_dropped': 1,
        'scheduling': FIFO['model_node']}}


SCRIPT = {
    'running': {
        'sim_arm_node: plant': {'lateness_p99_us': 25.0, 'deadline_misses': 3,
                                'scheduling': FIFO['sim_arm_node']},
        'model_node: driving torque': {'evaluated': 100, 'scheduling': FIFO['model_node']},
        'driver_node: arm': {'published': 100, 'scheduling': FIFO['driver_node']},
        'scenario_node: run': {'scheduling': 'SCHED_OTHER'},  # not a node of this graph
    },
    'window': [model_window(990.0, 100, 400, 10, 1100),
               model_window(1010.0, 300, 900, 15, 2100),
               {**model_window(1000.0, 200, 500, 40, 3100),
                'driver_node: arm': {'published': 4100, 'scheduling': FIFO['driver_node']}}],
    # The driver's final count once stopped, and the model's next report.
    'stopped': {'driver_node: arm': {'published': 5000, 'scheduling': FIFO['driver_node']},
                'model_node: driving torque': {'evaluated': 4950, 'rejected': 2,
                                               'unmatched_dropped': 1,
                                               'scheduling': FIFO['model_node']}},
    'cpu': {'sim_arm_node': 0.30, 'model_node': 0.50, 'driver_node': 0.40},
    'steal': 0.02,
}


def measure(monkeypatch, tmp_path, composed):
    stub = StubGraphRun(SCRIPT, tmp_path)
    monkeypatch.setattr(graph, 'GraphRun', stub)
    monkeypatch.setattr(graph.realtime, 'cpu_latency_in_force', lambda: 4e-5)
    reference = Result('graph.model_step_inprocess_4seg', 1e-5)
    priorities = {'sim_arm_node': 60, 'model_node': 60, 'driver_node': 55}
    results = graph._measure('graph.x', 3.0, 4, priorities, 5e-5, reference,
                             composed=composed, settle=1.0)
    return stub, {result.name: result for result in results}


def test_the_figures_are_medians_over_the_model_reports_windows(monkeypatch, tmp_path):
    stub, results = measure(monkeypatch, tmp_path, composed=False)
    rate = results['graph.x.rate']
    assert (rate.value, rate.unit, rate.samples, rate.target) == (1000.0, 'Hz', 3, 1000.0)
    assert rate.extra == {'scheduling': FIFO, 'steal': 0.02, 'cpu_latency_limit': 4e-5,
                          'cpu_latency_requested': 5e-5,
                          'sim_arm_lateness_p99': pytest.approx(25e-6),  # s, from µs
                          'sim_arm_deadline_misses': 3}
    # Latencies in s (reported in µs): the median window, the worst window's p99 beside it.
    p50, p99 = results['graph.x.latency_p50'], results['graph.x.latency_p99']
    assert p50.value == pytest.approx(200e-6) and p50.unit == 's'
    assert p50.reference == 'graph.model_step_inprocess_4seg'
    assert p50.ratio == pytest.approx(20.0)
    assert p99.value == pytest.approx(500e-6) and p99.target == 1e-3
    assert p99.extra['worst_window_p99'] == pytest.approx(900e-6)
    # Late over the window: 30 late of the 2000 evaluated between the first and last report.
    late = results['graph.x.late_fraction']
    assert late.value == 30 / 2000 and late.samples == 2000 and late.target == 0.01
    # The final counts, from the driver's report once stopped and the model's after it.
    assert stub.stopped == ['driver_node']
    fraction = results['graph.x.fraction_evaluated']
    assert fraction.value == 4950 / 5000 and fraction.samples == 5000
    assert fraction.extra == {'published': 5000, 'evaluated': 4950, 'rejected': 2,
                              'unmatched_dropped': 1}
    for name, core in SCRIPT['cpu'].items():
        assert (results[f'graph.x.cpu.{name}'].value, results[f'graph.x.cpu.{name}'].unit) == \
            (core, 'core')


def test_each_node_runs_with_the_variants_scheduling_and_segments(monkeypatch, tmp_path):
    stub, _ = measure(monkeypatch, tmp_path, composed=False)
    assert list(stub.started) == list(graph.NODES)  # the model listens before the driver
    low, high = graph.DOMAINS['graph']
    assert low <= int(stub.domain) <= high
    for name, (command, env) in stub.started.items():
        assert command[0] == str(Path(sys.executable).parent / name)
        assert command[1:4] == ['--ros-args', '--params-file', str(graph.CONFIG)]
        arguments = command[4:]
        assert f'{name}:realtime_priority:={60 if name != "driver_node" else 55}' in arguments
        assert f'{name}:cpu_latency_limit:=5e-05' in arguments
        assert env['ROS_DOMAIN_ID'] == stub.domain
    model = stub.started['model_node'][0]
    assert 'model_node:segments:=[1, 2, 3, 4]' in model
    # The simulated arm and the driver on the same simulated CAN group, of this bench's.
    arm = [a for a in stub.started['sim_arm_node'][0] if ':can.channel:=' in a][0]
    group = arm.split(':=')[1]
    assert group.startswith(graph.CAN_GROUPS['graph'] + '.')
    assert f'driver_node:arm.channel:={group}' in stub.started['driver_node'][0]


def test_composed_the_driver_and_model_share_a_process_and_the_window_counts(
        monkeypatch, tmp_path):
    stub, results = measure(monkeypatch, tmp_path, composed=True)
    assert list(stub.started) == ['sim_arm_node', graph.COMPOSED]
    command = stub.started[graph.COMPOSED][0]
    assert command[:3] == [sys.executable, '-c', graph.COMPOSE]
    assert 'model_node:segments:=[1, 2, 3, 4]' in command
    assert 'driver_node:arm.n_segments:=4' in command
    # One process ends both nodes at once: the counts are the window's, from the last reports
    # before it (100, 100) and after it (4100 published, 3100 evaluated).
    assert stub.stopped == []
    fraction = results['graph.x.fraction_evaluated']
    assert fraction.extra['published'] == 4000 and fraction.extra['evaluated'] == 3000
    assert fraction.value == 0.75


def test_a_graph_run_restores_the_environment_and_names_a_process_that_exited(
        monkeypatch, tmp_path):
    monkeypatch.setenv('ROS_DOMAIN_ID', '7')
    monkeypatch.delenv('ROS_STATIC_PEERS', raising=False)
    quit_code = "print('first'); print('bad parameter x'); raise SystemExit(3)"
    domain = free_domain()
    with graph.GraphRun(domain, 'bench_graph_test') as run:
        assert os.environ['ROS_DOMAIN_ID'] == domain
        assert run.node.get_name() == 'bench_graph_test'
        logs = run.logs
        run.start('sleeper', [sys.executable, '-c', 'import time; time.sleep(60)'], os.environ)
        run.start('quitter', [sys.executable, '-c', quit_code], os.environ)
        run.processes['quitter'].wait(timeout=30)
        # Its status and its last log line, from the bench's next look.
        with pytest.raises(BellowsError, match=r'^bench graph: quitter exited with status 3 '
                                               r'\(bad parameter x\)$'):
            run.spin(0.01)
        assert run.stop('quitter') == 3 and 'quitter' not in run.processes
        sleeper = run.processes['sleeper']
    # Leaving stops what still runs, and puts back what it changed.
    assert sleeper.poll() is not None
    assert os.environ['ROS_DOMAIN_ID'] == '7' and 'ROS_STATIC_PEERS' not in os.environ
    assert run.context is None and not logs.exists()
