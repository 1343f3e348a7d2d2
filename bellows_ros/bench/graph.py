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
Benchmark of the node graph over real DDS: sim_arm_node -> driver_node -> model_node.

Measured in one run, over the grid of where a user runs it (`variants`): each privilege x separate
or composed processes x 4 or 1 segments, named `graph[.user][.composed][.1seg].*`. Every node is a
plain rclpy node (runtime/node.py) started as a process of its own, as scripts/launch_sim.sh starts
it; the bench's own participant is a plain rclpy node in the bench process, in a context of its
own on the bench's domain (GraphRun). Everything stays on this host (LOOPBACK_ENVIRONMENT).
- privileges: as root (no mark), the host nodes run at the SCHED_FIFO priority
  config/nodes_hw.yaml gives them on a robot and hold the CPU latency limit the configs ask for
  (`cpu_latency_limit`, runtime/realtime.py); `.user` is what an ordinary user's nodes get, every
  node at normal scheduling and no latency limit (each node falls back to exactly that, with one
  warning, when the kernel refuses: runtime/realtime.py);
- the simulated arm runs at the host nodes' priority. A real arm has a processor of its own: it
  neither delays the host nor waits for it. On one machine its stand-in can be kept from one of
  the two only. At equal SCHED_FIFO priority no thread preempts another: each runs until it
  blocks (above them, each tick of the stand-in lands on the host path:
  bench_results/0.1.0/notebook.md, 2026-11-24, "where rclpy's tail came from");
- `.composed`: the driver and the model node in one process (runtime.run with both classes, as
  nodes/arm_graph.py composes them): what composition saves against separate processes
  (`cpu.driver_node+model_node` against the sum of the two);
- `.1seg`: one simulated segment (the default launch's), against the arm's four.
Each variant is measured over a 10 s window that starts 4 s after its samples flow. `--quick`
is a smoke run: the two variants of QUICK_VARIANTS, which between them take every value of each
dimension (`graph` and `graph.user.composed.1seg`), each over 3 s after 2 s, and wake-up
references of 1 s.
Figures:
- achieved rate: arm samples per second the model node evaluated (target 1000 Hz);
- fraction of the samples the driver published that the model node evaluated (target >= 0.99),
  from their final counters;
- end-to-end latency, sample stamp (driver, at arrival from the bus) -> driving torque published
  (model node), p50 and p99: the model node reports both per 1 s window on /diagnostics; the
  figure is the median over the windows, the worst window's p99 in `extra` (target p99 <= 1 ms);
- late fraction: of all samples evaluated in the window, the fraction whose torque was published
  more than 2 ms after the sample's stamp (the model node counts them): p99 <= 2 ms over the
  whole window, not per 1 s window, is `late_fraction <= 0.01`;
- CPU per node: utime + stime from /proc/<pid>/stat over the window, as a fraction of one core.
The scheduling each node actually got (from its /diagnostics) is in `graph*.rate`'s extra, with
the simulated arm's own tick lateness (p99 over its last ticks, s) and its missed ticks since it
started: the stand-in keeps its 1 kHz whatever its priority.
References, measured in the same run:
- `SegmentModel.step` for the same segments, in-process (the model's own cost, without DDS); the
  latency ratio is against it;
- `graph.platform.wakeup_lateness`: how late a lone 1 kHz sleeping loop wakes on the idle machine,
  at the model node's SCHED_FIFO priority and under the configured CPU latency limit (p99 in
  `value`); `graph.platform.wakeup_lateness_no_latency_limit`: the same loop at normal
  scheduling without the limit, as an ordinary user's loop runs.
  One wake-up is the least any hop of the graph pays, so this is the floor under the graph's p99
  on this machine at this time: on a virtual machine whose host is busy it reaches milliseconds,
  whatever the graph does.
  `slots`: the 1 ms slots the loop lived through; `slots_missed`: the share of them it lost to
  waking a whole period late, a ceiling on the rate any 1 kHz loop here can hold;
- `steal`: the share of CPU time the hypervisor took from this machine during each window
  (/proc/stat), and `cpu_latency_limit`: the limit in force then (s, read back from the kernel;
  nan where the device is not readable), both in `graph*.rate`'s extra.
Nothing here asserts a time. A node that exits is an error (BellowsError with its log), not a zero.
"""
import os
from pathlib import Path
import random
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time

from bellows_ros.bench import Result, timing
from bellows_ros.config.segment import load_segment_params
from bellows_ros.errors import BellowsError
from bellows_ros.hardware.loop_timing import LoopStats, PeriodicLoop
from bellows_ros.io import params
from bellows_ros.models.segment import SegmentModel
from bellows_ros.runtime import realtime
from bellows_ros.runtime.messages import msg
from bellows_ros.runtime.node import LOOPBACK_ENVIRONMENT

# Each bench's ROS domains (drawn per graph) and simulated CAN groups (239.74.170.x: x drawn),
# apart from one another and from the tests' (1-101; a graph of one bench never hears another's).
# Within 215-232: Fast DDS's ports for domains 102-214 fall among Linux's ephemeral ports
# (ROS 2's documentation, "The ROS_DOMAIN_ID").
DOMAINS = {'graph': (215, 217), 'graph_actuator': (218, 219), 'graph_floor': (220, 225)}
CAN_GROUPS = {'graph': '239.74.170', 'graph_actuator': '239.74.171', 'graph_floor': '239.74.172'}
# s: the longest the bench's executor runs before the bench looks at its node processes again.
SPIN_SLICE = 0.05


def node_environment(domain, **extra):
    """Return the environment of a node process on `domain`, on loopback, with `extra`."""
    return dict(os.environ, ROS_DOMAIN_ID=str(domain), **LOOPBACK_ENVIRONMENT, **extra)


# The installed config (a pip or colcon install has no source tree beside the package).
CONFIG = params.default_file('nodes_sim')
ROBOT_CONFIG = params.default_file('nodes_hw')
NODES = ('sim_arm_node', 'model_node', 'driver_node')  # in start order
COMPOSED = 'driver_node+model_node'
# The composed process: the model node first, so that it listens before the driver publishes.
COMPOSE = ('from bellows_ros.nodes.driver_node import DriverNode; '
           'from bellows_ros.nodes.model_node import ModelNode; '
           'from bellows_ros.runtime import run; raise SystemExit(run((ModelNode, DriverNode)))')


def _cpu_seconds(pid):
    """Return utime + stime of a process, s (fields 14 and 15 of /proc/<pid>/stat)."""
    with open(f'/proc/{pid}/stat') as stream:
        fields = stream.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def _model_reference(segments):
    model = SegmentModel(load_segment_params())
    state = {'k': 0}

    def step_all():
        state['k'] += 1
        psi = 0.3 * ((state['k'] % 200) / 100.0 - 1.0)
        for _ in range(segments):
            model.step(psi, 0.1, 3.0e5, 1.2e5)
    return timing(f'graph.model_step_inprocess_{segments}seg', step_all, 5000)


SEGMENTS = (4, 1)     # the arm's four; the default launch's one
PRIVILEGES = ('root', 'user')
# s: each variant's window, and how long its graph runs before it (the model's first reports)
WINDOW, SETTLE = 10.0, 4.0
# --quick, a smoke run: two variants that between them take each value of each dimension (root
# and user, separate and composed, 4 and 1 segments), and shorter waits (s): the window (it holds
# two model reports at least: `late_fraction`), the settling, each wake-up reference.
QUICK_VARIANTS = ('graph', 'graph.user.composed.1seg')
QUICK_WINDOW, QUICK_SETTLE, QUICK_WAKEUP = 3.0, 2.0, 1.0


def variants(quick=False):
    """Return the grid, (prefix, privilege, composed, segments) per variant; quick: its few."""
    grid = []
    for privilege in PRIVILEGES:
        for composed in (False, True):
            for segments in SEGMENTS:
                marks = [mark for mark, on in (('user', privilege == 'user'),
                                               ('composed', composed),
                                               (f'{segments}seg', segments != 4)) if on]
                grid.append(('.'.join(['graph', *marks]), privilege, composed, segments))
    if quick:
        return [variant for variant in grid if variant[0] in QUICK_VARIANTS]
    return grid


def run(quick=False):
    window, settle = (QUICK_WINDOW, QUICK_SETTLE) if quick else (WINDOW, SETTLE)
    wakeup = QUICK_WAKEUP if quick else window
    references = {segments: _model_reference(segments) for segments in SEGMENTS}
    results = list(references.values())
    host = {name: params.read_file(ROBOT_CONFIG, name)['realtime_priority']
            for name in ('driver_node', 'model_node')}
    scheduling = {'root': dict(host, sim_arm_node=max(host.values())),
                  'user': dict.fromkeys(NODES, 0)}
    limit = params.read_file(CONFIG, 'model_node')['cpu_latency_limit']
    latency = {'root': limit, 'user': -1.0}
    results.append(_wakeup_reference('graph.platform.wakeup_lateness', wakeup,
                                     host['model_node'], limit))
    results.append(_wakeup_reference('graph.platform.wakeup_lateness_no_latency_limit', wakeup,
                                     0, -1.0))
    for prefix, privilege, composed, segments in variants(quick):
        results += _measure(prefix, window, segments, scheduling[privilege],
                            latency[privilege], references[segments], composed=composed,
                            settle=settle)
    return results


def _measure(prefix, window, segments, priorities, latency_limit, reference, composed=False,
             settle=SETTLE):
    """
    Run the three nodes for `window` s after `settle` s; return their figures.

    Each node runs at the given `realtime_priority` and `cpu_latency_limit`; `composed` runs the
    driver and the model node in one process (COMPOSE).
    """
    domain = str(random.randint(*DOMAINS['graph']))
    group = f'{CAN_GROUPS["graph"]}.{random.randint(2, 250)}'
    env = node_environment(domain)
    given = {'sim_arm_node': {'can.channel': group, 'n_segments': segments},
             'driver_node': {'arm.channel': group, 'arm.n_segments': segments,
                             'actuator.enabled': 'false', 'wait_for_subscribers': 20.0,
                             'autostart': 'true'},
             'model_node': {'segments': list(range(1, segments + 1)), 'latency_budget': 0.002}}
    binary = Path(sys.executable).parent
    windows, final = [], {}
    with GraphRun(domain, 'bench_graph') as graph:
        node = graph.node

        def on_diagnostics(array):
            for status in array.status:
                values = {kv.key: kv.value for kv in status.values}
                final[status.name] = values
                if status.name.startswith('model_node') and 'latency_p99_us' in values:
                    windows.append(values)
        node.create_subscription(msg.DiagnosticArray, '/diagnostics', on_diagnostics, 50)
        for name in NODES:
            given[name].update(realtime_priority=priorities[name],
                               cpu_latency_limit=float(latency_limit))
        # `-p node:name:=value`: wins over the node's own section of the file (rcl's rule).
        overrides = {name: [arg for key, value in given[name].items()
                            for arg in ('-p', f'{name}:{key}:={value}')] for name in NODES}
        commands = {name: [str(binary / name), '--ros-args', '--params-file', str(CONFIG),
                           *overrides[name]] for name in NODES}
        if composed:
            commands = {'sim_arm_node': commands['sim_arm_node'],
                        COMPOSED: [sys.executable, '-c', COMPOSE, '--ros-args', '--params-file',
                                   str(CONFIG), *overrides['model_node'],
                                   *overrides['driver_node']]}
        for name, command in commands.items():
            graph.start(name, command, env)
            if name in ('model_node', COMPOSED):
                # The driver publishes from its first sample on: the model must listen by then
                # (and the driver waits until it has matched it).
                end = time.monotonic() + 60.0
                while 'model_node: driving torque' not in final and time.monotonic() < end:
                    graph.spin(0.05)
        # The driver publishes once it has matched the model (wait_for_subscribers): on a busy
        # machine Fast DDS's discovery between two new processes takes seconds.
        end = time.monotonic() + 60.0
        while _counts(final)[0] == 0:
            if time.monotonic() > end:
                raise BellowsError(f'bench {prefix}: the driver published no sample in 60 s')
            graph.spin(0.05)
        graph.spin(settle)  # the model's first reports, past the start
        counts0 = _counts(final)
        windows.clear()
        limit_in_force = realtime.cpu_latency_in_force()
        cpu, stolen = graph.cpu_window(window)
        measured = list(windows)
        counts1 = _counts(final)
        if not composed:  # composed, the driver's last count and the model's come together
            graph.stop('driver_node')  # its close() publishes its final count
            graph.spin(2.5)  # the model's next report carries its final count
    driver = final.get('driver_node: arm', {})
    model = final.get('model_node: driving torque', {})
    published = int(driver.get('published', 0))
    evaluated = int(model.get('evaluated', 0))
    if composed:
        # One process ends both nodes at once: the counts of the window, from their last reports
        # before and after it (each a second apart at most), stand for the final counts.
        published, evaluated = (b - a for a, b in zip(counts0, counts1))
    rates = [float(w['rate_hz']) for w in measured]
    p50 = [float(w['latency_p50_us']) * 1e-6 for w in measured]
    p99 = [float(w['latency_p99_us']) * 1e-6 for w in measured]
    # A node reports several statuses (one per concern); the one of its loop says how it ran.
    scheduling = {name.split(':')[0]: values['scheduling'] for name, values in final.items()
                  if name.split(':')[0] in NODES and 'scheduling' in values}
    arm = final.get('sim_arm_node: plant', {})
    arm_lateness = float(arm.get('lateness_p99_us', 'nan')) * 1e-6
    results = [Result(f'{prefix}.rate', statistics.median(rates) if rates else 0.0, 'Hz',
                      len(rates), target=1000.0,
                      extra={'scheduling': scheduling, 'steal': stolen,
                             'cpu_latency_limit': limit_in_force,
                             'cpu_latency_requested': float(latency_limit),
                             'sim_arm_lateness_p99': arm_lateness,
                             'sim_arm_deadline_misses': int(arm.get('deadline_misses', -1))},
                      extra_units={'steal': '', 'cpu_latency_limit': 's',
                                   'cpu_latency_requested': 's',
                                   'sim_arm_lateness_p99': 's', 'sim_arm_deadline_misses': ''})]
    results.append(Result(f'{prefix}.fraction_evaluated',
                          evaluated / published if published else 0.0, '', published,
                          target=0.99,
                          extra={'published': published, 'evaluated': evaluated,
                                 'rejected': int(model.get('rejected', 0)),
                                 'unmatched_dropped': int(model.get('unmatched_dropped', 0))}))
    latency50 = statistics.median(p50) if p50 else float('nan')
    results.append(Result(f'{prefix}.latency_p50', latency50, 's', len(p50),
                          reference=reference.name, ratio=latency50 / reference.value))
    results.append(Result(f'{prefix}.latency_p99', statistics.median(p99) if p99 else float('nan'),
                          's', len(p99), target=1e-3,
                          extra={'worst_window_p99': max(p99) if p99 else float('nan')}))
    if len(measured) >= 2:
        late = int(measured[-1]['late']) - int(measured[0]['late'])
        count = int(measured[-1]['evaluated']) - int(measured[0]['evaluated'])
        results.append(Result(f'{prefix}.late_fraction', late / count if count else float('nan'),
                              '', count, target=0.01, extra={'late_over_2ms': late}))
    for name, fraction in cpu.items():
        results.append(Result(f'{prefix}.cpu.{name}', fraction, 'core', 1))
    return results


def _counts(final):
    """Return (published by the driver, evaluated by the model) of their latest reports."""
    return (int(final.get('driver_node: arm', {}).get('published', 0)),
            int(final.get('model_node: driving torque', {}).get('evaluated', 0)))


def _wakeup_reference(name, seconds, priority, latency_limit):
    """
    Measure the lateness of a lone 1 kHz sleeping loop (PeriodicLoop, as the simulated devices).

    The loop runs on a thread at SCHED_FIFO `priority` when granted (0: normal scheduling), for
    `seconds` s, with this process holding `latency_limit` (s; negative = none) as a node would.
    """
    stats = LoopStats(window=int(seconds * 1000) + 1000)
    stop = threading.Event()
    granted = []

    def loop():
        try:
            if priority > 0:
                os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))  # this thread
                granted.append(True)
        except (AttributeError, PermissionError):
            pass
        for _ in PeriodicLoop(1e-3, stats).ticks(stop):
            pass
    thread = threading.Thread(target=loop, name='wakeup-reference', daemon=True)
    request = _hold_latency_limit(latency_limit)
    try:
        limit_in_force = realtime.cpu_latency_in_force()
        times = _cpu_times()
        thread.start()
        time.sleep(seconds)
        stop.set()
        thread.join()
    finally:
        if request is not None:
            os.close(request)
    summary = stats.summary()
    slots = int(summary['count'] + summary['misses'])
    return Result(name, summary['lateness_p99'], 's',
                  int(summary['count']),
                  extra={'p50': summary['lateness_p50'], 'max': summary['lateness_max'],
                         'slots': slots, 'slots_missed': summary['misses'] / slots,
                         'scheduling': f'SCHED_FIFO {priority}' if granted else 'SCHED_OTHER',
                         'steal': _steal_fraction(times, _cpu_times()),
                         'cpu_latency_limit': limit_in_force,
                         'cpu_latency_requested': float(latency_limit)},
                  extra_units={'slots': '', 'slots_missed': '', 'steal': '',
                               'cpu_latency_limit': 's', 'cpu_latency_requested': 's'})


def _hold_latency_limit(limit):
    """
    Make the bench's own CPU latency request: an fd to close, or None when off or not permitted.

    Without it the reference runs unrestricted, which its `cpu_latency_limit` figure shows.
    """
    if limit < 0:
        return None
    try:
        return realtime.hold_cpu_latency(limit)
    except OSError:
        return None


def _cpu_times():
    """Return the machine's CPU time counters (first line of /proc/stat), or None."""
    try:
        with open('/proc/stat') as stream:
            return [int(x) for x in stream.readline().split()[1:]]
    except OSError:
        return None


def _steal_fraction(start, end):
    """Share of all CPU time the hypervisor stole between two `_cpu_times()` readings."""
    if start is None or end is None or len(end) < 8:
        return float('nan')
    delta = [b - a for a, b in zip(start, end)]
    return delta[7] / sum(delta) if sum(delta) else float('nan')


class GraphRun:
    """
    The bench's side of one node graph, shared by graph, graph_actuator and graph_floor.

    `with GraphRun(domain, name) as graph:` joins `domain` on loopback: the bench's own
    participant, a plain rclpy node `graph.node` in a context of its own (`graph.context`), spun
    on its own executor in bounded slices by `graph.spin(seconds)`. `graph.start(name, command,
    env)` starts a node process logging to `graph.logs/<name>.log`, `graph.check_alive()` raises
    if one has exited. On exit every process is sent SIGINT (killed after 10 s), the node and
    the context are shut down, ROS_DOMAIN_ID and the loopback settings are restored, the logs
    are removed.
    """

    def __init__(self, domain, name='bench_graph'):
        self.domain, self.name = domain, name
        self.processes = {}
        self._logs = tempfile.TemporaryDirectory()
        self.logs = Path(self._logs.name)
        self._files = []
        self._previous = {}
        self.context = self.node = self.executor = None

    def __enter__(self):
        import rclpy
        import rclpy.node
        from rclpy.signals import SignalHandlerOptions

        names = ('ROS_DOMAIN_ID', *LOOPBACK_ENVIRONMENT)
        self._previous = {name: os.environ.get(name) for name in names}
        # The bench's participant reads these from its own environment (rmw at init).
        os.environ.update(ROS_DOMAIN_ID=self.domain, **LOOPBACK_ENVIRONMENT)
        try:
            self.context = rclpy.Context()
            # No signal handlers: Ctrl-C stays the bench's (KeyboardInterrupt, then __exit__).
            rclpy.init(context=self.context, domain_id=int(self.domain),
                       signal_handler_options=SignalHandlerOptions.NO)
            self.node = rclpy.node.Node(self.name, context=self.context)
            self.executor = _bench_executor(self.context)
            self.executor.add_node(self.node)
        except BaseException:
            self._leave()
            self._restore()
            raise
        return self

    def spin(self, seconds):
        """Spin the bench's node for `seconds` s in bounded slices; raises if a node exited."""
        from rclpy.task import Future

        never = Future()
        end = time.monotonic() + seconds
        while True:
            left = end - time.monotonic()
            if left <= 0:
                break
            self.executor.spin_until_future_complete(never, timeout_sec=min(SPIN_SLICE, left))
            self.check_alive()

    def start(self, name, command, env):
        """Start node process `name` (`command`, in `env`), its output in logs/<name>.log."""
        log = open(self.logs / f'{name}.log', 'w')
        self._files.append(log)
        self.processes[name] = subprocess.Popen(command, env=env, stdout=log,
                                                stderr=subprocess.STDOUT)

    def cpu_window(self, seconds):
        """
        Spin the bench's node for `seconds` s; return (CPU of each node process, steal).

        CPU: utime + stime over the window, as a fraction of one core; steal: the share of all
        CPU time the hypervisor took meanwhile. Raises if a node process exited.
        """
        cpu0 = {name: _cpu_seconds(p.pid) for name, p in self.processes.items()}
        times = _cpu_times()
        start = time.monotonic()
        self.spin(seconds)
        elapsed = time.monotonic() - start
        stolen = _steal_fraction(times, _cpu_times())
        self.check_alive()
        return {name: (_cpu_seconds(p.pid) - cpu0[name]) / elapsed
                for name, p in self.processes.items()}, stolen

    def check_alive(self):
        """Raise BellowsError naming a node process that has exited, with its last log line."""
        for name, process in self.processes.items():
            if process.poll() is not None:
                log = (self.logs / f'{name}.log').read_text().strip().splitlines()
                raise BellowsError(f'bench graph: {name} exited with status '
                                   f'{process.returncode}' + (f' ({log[-1]})' if log else ''))

    def stop(self, name, timeout=10.0):
        """Stop node process `name` (SIGINT; killed after `timeout` s); returns its status."""
        process = self.processes.pop(name)
        if process.poll() is None:
            process.send_signal(signal.SIGINT)
        try:
            return process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            process.kill()
            return process.wait()

    def __exit__(self, *exc):
        for process in self.processes.values():
            if process.poll() is None:
                process.send_signal(signal.SIGINT)
        for process in self.processes.values():
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        self._leave()
        self._restore()
        for log in self._files:
            log.close()
        self._logs.cleanup()

    def _leave(self):
        if self.executor is not None:
            self.executor.shutdown()
        if self.node is not None:
            self.node.destroy_node()
        if self.context is not None:
            self.context.try_shutdown()
        self.context = self.node = self.executor = None

    def _restore(self):
        for name, value in self._previous.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def _bench_executor(context):
    """Return the bench's executor: rclpy's EventsExecutor where it has one, as the nodes'."""
    from rclpy.executors import SingleThreadedExecutor

    from bellows_ros.runtime.node import EventsExecutor

    if EventsExecutor is not None:
        return EventsExecutor(context=context)
    return SingleThreadedExecutor(context=context)


if __name__ == '__main__':
    for result in run(quick='--quick' in sys.argv):
        print(result.as_dict())
