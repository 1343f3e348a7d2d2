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
`bellows bench --only graph`: the node graph's figures and the platform reference beside them.

No time is asserted (shared machine): only that every figure is measured, is a sane number, and
that the counts the bench reports agree with each other.

The graph bench (bench/graph.py) is being ported from the removed DDS runtime to rclpy: while
its source still names dds_node, the tests that run it are expected to fail (xfail, not strict:
reported as XFAIL, or XPASS once it works), and the last one still asserts the old grid
(runtimes x privileges x processes x segments), to be brought to the ported bench's.
"""
import json
import math
import os
from pathlib import Path
import time

import pytest

from bellows_ros import params
from bellows_ros.bench import Result
from bellows_ros.cli import main
from bellows_ros.cli.bench import format_table
from bellows_ros.runtime import realtime

BENCH = Path(__file__).resolve().parent.parent / 'bellows_ros' / 'bench' / 'graph.py'
BEING_PORTED = pytest.mark.xfail(
    'dds_node' in BENCH.read_text(), strict=False,
    reason='graph bench being ported: bellows_ros/bench/graph.py still uses the removed '
           'DDS runtime (dds_node, runtime.node.rclpy_unavailable)')


def bench_graph():
    """Return bellows_ros.bench.graph (imported here: it fails to import while being ported)."""
    from bellows_ros.bench import graph
    return graph


def latency_requests_held():
    """Return this process's open file descriptors on the PM QoS device (its requests)."""
    fds = Path('/proc/self/fd')
    return [fd for fd in fds.iterdir()
            if os.path.realpath(fd) == os.path.realpath(realtime.CPU_LATENCY_DEVICE)]


@BEING_PORTED
def test_the_wakeup_reference_measures_a_lone_1khz_loop():
    """
    What the bench controls: its own PM QoS request, in force while it runs, withdrawn after.

    The limit in force is the least of every process's request on the host: ours can only be
    lowered by others, never raised, so the run saw at most what it asked for.
    """
    graph = bench_graph()
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


def test_fractions_in_extra_are_shown_without_the_figures_unit():
    table = format_table([Result('x.rate', 990.0, 'Hz', 1, extra={'steal': 0.125, 'p50': 980.0},
                                 extra_units={'steal': ''})])
    assert '    steal:      0.125 \n' in table + '\n'
    assert '    p50:        980 Hz' in table


@pytest.mark.slow
@BEING_PORTED
def test_graph_bench_reports_every_figure_for_each_variant(capsys):
    graph = bench_graph()
    from bellows_ros.runtime.node import rclpy_unavailable  # the old grid (see the docstring)
    configured = params.read_file(graph.CONFIG, 'model_node')['cpu_latency_limit']
    assert main(['bench', '--only', 'graph', '--quick', '--json']) == 0
    results = {r['name']: r for r in json.loads(capsys.readouterr().out)}
    assert 'graph.platform.wakeup_lateness' in results
    assert 'graph.platform.wakeup_lateness_no_latency_limit' in results
    rclpy_missing = rclpy_unavailable()
    if rclpy_missing:
        assert results['graph.rclpy.rate']['extra']['skipped'].endswith(rclpy_missing)
    grid = graph.variants(rclpy_missing)
    # The whole grid, each variant once: runtimes x privileges x processes x segment counts.
    assert len({prefix for prefix, *_ in grid}) == len(grid) == (4 if rclpy_missing else 8) * 2
    for prefix, runtime, _, composed, _ in grid:
        evaluated = results[f'{prefix}.fraction_evaluated']
        # samples flowed (3 s window; the rate is host-bound)
        assert evaluated['extra']['published'] > 100
        assert evaluated['value'] == (evaluated['extra']['evaluated']
                                      / evaluated['extra']['published'])
        # A fraction (how near 1 depends on the host, which the bench reports, not the test);
        # the composed count comes from reports up to a second apart: it may pass 1 a little.
        assert evaluated['extra']['evaluated'] > 0
        assert 0.0 < evaluated['value'] <= (1.1 if composed else 1.0)
        rate = results[f'{prefix}.rate']
        assert rate['extra']['runtime'] == runtime
        assert set(rate['extra']['scheduling']) == set(graph.NODES)
        assert rate['extra']['sim_arm_lateness_p99'] >= 0.0    # the stand-in reported its ticks
        assert rate['extra']['sim_arm_deadline_misses'] >= 0
        assert 0.0 < rate['value'] <= 1100.0
        p50 = results[f'{prefix}.latency_p50']['value']
        p99 = results[f'{prefix}.latency_p99']['value']
        assert 0.0 < p50 <= p99
        assert 0.0 <= results[f'{prefix}.late_fraction']['value'] <= 1.0
        processes = ('sim_arm_node', graph.COMPOSED) if composed else graph.NODES
        for name in processes:
            assert results[f'{prefix}.cpu.{name}']['value'] > 0.01    # every process worked
    for prefix, runtime, privilege, composed, segments in grid:
        rate = results[f'{prefix}.rate']
        reference = results[f'{prefix}.latency_p50']['reference']
        assert reference == f'graph.model_step_inprocess_{segments}seg'
        scheduling = rate['extra']['scheduling']
        if privilege == 'user':
            # What an ordinary user's nodes get: normal scheduling, no latency request.
            assert all(v.startswith('SCHED_OTHER') for v in scheduling.values()), prefix
            assert rate['extra']['cpu_latency_requested'] < 0, prefix
        else:
            assert rate['extra']['cpu_latency_requested'] == configured, prefix
            if os.access(realtime.CPU_LATENCY_DEVICE, os.W_OK):    # the nodes could hold it
                assert rate['extra']['cpu_latency_limit'] <= configured, prefix
            if scheduling['model_node'].startswith('SCHED_FIFO'):    # granted on this machine
                # The stand-in for the arm at the host nodes' priority: neither preempts.
                assert scheduling['sim_arm_node'] == scheduling['model_node'], prefix
    assert results['graph.platform.wakeup_lateness']['extra']['cpu_latency_requested'] == \
        configured
    user_loop = results['graph.platform.wakeup_lateness_no_latency_limit']['extra']
    assert user_loop['cpu_latency_requested'] < 0
    assert user_loop['scheduling'] == 'SCHED_OTHER'
    assert latency_requests_held() == []
    # bench/graph_actuator.py (its module name holds 'graph'): the whole graph, every node worked.
    from bellows_ros.bench import graph_actuator
    for prefix in ('graph_actuator',) + (() if rclpy_missing else ('graph_actuator.rclpy',)):
        assert 0.0 < results[f'{prefix}.rate']['value'] <= 1100.0
        assert results[f'{prefix}.rate']['extra']['stiffness_control_hz'] > 0.0
        for name in graph_actuator.NODES:
            assert results[f'{prefix}.cpu.{name}']['value'] > 0.01, name
