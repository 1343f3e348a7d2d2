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
Benchmark of the whole simulated graph against its floor, measured in the same run.

The whole graph (`graph.whole.*`) is the graph scripts/launch_sim.sh runs, each node a process of
its own with config/nodes_sim.yaml and the launch's per-run CAN group and pty, on a four-segment
arm: sim_arm_node (4 segments), sim_actuator_node, driver_node (arm and actuator, autostart),
model_node (segments 1-4), stiffness_controller_node, arm_controller_node (the config's
segments) and scenario_node, running its scenario (stiffness step, angle sweep) with a duration
far longer than the window (it is stopped before it ends; it writes nothing).

The floor (`graph.floor.*`) is, for each of those nodes, the least a node with the same traffic
costs: a minimal rclpy node (FLOORS) with the same name, the same subscriptions and publications
(same message types, same QoS: bellows_ros/interfaces.py), the same device links, the same
rates, with the same scheduling (the config's `realtime_priority` and `cpu_latency_limit`), spun
the same way (runtime.run: EventsExecutor in bounded slices), each a process of its own, in a
graph of floor nodes that reproduces the whole graph's traffic. It takes its messages serialized
(`raw=True`), publishes messages serialized once and writes frames laid out once: decoding,
encoding and everything a node computes are the node's own work, above the floor.
- the simulated devices: their links' traffic from a 1 kHz PeriodicLoop thread, with the same
  libraries: the simulated arm sends a frame per segment each tick and its status every 100 ms
  on the simulated CAN bus (python-can udp_multicast on loopback, its own frames dropped in the
  kernel as the node's are) and reads the host's frames; the simulated actuator writes a
  telemetry frame each tick to a pty of its own (linked at the driver's port) and reads what the
  host wrote. No plant, no codec;
- the driver: its arm reader reads the CAN frames as they come and publishes the arm sample
  message once per instant (a frame per segment); its transmit thread sends the set-point and
  heartbeat frames every 10 ms (their DBC cycle time); its actuator reader reads the pty
  (pyserial) and publishes the actuator sample message per telemetry frame's bytes, with a
  heartbeat every `heartbeat_period` (config/hardware.yaml) and a motor command frame per motor
  command. On joint_states the 4 segments' angles, rates and chamber pressures
  (`arm_sample_names`), on actuator/joint_states the actuator's compressions, spring force and
  chamber pressure (`actuator_sample_names`);
- a node that publishes on each input sample publishes a serialized message per input: the
  model's floor both torques per arm sample, the arm controller's floor a pressure command
  every `control_every` arm samples (and ~/state every 20 ms of samples), the stiffness
  controller's floor a motor command every `control_every` actuator samples and the stiffness
  every `publish_every` commands; each subscribes to the same topics as its node, with the same
  QoS (the arm controller best effort, newest only, to the arm samples), so each 1 kHz node
  receives its own group's sample topic only;
- the scenario's floor a 50 Hz timer publishing the angle set-point each tick and the stiffness
  set-point once a second, subscribed as the scenario is (best effort for the samples of both
  groups and the driving torque; the stiffness, the vented state and /diagnostics);
- every floor node but the scenario's publishes one pre-built /diagnostics array a second, as
  each node's diagnostics.Updater does.
What a node costs above its floor is its own work (models, plants, codecs, checks); the floor
is what rclpy, Fast DDS, the device links and the Python callbacks cost for its traffic on this
machine now.
Each graph is measured over a 20 s window once it has settled 3 s (`--quick`, a smoke run: 3 s
after 1 s).

Figures (CPU: utime + stime from /proc/<pid>/stat over the window, a fraction of one core):
- `graph.floor.cpu.<node>`, `graph.whole.cpu.<node>` (reference the floor, ratio), with the
  scheduling the process got, its busiest threads (by kernel thread name, fraction of a core)
  and its run-queue wait (`runqueue_wait`: s its threads were ready to run but waited for a CPU,
  per s of window, summed over its threads; from /proc/<pid>/task/*/schedstat) in `extra`: a
  node starved by the SCHED_FIFO nodes or by other work on the machine uses less CPU than it
  would, and waits, so a ratio below 1 is starvation, not a node cheaper than its floor;
- `graph.floor.cpu.total`, `graph.whole.cpu.total` (target 1.3 core; reference the floor's),
  with the bench process's own CPU, the machine's steal and its load average before and after
  the graph ran in `extra` (other work on a shared machine shows there);
- `graph.floor.torque_rate`, `graph.whole.torque_rate` (target 1000 Hz): the messages per
  second an independent client, the bench's own plain rclpy subscriber, received on
  /bellows/driving_torque over the window (each carries every segment), with, for the whole
  graph, the model node's own rate (median of its /diagnostics reports in the window; nan when
  none came, a starved node's) in `extra`.
Nothing here asserts a time. A node that exits is an error (BellowsError with its log line).
"""
from array import array
import errno
import math
import os
from pathlib import Path
import random
import resource
import statistics
import sys
import threading
import time

import can
from rclpy.qos import qos_profile_sensor_data
from rclpy.serialization import serialize_message
import serial

from bellows_ros import interfaces

from bellows_ros.bench import Result
from bellows_ros.bench.graph import CAN_GROUPS, DOMAINS, GraphRun, node_environment
from bellows_ros.config.hardware import actuator_board_config
from bellows_ros.errors import BellowsError
from bellows_ros.hardware import can_protocol, serial_protocol
from bellows_ros.hardware.arm_bus import open_can
from bellows_ros.hardware.can_echo_filter import drop_own_frames
from bellows_ros.hardware.loop_timing import PeriodicLoop
from bellows_ros.hardware.sim_actuator_board import check_free, link_pty, owns_link
from bellows_ros.io import params
from bellows_ros.nodes import diagnostics
from bellows_ros.runtime import Node, realtime
from bellows_ros.runtime.messages import msg
from bellows_ros.runtime.parameters import Spec

CONFIG = params.default_file('nodes_sim')
# The nodes of scripts/launch_sim.sh, in its order.
NODES = ('sim_arm_node', 'sim_actuator_node', 'driver_node', 'model_node',
         'stiffness_controller_node', 'arm_controller_node', 'scenario_node')
SEGMENTS = 4                  # the arm's four
SCENARIO_DURATION = 3600.0    # s: the scenario runs on through the window
TOTAL_TARGET = 1.3            # core: the whole graph (the target)
TORQUE_TARGET = 1000.0        # Hz: every sample's driving torque
START_TIMEOUT = 120.0         # s: a loaded shared machine starts seven Python processes slowly
SETTLE = 3.0                  # s: discovery and the first reports, before the window
# s: --quick, a smoke run of both graphs (each node works, each figure is measured): the window,
# and the settling before it once the torque and the scenario's set-points flow
QUICK_WINDOW, QUICK_SETTLE = 3.0, 1.0
THREADS_SHOWN = 6             # busiest threads of a process in `extra`
# A floor node process: FLOORS[name] run as the nodes run (runtime.run).
FLOOR_MAIN = ('import sys; from bellows_ros.bench.graph_floor import FLOORS; '
              'from bellows_ros.runtime import run; raise SystemExit(run(FLOORS[sys.argv[1]]))')


def run(quick=False):
    window, settle = (QUICK_WINDOW, QUICK_SETTLE) if quick else (20.0, SETTLE)
    floor = _run_graph('floor', window, settle)
    whole = _run_graph('whole', window, settle)
    results = []
    for kind, run_ in (('floor', floor), ('whole', whole)):
        for name in NODES:
            result = Result(f'graph.{kind}.cpu.{name}', run_['cpu'][name], 'core', 1,
                            extra={'scheduling': run_['scheduling'][name],
                                   'runqueue_wait': run_['waited'][name],
                                   'threads': run_['threads'][name]},
                            extra_units={'runqueue_wait': ''})
            if kind == 'whole':
                _against(result, floor['cpu'][name], f'graph.floor.cpu.{name}')
            results.append(result)
        total = Result(f'graph.{kind}.cpu.total', sum(run_['cpu'].values()), 'core', len(NODES),
                       target=TOTAL_TARGET,
                       extra={'window': run_['window'], 'bench_process': run_['bench_cpu'],
                              'steal': run_['steal'], 'loadavg_before': run_['loadavg'][0],
                              'loadavg_after': run_['loadavg'][1]},
                       extra_units={'window': 's', 'steal': ''})
        rate = Result(f'graph.{kind}.torque_rate', run_['torque_rate'], 'Hz',
                      run_['torque_messages'], target=TORQUE_TARGET,
                      extra={'segments_per_message': SEGMENTS},
                      extra_units={'segments_per_message': ''})
        if kind == 'whole':  # the model node's own count (nan: no report in the window)
            rate.extra['model_rate_hz'] = run_['model_rate']
            rate.extra_units['model_rate_hz'] = 'Hz'
        if kind == 'whole':
            _against(total, sum(floor['cpu'].values()), 'graph.floor.cpu.total')
            _against(rate, floor['torque_rate'], 'graph.floor.torque_rate')
        results += [total, rate]
    return results


def _against(result, reference_value, reference_name):
    result.reference = reference_name
    result.ratio = result.value / reference_value if reference_value else float('nan')


def _overrides(name, port, group, output):
    """Return the whole graph's per-run values (launch_sim.sh's launch_parameters.yaml)."""
    given = {'sim_arm_node': {'can.channel': group, 'n_segments': SEGMENTS},
             'sim_actuator_node': {'port': port},
             'driver_node': {'autostart': 'true', 'arm.channel': group,
                             'arm.n_segments': SEGMENTS, 'actuator.port': port,
                             # the consumers listen before the first sample goes out
                             'wait_for_subscribers': 20.0},
             'model_node': {'segments': list(range(1, SEGMENTS + 1))},
             'scenario_node': {'duration': SCENARIO_DURATION, 'output_dir': output}}
    # `-p node:name:=value`: wins over the node's own section of the file (rcl's rule).
    return [arg for key, value in given.get(name, {}).items()
            for arg in ('-p', f'{name}:{key}:={value}')]


def _floor_arguments(name, port, group):
    """Return a floor node's parameters: its node's scheduling and traffic, from the config."""
    config = params.read_file(CONFIG, name)
    given = {'realtime_priority': config.get('realtime_priority', 0),
             'cpu_latency_limit': float(config.get('cpu_latency_limit', -1.0))}
    if name in ('sim_arm_node', 'driver_node'):
        given['can_channel'] = group
    if name in ('sim_actuator_node', 'driver_node'):
        given['port'] = port
    if name in ('sim_arm_node', 'driver_node', 'model_node'):
        given['segments'] = list(range(1, SEGMENTS + 1))
    if name == 'arm_controller_node':
        given['segments'] = list(config['segments'])
    for key in ('control_every', 'publish_every'):
        if key in config:
            given[key] = config[key]
    return [arg for key, value in given.items() for arg in ('-p', f'{key}:={value}')]


def _run_graph(kind, window, settle):
    """Start the `kind` ('whole' or 'floor') graph; its figures over `window` s after `settle`."""
    domain = str(random.randint(*DOMAINS['graph_floor']))
    group = f'{CAN_GROUPS["graph_floor"]}.{random.randint(2, 250)}'
    env = node_environment(domain)
    binary = Path(sys.executable).parent
    loadavg_before = _loadavg()
    final, model_rates, torque = {}, [], [0]
    with GraphRun(domain, f'bench_graph_{kind}') as graph:
        port, output = str(graph.logs / 'actuator'), str(graph.logs / 'scenario')
        node = graph.node

        def on_diagnostics(array_):
            for status in array_.status:
                values = {kv.key: kv.value for kv in status.values}
                final[status.name] = values
                if status.name == 'model_node: driving torque' and 'rate_hz' in values:
                    model_rates.append(float(values['rate_hz']))

        def on_torque(_):
            torque[0] += 1
        node.create_subscription(msg.DiagnosticArray, interfaces.DIAGNOSTICS.name,
                                 on_diagnostics, interfaces.DIAGNOSTICS.depth)
        # The independent client: a plain rclpy subscriber, with the contract's QoS.
        node.create_subscription(msg.JointState, interfaces.DRIVING_TORQUE.resolved(),
                                 on_torque, interfaces.DRIVING_TORQUE.depth)

        def command(name):
            if kind == 'floor':
                return [sys.executable, '-c', FLOOR_MAIN, name, '--ros-args',
                        *_floor_arguments(name, port, group)]
            return [str(binary / name), '--ros-args', '--params-file', str(CONFIG),
                    *_overrides(name, port, group, output)]

        def wait(what, done):
            end = time.monotonic() + START_TIMEOUT
            while not done():
                if time.monotonic() > end:
                    raise BellowsError(f'bench graph_floor ({kind}): no {what} after '
                                       f'{START_TIMEOUT:g} s')
                graph.spin(0.05)

        # launch_sim.sh's order, but the driver after its consumers (wait_for_subscribers) and
        # the scenario once samples flow, as launch_sim.sh starts it 3 s after the others.
        graph.start('sim_arm_node', command('sim_arm_node'), env)
        graph.start('sim_actuator_node', command('sim_actuator_node'), env)
        wait(f'pty at {port}', lambda: os.path.exists(port))
        for name in ('model_node', 'stiffness_controller_node', 'arm_controller_node',
                     'driver_node'):
            graph.start(name, command(name), env)
        wait('driving torque on /bellows/driving_torque', lambda: torque[0] > 0)
        if kind == 'whole':
            wait("the driver's actuator samples", lambda: int(
                final.get('driver_node: actuator', {}).get('published', 0)) > 0)
        graph.start('scenario_node', command('scenario_node'), env)
        wait('scenario (a publisher of the stiffness set-point)', lambda: node.count_publishers(
            interfaces.STIFFNESS_SETPOINT.resolved()) > 0)
        graph.spin(settle)
        pids = {name: process.pid for name, process in graph.processes.items()}
        threads0 = {name: _thread_seconds(pid) for name, pid in pids.items()}
        bench0 = _own_cpu_seconds()
        count0, start = torque[0], time.monotonic()
        model_rates.clear()
        cpu, stolen = graph.cpu_window(window)
        elapsed = time.monotonic() - start
        count = torque[0] - count0
        bench_cpu = (_own_cpu_seconds() - bench0) / elapsed
        threads1 = {name: _thread_seconds(pid) for name, pid in pids.items()}
        threads = {name: _busiest(threads0[name], threads1[name], elapsed) for name in pids}
        waited = {name: _waited(threads0[name], threads1[name], elapsed) for name in pids}
        scheduling = {name: _scheduling(pid) for name, pid in pids.items()}
    return {'cpu': cpu, 'steal': stolen, 'window': elapsed, 'torque_rate': count / elapsed,
            'torque_messages': count, 'bench_cpu': bench_cpu, 'threads': threads,
            'scheduling': scheduling, 'waited': waited,
            'model_rate': statistics.median(model_rates) if model_rates else float('nan'),
            'loadavg': (loadavg_before, _loadavg())}


def _loadavg():
    """Return the load average over 1, 5 and 15 minutes ('' where /proc does not say)."""
    try:
        with open('/proc/loadavg') as stream:
            return ' '.join(stream.read().split()[:3])
    except OSError:
        return ''


def _own_cpu_seconds():
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def _thread_seconds(pid):
    """
    {thread id: (kernel thread name, utime + stime s, run-queue wait s)} of process `pid`.

    The wait (/proc/<pid>/task/<tid>/schedstat, nan where the kernel keeps no schedstats) is the
    time the thread was ready to run but not running: a node starved by others shows there.
    """
    found = {}
    try:
        tids = os.listdir(f'/proc/{pid}/task')
    except OSError:
        return found
    for tid in tids:
        try:
            with open(f'/proc/{pid}/task/{tid}/stat') as stream:
                text = stream.read()
        except OSError:
            continue  # the thread ended in between
        name = text[text.index('(') + 1:text.rindex(')')]
        fields = text.rsplit(')', 1)[1].split()  # utime, stime: fields 14 and 15 of stat
        try:
            with open(f'/proc/{pid}/task/{tid}/schedstat') as stream:
                waited = int(stream.read().split()[1]) * 1e-9
        except (OSError, IndexError, ValueError):
            waited = float('nan')
        found[tid] = (name, (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK'),
                      waited)
    return found


def _busiest(before, after, elapsed):
    """Return the busiest threads over the window, {name: fraction of a core}, by name."""
    by_name = {}
    for tid, (name, seconds, _) in after.items():
        spent = seconds - before.get(tid, (name, 0.0, 0.0))[1]
        by_name[name] = by_name.get(name, 0.0) + spent / elapsed
    busiest = sorted(by_name.items(), key=lambda item: -item[1])[:THREADS_SHOWN]
    return {name: round(fraction, 4) for name, fraction in busiest if fraction > 0}


def _waited(before, after, elapsed):
    """Run-queue wait of all a process's threads over the window, s per s of window."""
    return sum(waited - before.get(tid, (name, 0.0, 0.0))[2]
               for tid, (name, _, waited) in after.items()) / elapsed


def _scheduling(pid):
    """Return the policy of a process's main thread: 'SCHED_FIFO 60', 'SCHED_OTHER'."""
    try:
        policy = os.sched_getscheduler(pid)
        priority = os.sched_getparam(pid).sched_priority
    except OSError:
        return 'unknown'
    if policy == os.SCHED_FIFO:
        return f'SCHED_FIFO {priority}'
    return {os.SCHED_OTHER: 'SCHED_OTHER', os.SCHED_RR: f'SCHED_RR {priority}'}.get(
        policy, str(policy))


# --- the floor nodes ------------------------------------------------------------------------
FLOOR_PARAMETERS = (
    Spec('can_channel', '', "the simulated CAN bus's group (the simulated arm, the driver)"),
    Spec('port', '', "the simulated actuator's pty (the simulated actuator, the driver)"),
    Spec('segments', [1], 'arm segments of its frames (simulated arm), messages (driver, '
         'model) or commands (arm controller)'),
    Spec('control_every', 5, 'samples per command (the controllers)', low=1, high=100),
    Spec('publish_every', 2, 'commands per stiffness message (the stiffness controller)',
         low=1, high=100),
)


def _ignore(message):
    """Take a subscription's message and do nothing with it."""


def _joint_state(names, **fields):
    message = msg.JointState(name=list(names),
                             **{key: array('d', values) for key, values in fields.items()})
    message.header.stamp.sec = 1
    return message


def _serialized(names, **fields):
    """Return a JointState serialized once: the node publishes its samples serialized."""
    return serialize_message(_joint_state(names, **fields))


def _telemetry():
    """Return a TELEMETRY frame of the actuator board, encoded once."""
    return serial_protocol.encode(serial_protocol.Telemetry(
        seq=1, t_us=1000, encoder_counts=100, pressure_pa=200000, spring_um=10000,
        force_mn=20000, status=0))


def _frame(db, name):
    """Return a CAN frame of the DBC's message `name`, its bytes laid out once."""
    message = db.get_message_by_name(name)
    return can.Message(arbitration_id=message.frame_id, is_extended_id=False,
                       data=bytes(message.length))


class _FloorNode(Node):
    """A floor node: its node's name, scheduling parameters and /diagnostics once a second."""

    reports = True  # every node of the graph but the scenario has a diagnostics.Updater

    def __init__(self, name, **kwargs):
        super().__init__(name, **kwargs)
        self.given = self.declare_specs(FLOOR_PARAMETERS)
        realtime.declare(self)  # runtime.run applies them, as to the node this stands for
        self.check_parameters()
        self.segments = list(self.given['segments'])
        if self.reports:
            status = msg.DiagnosticStatus(
                name=f'{name}: floor', message='floor', hardware_id='floor',
                values=[msg.KeyValue(key=f'key_{i}', value='0.000') for i in range(12)])
            self.diagnostics = msg.DiagnosticArray(status=[status])
            self.diagnostics_pub = self.publisher(interfaces.DIAGNOSTICS)
            self.create_timer(diagnostics.PERIOD,
                              lambda: self.diagnostics_pub.publish(self.diagnostics))
        self._stop = threading.Event()
        self._threads, self._buses = [], []

    def loop(self, body, name, period=interfaces.SAMPLE_PERIOD):
        """Run `body()` every `period` s on a thread of its own (PeriodicLoop)."""
        def ticks():
            for _ in PeriodicLoop(period).ticks(self._stop):
                body()
        self.thread(ticks, name)

    def thread(self, target, name):
        """Run `target()` on a thread of its own until the node closes (it checks `_stop`)."""
        thread = threading.Thread(target=target, name=name, daemon=True)
        thread.start()
        self._threads.append(thread)

    def bus(self, drop):
        """Open the simulated CAN bus as the node does, its own frames (`drop`) kept out."""
        bus = open_can('udp_multicast', self.given['can_channel'])
        drop_own_frames(bus, drop)
        self._buses.append(bus)
        return bus

    def close(self):
        self._stop.set()
        for thread in self._threads:
            thread.join(timeout=1.0)
        for bus in self._buses:
            bus.shutdown()


class SimArmFloor(_FloorNode):
    """sim_arm_node's floor: its CAN traffic at 1 kHz, pre-built frames (no plant, no codec)."""

    def __init__(self, **kwargs):
        super().__init__('sim_arm_node', **kwargs)
        db = can_protocol.load_dbc(None)
        samples = [_frame(db, f'ARM_SEG{s}_SAMPLE') for s in self.segments]
        status = _frame(db, 'ARM_STATUS')
        status_every = round(db.get_message_by_name('ARM_STATUS').cycle_time * 1e-3
                             / interfaces.SAMPLE_PERIOD)
        bus = self.bus(drop={frame.arbitration_id for frame in samples + [status]})
        ticks = [0]

        def tick():
            for _ in range(64):  # the host's frames, bounded per tick as the simulated arm's
                if bus.recv(timeout=0) is None:
                    break
            for frame in samples:
                bus.send(frame, timeout=0.01)
            if ticks[0] % status_every == 0:
                bus.send(status, timeout=0.01)
            ticks[0] += 1
        self.loop(tick, 'sim-arm-floor')


class SimActuatorFloor(_FloorNode):
    """sim_actuator_node's floor: a pty, a pre-built telemetry frame written each 1 ms tick."""

    def __init__(self, **kwargs):
        super().__init__('sim_actuator_node', **kwargs)
        self.port = self.given['port']
        check_free(self.port)  # as the simulated board: only where nothing exists
        master, slave, self.target = link_pty(self.port)
        self.fds = (master, slave)
        telemetry = _telemetry()

        def tick():
            try:
                os.read(master, 4096)  # the host's motor commands and heartbeats
            except OSError as error:
                if error.errno not in (errno.EAGAIN, errno.EIO):
                    raise
            try:
                os.write(master, telemetry)
            except OSError as error:  # a driver that does not read yet: the pty is full
                if error.errno not in (errno.EAGAIN, errno.EIO):
                    raise
        self.loop(tick, 'sim-actuator-floor')

    def close(self):
        super().close()
        for fd in self.fds:
            os.close(fd)
        if owns_link(self.port, self.target):  # the link this node made, and only that one
            os.unlink(self.port)


class DriverFloor(_FloorNode):
    """driver_node's floor: its devices' traffic in, a serialized message per sample out."""

    def __init__(self, **kwargs):
        super().__init__('driver_node', **kwargs)
        arm_pub = self.publisher(interfaces.JOINT_STATES)
        actuator_pub = self.publisher(interfaces.ACTUATOR_JOINT_STATES)
        self.publisher(interfaces.VENTED).publish(msg.Bool(data=True))  # latched, on change
        self.subscription(interfaces.ESTOP, _ignore)
        self.subscription(interfaces.PRESSURE_COMMAND, _ignore, raw=True)
        # The driver's messages, field for field: the joints' state and the chambers' pressure,
        # NaN where an entry has no value (interfaces.py).
        n, nan = len(self.segments), math.nan
        arm = _serialized(interfaces.arm_sample_names(self.segments),
                          position=[0.1] * n + [nan] * 2 * n, velocity=[0.0] * n + [nan] * 2 * n,
                          effort=[nan] * n + [2e5] * 2 * n)
        actuator = _serialized(interfaces.actuator_sample_names(),
                               position=[0.01, 0.01, nan], effort=[nan, 20.0, 2e5])
        lock = threading.Lock()  # both device threads publish, as the driver's readers do

        db = can_protocol.load_dbc(None)
        setpoints = [_frame(db, m.name) for m in db.messages
                     if m.name.startswith('ARM_SETPOINT_')]
        host = setpoints + [_frame(db, 'ARM_HOST_HEARTBEAT')]
        bus = self.bus(drop={frame.arbitration_id for frame in host})
        sample_ids = {db.get_message_by_name(f'ARM_SEG{s}_SAMPLE').frame_id
                      for s in self.segments}
        frames = [0]

        def arm_reader():
            while not self._stop.is_set():
                frame = bus.recv(timeout=0.05)
                if frame is None or frame.arbitration_id not in sample_ids:
                    continue
                frames[0] += 1
                if frames[0] % n == 0:
                    with lock:
                        arm_pub.publish(arm)

        def arm_tx():
            for frame in host:
                bus.send(frame, timeout=0.01)
        self.thread(arm_reader, 'arm-reader-floor')
        self.loop(arm_tx, 'arm-tx-floor',
                  db.get_message_by_name('ARM_HOST_HEARTBEAT').cycle_time * 1e-3)

        board = actuator_board_config()
        port = serial.Serial(self.given['port'], board.baud, timeout=0.02, write_timeout=0.05)
        self.serial = port
        telemetry_size = len(_telemetry())
        heartbeat = serial_protocol.encode(serial_protocol.Heartbeat(seq=1))
        motor = serial_protocol.encode(serial_protocol.MotorCommand(seq=1, duty_q15=1000))
        received = [0]

        def actuator_reader():
            while not self._stop.is_set():
                received[0] += len(port.read(max(1, port.in_waiting)))
                while received[0] >= telemetry_size:
                    received[0] -= telemetry_size
                    with lock:
                        actuator_pub.publish(actuator)

        def send(frame):
            try:
                port.write(frame)
            except (serial.SerialException, OSError):
                pass  # as the driver's board: a write that times out is counted, not fatal

        def actuator_heartbeat():
            while not self._stop.wait(board.heartbeat_period):
                send(heartbeat)
        self.subscription(interfaces.MOTOR_COMMAND, lambda _: send(motor))
        self.thread(actuator_reader, 'actuator-reader-floor')
        self.thread(actuator_heartbeat, 'actuator-heartbeat-floor')

    def close(self):
        super().close()
        self.serial.close()


class ModelFloor(_FloorNode):
    """model_node's floor: both torque messages (pre-built) per arm sample."""

    def __init__(self, **kwargs):
        super().__init__('model_node', **kwargs)
        joints = [interfaces.segment_joint(s) for s in self.segments]
        drive_pub = self.publisher(interfaces.DRIVING_TORQUE)
        external_pub = self.publisher(interfaces.EXTERNAL_TORQUE)
        drive = _serialized(joints, effort=[0.5] * len(joints))
        external = _serialized(joints, effort=[0.0] * len(joints))

        def on_sample(_):
            drive_pub.publish(drive)
            external_pub.publish(external)
        self.subscription(interfaces.JOINT_STATES, on_sample, raw=True)


class StiffnessControllerFloor(_FloorNode):
    """stiffness_controller_node's floor: a motor command every `control_every` samples."""

    def __init__(self, **kwargs):
        super().__init__('stiffness_controller_node', **kwargs)
        motor_pub = self.publisher(interfaces.MOTOR_COMMAND)
        stiffness_pub = self.publisher(interfaces.STIFFNESS)
        duty, stiffness = msg.Float64(data=0.1), msg.Float64(data=1500.0)
        every, publish_every = self.given['control_every'], self.given['publish_every']
        samples = [0]

        def on_sample(_):
            samples[0] += 1
            if samples[0] % every:
                return
            motor_pub.publish(duty)
            if (samples[0] // every) % publish_every == 0:
                stiffness_pub.publish(stiffness)
        self.subscription(interfaces.STIFFNESS_SETPOINT, _ignore)
        self.subscription(interfaces.ACTUATOR_JOINT_STATES, on_sample, raw=True)


class ArmControllerFloor(_FloorNode):
    """arm_controller_node's floor: a pressure command every `control_every` arm samples."""

    # s of samples between ~/state messages (arm_controller_node.STATE_PERIOD)
    STATE_EVERY = round(0.02 / interfaces.SAMPLE_PERIOD)

    def __init__(self, **kwargs):
        super().__init__('arm_controller_node', **kwargs)
        chains = [interfaces.chain_chamber(s, c) for s in self.segments for c in (1, 2)]
        command_pub = self.publisher(interfaces.PRESSURE_COMMAND)
        command = _serialized(chains, effort=[2e5] * len(chains))
        # control_msgs has no wheel on PyPI: the node publishes ~/state only where it imports.
        state_pub, state = None, None
        if msg.JointTrajectoryControllerState is not None:
            state_pub = self.publisher(interfaces.TRAJECTORY_STATE)
            joints = [interfaces.segment_joint(s) for s in self.segments]
            state = msg.JointTrajectoryControllerState(joint_names=joints)
        every = self.given['control_every']
        samples = [0]

        def on_sample(_):
            samples[0] += 1
            if (samples[0] - 1) % every == 0:
                command_pub.publish(command)
            if state_pub is not None and samples[0] % self.STATE_EVERY == 0:
                state_pub.publish(state)
        # As the node: best effort, newest only (a command acts on the present).
        self.subscription(interfaces.JOINT_STATES, on_sample, newest_only=True, raw=True)
        for topic in (interfaces.PSI_SETPOINT, interfaces.JOINT_TRAJECTORY, interfaces.VENTED):
            self.subscription(topic, _ignore)


class ScenarioFloor(_FloorNode):
    """scenario_node's floor: set-points from a 50 Hz timer; subscribed as the scenario is."""

    reports = False  # the scenario has no /diagnostics

    def __init__(self, **kwargs):
        super().__init__('scenario_node', **kwargs)
        setpoint_pub = self.publisher(interfaces.STIFFNESS_SETPOINT)
        angle_pub = self.publisher(interfaces.PSI_SETPOINT)
        setpoint = msg.Float64(data=1400.0)
        angle = _joint_state([interfaces.segment_joint(1)], position=[0.1], velocity=[0.0])
        ticks = [0]

        def command():
            if ticks[0] % 50 == 0:  # the scenario's: on change, and once a second
                setpoint_pub.publish(setpoint)
            ticks[0] += 1
            angle_pub.publish(angle)
        for topic in (interfaces.STIFFNESS, interfaces.VENTED, interfaces.DIAGNOSTICS):
            self.subscription(topic, _ignore)
        # Best effort, as the scenario takes them (it never holds up the driver's writers).
        for topic in (interfaces.JOINT_STATES, interfaces.ACTUATOR_JOINT_STATES,
                      interfaces.DRIVING_TORQUE):
            self.create_subscription(msg.JointState, topic.name, _ignore,
                                     qos_profile_sensor_data, raw=True)
        self.create_timer(0.02, command)


FLOORS = {'sim_arm_node': SimArmFloor, 'sim_actuator_node': SimActuatorFloor,
          'driver_node': DriverFloor, 'model_node': ModelFloor,
          'stiffness_controller_node': StiffnessControllerFloor,
          'arm_controller_node': ArmControllerFloor, 'scenario_node': ScenarioFloor}


if __name__ == '__main__':
    for result in run(quick='--quick' in sys.argv):
        print(result.as_dict())
