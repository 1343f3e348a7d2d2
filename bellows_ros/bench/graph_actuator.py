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
Benchmark of the whole simulated graph, the arm and the actuator together, over real DDS.

sim_arm_node (one segment, CAN over udp_multicast) and sim_actuator_node (pty) -> driver_node
(both device groups) -> model_node, arm_controller_node (holding its first angle) and
stiffness_controller_node (no set-point: holding still), as scripts/launch_sim.sh runs them, with
config/nodes_sim.yaml's scheduling, on the DDS runtime (`graph_actuator.*`) and, where rclpy
imports, on rclpy (`graph_actuator.rclpy.*`). What `graph` (bench/graph.py) leaves out: the
1 kHz arm nodes and the stiffness controller side by side, each a subscriber of the driver's
sample topics, so that what one node pays for the other group's samples shows in its CPU.
Figures:
- CPU per node: utime + stime from /proc/<pid>/stat over the window, as a fraction of one core;
- `rate`: samples per second the model node evaluated (median of its 1 s reports), with the
  stiffness controller's control rate and the scheduling each node got in `extra`.
Nothing here asserts a time. A node that exits is an error (BellowsError with its log).
"""
import os
from pathlib import Path
import random
import statistics
import sys
import time

from bellows_ros import params
from bellows_ros.bench import Result
from bellows_ros.bench.graph import _spin, GraphRun
from bellows_ros.runtime.node import rclpy_unavailable

CONFIG = params.default_file('nodes_sim')
# In start order: the consumers listen before the driver publishes its first sample.
NODES = ('sim_arm_node', 'sim_actuator_node', 'model_node', 'arm_controller_node',
         'stiffness_controller_node', 'driver_node')
CONSUMERS = ('model_node: driving torque', 'stiffness_controller_node: control',
             'arm_controller_node: segment_1')


def run(quick=False):
    window = 3.0 if quick else 10.0
    results = _measure('graph_actuator', 'dds', window)
    missing = rclpy_unavailable()
    if missing:
        results.append(Result('graph_actuator.rclpy.rate', float('nan'), 'Hz', 0,
                              extra={'skipped': f'rclpy not importable: {missing}'}))
    else:
        results += _measure('graph_actuator.rclpy', 'rclpy', window)
    return results


def _measure(prefix, runtime, window):
    """Run the six nodes on `runtime` ('dds' or 'rclpy') for `window` s; return their figures."""
    from bellows_ros.runtime import dds_node
    from bellows_ros.runtime.messages import msg

    domain = str(random.randint(40, 59))
    group = f'239.74.168.{random.randint(2, 250)}'
    graph = GraphRun(dds_node, domain)
    port = str(graph.logs / 'actuator')
    env = dict(os.environ, ROS_DOMAIN_ID=domain, BELLOWS_RUNTIME=runtime,
               **dds_node.LOOPBACK_ENVIRONMENT)
    given = {'sim_arm_node': {'can.channel': group},
             'sim_actuator_node': {'port': port},
             'driver_node': {'arm.channel': group, 'actuator.port': port,
                             'wait_for_subscribers': 20.0, 'autostart': 'true'},
             'model_node': {}, 'arm_controller_node': {}, 'stiffness_controller_node': {}}
    binary = Path(sys.executable).parent
    reports, final = {}, {}
    with graph:
        node = dds_node.Node('bench_graph_actuator')

        def on_diagnostics(array):
            for status in array.status:
                values = {kv.key: kv.value for kv in status.values}
                final[status.name] = values
                if 'rate_hz' in values:
                    reports.setdefault(status.name, []).append(float(values['rate_hz']))
        node.create_subscription(msg.DiagnosticArray, '/diagnostics', on_diagnostics, 50)
        for name in NODES:
            arguments = [arg for key, value in given[name].items()
                         for arg in ('-p', f'{name}:{key}:={value}')]
            if name == 'driver_node':
                end = time.monotonic() + 60.0
                while not all(c in final for c in CONSUMERS) and time.monotonic() < end:
                    dds_node.spin_once(node, timeout_sec=0.05)
                    graph.check_alive()
            graph.start(name, [str(binary / name), '--ros-args', '--params-file', str(CONFIG),
                               *arguments], env)
        # The driver publishes once every consumer has matched (wait_for_subscribers).
        end = time.monotonic() + 60.0
        while time.monotonic() < end and not all(
                int(final.get(f'driver_node: {group}', {}).get('published', 0)) > 0
                for group in ('arm', 'actuator')):
            dds_node.spin_once(node, timeout_sec=0.05)
            graph.check_alive()
        _spin(dds_node, node, 3.0)  # settle
        graph.check_alive()
        reports.clear()
        cpu, stolen = graph.cpu_window(node, window)
    model = reports.get('model_node: driving torque', [])
    control = reports.get('stiffness_controller_node: control', [])
    scheduling = {name.split(':')[0]: values['scheduling'] for name, values in final.items()
                  if 'scheduling' in values}
    results = [Result(f'{prefix}.rate', statistics.median(model) if model else 0.0, 'Hz',
                      len(model), target=1000.0,
                      extra={'runtime': runtime, 'scheduling': scheduling, 'steal': stolen,
                             'stiffness_control_hz': (statistics.median(control) if control
                                                      else 0.0)},
                      extra_units={'steal': '', 'stiffness_control_hz': 'Hz'})]
    for name, fraction in cpu.items():
        results.append(Result(f'{prefix}.cpu.{name}', fraction, 'core', 1))
    return results


if __name__ == '__main__':
    for result in run(quick='--quick' in sys.argv):
        print(result.as_dict())
