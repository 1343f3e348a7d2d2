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
Benchmark of the simulated graph, the arm and the actuator together, over real DDS.

sim_arm_node (one segment, CAN over udp_multicast) and sim_actuator_node (pty) -> driver_node
(both device groups) -> model_node, arm_controller_node (holding its first angle) and
stiffness_controller_node (no set-point: holding still), as scripts/launch_sim.sh runs them, with
config/nodes_sim.yaml's scheduling, each a plain rclpy node in a process of its own
(`graph_actuator.*`; the bench's participant and loopback as bench/graph.py's GraphRun). What
`graph` (bench/graph.py) leaves out: the
1 kHz arm nodes and the stiffness controller side by side, each a subscriber of the driver's
sample topics, so that what one node pays for the other group's samples shows in its CPU.
Figures:
- CPU per node: utime + stime from /proc/<pid>/stat over the window, as a fraction of one core;
- `rate`: samples per second the model node evaluated (median of its 1 s reports), with the
  stiffness controller's control rate and the scheduling each node got in `extra`.
Nothing here asserts a time. A node that exits is an error (BellowsError with its log).
"""
from pathlib import Path
import random
import statistics
import sys
import time

from bellows_ros.bench import Result
from bellows_ros.bench.graph import CAN_GROUPS, DOMAINS, GraphRun, node_environment
from bellows_ros.io import params
from bellows_ros.runtime.messages import msg

CONFIG = params.default_file('nodes_sim')
# In start order: the consumers listen before the driver publishes its first sample.
NODES = ('sim_arm_node', 'sim_actuator_node', 'model_node', 'arm_controller_node',
         'stiffness_controller_node', 'driver_node')
CONSUMERS = ('model_node: driving torque', 'stiffness_controller_node: control',
             'arm_controller_node: segment_1')


def run(quick=False):
    window = 3.0 if quick else 10.0
    return _measure('graph_actuator', window)


def _measure(prefix, window):
    """Run the six nodes for `window` s; return their figures."""
    domain = str(random.randint(*DOMAINS['graph_actuator']))
    group = f'{CAN_GROUPS["graph_actuator"]}.{random.randint(2, 250)}'
    graph = GraphRun(domain, 'bench_graph_actuator')
    port = str(graph.logs / 'actuator')
    env = node_environment(domain)
    given = {'sim_arm_node': {'can.channel': group},
             'sim_actuator_node': {'port': port},
             'driver_node': {'arm.channel': group, 'actuator.port': port,
                             'wait_for_subscribers': 20.0, 'autostart': 'true'},
             'model_node': {}, 'arm_controller_node': {}, 'stiffness_controller_node': {}}
    binary = Path(sys.executable).parent
    reports, final = {}, {}
    with graph:
        node = graph.node

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
                    graph.spin(0.05)
            graph.start(name, [str(binary / name), '--ros-args', '--params-file', str(CONFIG),
                               *arguments], env)
        # The driver publishes once every consumer has matched (wait_for_subscribers).
        end = time.monotonic() + 60.0
        while time.monotonic() < end and not all(
                int(final.get(f'driver_node: {group}', {}).get('published', 0)) > 0
                for group in ('arm', 'actuator')):
            graph.spin(0.05)
        graph.spin(3.0)  # settle
        reports.clear()
        cpu, stolen = graph.cpu_window(window)
    model = reports.get('model_node: driving torque', [])
    control = reports.get('stiffness_controller_node: control', [])
    scheduling = {name.split(':')[0]: values['scheduling'] for name, values in final.items()
                  if 'scheduling' in values}
    results = [Result(f'{prefix}.rate', statistics.median(model) if model else 0.0, 'Hz',
                      len(model), target=1000.0,
                      extra={'scheduling': scheduling, 'steal': stolen,
                             'stiffness_control_hz': (statistics.median(control) if control
                                                      else 0.0)},
                      extra_units={'steal': '', 'stiffness_control_hz': 'Hz'})]
    for name, fraction in cpu.items():
        results.append(Result(f'{prefix}.cpu.{name}', fraction, 'core', 1))
    return results


if __name__ == '__main__':
    for result in run(quick='--quick' in sys.argv):
        print(result.as_dict())
