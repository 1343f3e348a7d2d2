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
`bellows bench --only 'graph*'`: the node graph's figures and the platform reference beside them.

No time is asserted (shared machine): only that every figure is measured, is a sane number, and
that the counts the bench reports agree with each other. One quick run of every graph bench
(`graph`, `graph_actuator`, `graph_floor`: the modules `--only 'graph*'` selects) serves the tests
that read its results; of bench/graph.py's grid it measures the variants that between them take
every value of each of its dimensions (`graph.variants(quick=True)`).
"""
import contextlib
import io
import json
import math
import os
import re

from node_processes import session_processes
import pytest
from test_bench_graph import latency_requests_held
from test_bench_graph_floor import documented_whole_graph_names

from bellows_ros.bench import graph, graph_actuator, graph_floor, Result
from bellows_ros.cli import main
from bellows_ros.cli.bench import format_table
from bellows_ros.io import params
from bellows_ros.runtime import realtime

pytestmark = pytest.mark.realtime  # runs alone, after the others (scripts/test.sh)


@pytest.fixture(scope='module')
def graph_results():
    """Run `bellows bench --only 'graph*' --quick --json` once: {name: result as a dict}."""
    out = io.StringIO()
    before = session_processes()
    with contextlib.redirect_stdout(out):
        assert main(['bench', '--only', 'graph*', '--quick', '--json']) == 0
    # Every node process the benches started was stopped and reaped: none is left.
    assert [name for pid, name in session_processes().items() if pid not in before] == []
    return {r['name']: r for r in json.loads(out.getvalue())['results']}


@pytest.mark.slow
def test_graph_bench_reports_every_figure_for_each_variant(graph_results):
    results = graph_results
    configured = params.read_file(graph.CONFIG, 'model_node')['cpu_latency_limit']
    assert 'graph.platform.wakeup_lateness' in results
    assert 'graph.platform.wakeup_lateness_no_latency_limit' in results
    grid = graph.variants()
    # The whole grid, each variant once: privileges x processes x segment counts.
    assert len({prefix for prefix, *_ in grid}) == len(grid) == 8
    # Named as the module says: graph[.user][.composed][.1seg].*, and no runtime mark left.
    assert re.search(r'`graph\[\.user\]\[\.composed\]\[\.1seg\]\.\*`', graph.__doc__)
    assert all(re.fullmatch(r'graph(\.user)?(\.composed)?(\.1seg)?', prefix)
               for prefix, *_ in grid)
    assert not [name for name in results if '.rclpy' in name or '.dds' in name]
    # The quick run measured its variants (test_bench_graph.py: they cover the grid), and only
    # those.
    quick = graph.variants(quick=True)
    assert ({prefix for prefix, *_ in grid if f'{prefix}.rate' in results}
            == {prefix for prefix, *_ in quick})
    for prefix, _, composed, _ in quick:
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
    for prefix, privilege, composed, segments in quick:
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
    # bench/graph_actuator.py ('graph*' selects it): the arm and the actuator, every
    # node worked.
    assert 0.0 < results['graph_actuator.rate']['value'] <= 1100.0
    assert results['graph_actuator.rate']['extra']['stiffness_control_hz'] > 0.0
    for name in graph_actuator.NODES:
        assert results[f'graph_actuator.cpu.{name}']['value'] > 0.01, name


@pytest.mark.slow
def test_each_node_of_the_whole_graph_has_its_floor_and_ratio(graph_results):
    whole = {name: r for name, r in graph_results.items()
             if name.startswith(('graph.whole.', 'graph.floor.'))}
    # Exactly the figures the module's docstring names.
    assert set(whole) == documented_whole_graph_names()
    for node in graph_floor.NODES:
        figure, floor = whole[f'graph.whole.cpu.{node}'], whole[f'graph.floor.cpu.{node}']
        assert figure['unit'] == floor['unit'] == 'core'
        assert figure['reference'] == f'graph.floor.cpu.{node}'
        assert floor['reference'] is None
        # Every process ran through the window and its CPU was read (no speed asserted).
        assert floor['value'] > 0.0 and figure['value'] > 0.0, node
        assert figure['ratio'] == pytest.approx(figure['value'] / floor['value'])
        for result in (figure, floor):
            extra = result['extra']
            assert re.fullmatch(r'SCHED_OTHER|SCHED_FIFO \d+', extra['scheduling']), node
            # Same scheduling for a node and its floor (the config's).
            assert isinstance(extra['threads'], dict) and extra['threads'], node
            assert math.isnan(extra['runqueue_wait']) or extra['runqueue_wait'] >= 0.0
        assert figure['extra']['scheduling'] == floor['extra']['scheduling'], node
    for kind in ('whole', 'floor'):
        total = whole[f'graph.{kind}.cpu.total']
        assert total['target'] == graph_floor.TOTAL_TARGET
        assert total['value'] == pytest.approx(
            sum(whole[f'graph.{kind}.cpu.{node}']['value'] for node in graph_floor.NODES))
        assert total['extra']['window'] > 0.0
        assert total['extra']['loadavg_before'] and total['extra']['loadavg_after']
        rate = whole[f'graph.{kind}.torque_rate']
        assert rate['unit'] == 'Hz' and rate['target'] == graph_floor.TORQUE_TARGET
        # Messages the bench's own subscriber counted over the window (none asserted: a starved
        # model node publishes none).
        assert rate['value'] == pytest.approx(rate['samples'] / total['extra']['window'])
    assert whole['graph.whole.cpu.total']['reference'] == 'graph.floor.cpu.total'
    assert whole['graph.whole.torque_rate']['reference'] == 'graph.floor.torque_rate'
    table = format_table([Result(**r) for r in whole.values()])
    assert 'graph.whole.cpu.model_node' in table and 'graph.floor.cpu.model_node' in table
