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
scenario_node: a short scripted scenario on the running graph, printed and plotted.

1. Stiffness step: set-point `stiffness_low` (1400 N/m; raised to 1 % above the bottom of the
   actuator model's range when that is higher), then at `step_time` `stiffness_high` (1900 N/m).
2. Angle tracking, like for like: `segment_1` follows the built-in angle `trajectory`
   (`reversals`: moves at 0.4-2.6 rad/s, reversals and holds) through the arm controller
   (arm_controller_node), the set-points published on /arm/psi_setpoint at 50 Hz, twice on the
   same graph: first with paper A's model inverted as feedforward, then, after a hold of `GAP`
   s, feedback only (the controller's live parameter `feedforward` set to `none` through its
   parameter service; set back to what it was afterwards). `compare_feedforward: false` runs
   the trajectory once, with the controller as configured.
   From `trajectory_start` on the trajectory's first set-point is held; the first run starts
   once the arm is ready for it (`READY`): the controller says on /diagnostics that it follows
   the topic, and the angle has stayed within `READY_TOLERANCE` of that set-point, unvented,
   for `READY` s. A run that began while the graph was still coming up (a vent at activation,
   set-points sent before the controller's reader matched) would score the start-up, not the
   controller.

What comes back is recorded: /actuator/stiffness, /joint_states (segment_1 Ψ and pressures),
/actuator/joint_states (air_chamber x_c), /bellows/driving_torque (segment_1 τ_drive); of the
three 1 kHz topics one sample in `SERIES_EVERY` is kept (a 200 Hz series). At the end
it prints a summary (step settling time and overshoot; the RMS tracking error of each run and their
ratio) and writes `output_dir/scenario.csv` and `output_dir/scenario.png`, whose angle and error
panels show both runs on the trajectory's own time axis.

Parameters: duration (s), step_time (s), stiffness_low, stiffness_high (N/m), trajectory (str),
trajectory_start (s), compare_feedforward (bool), output_dir (str), actuator_params (str),
realtime_priority (SCHED_FIFO priority, 0 = normal scheduling; when the 1 kHz nodes run
SCHED_FIFO give it one too, below theirs), cpu_latency_limit (s: CPU wake-up latency held while
the node runs, 0 = idle CPUs poll, negative = off; runtime/realtime.py).
"""
import csv
import itertools
import math
from pathlib import Path

from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient

from bellows_ros import interfaces
from bellows_ros.config.actuator import load_actuator_params
from bellows_ros.control import angle_trajectory
from bellows_ros.errors import BellowsError
from bellows_ros.io.outputs import atomic_file
from bellows_ros.models.stiffness_map import stiffness_range
from bellows_ros.runtime import Node, realtime, run
from bellows_ros.runtime.parameters import Spec


# The scenario drives and records segment 1 of the arm, and the actuator.
SEGMENT = interfaces.segment_joint(1)
AIR_CHAMBER = interfaces.ACTUATOR_JOINTS[0]
# s: the hold at the trajectory's end point (rest) between the two runs; the controller's
# feedforward is switched at its middle.
GAP = 3.0
# The two runs of the comparison: (label, the arm controller's `feedforward`).
RUNS = (('paper A feedforward', 'paper_a'), ('feedback only', 'none'))
# s the arm holds the trajectory's first set-point, within READY_TOLERANCE rad, before a run.
READY, READY_TOLERANCE = 1.0, 0.05
# Of the 1 kHz samples the scenario keeps one in SERIES_EVERY: 200 Hz resolves the trajectory's
# moves. It reads every sample's bytes as the 1 kHz nodes do (runtime/joint_state_cdr.py): 2.6 us
# a sample, against 1.8 us a sample for rclpy decoding one in five
# (bench_results/0.1.0/notebook.md, 2026-11-29).
SERIES_EVERY = 5

PARAMETERS = (
    Spec('duration', 80.0, 'length of the scenario, s', low=1.0, high=24 * 3600.0),
    Spec('step_time', 5.0, 'time of the stiffness step, s', low=0.0, high=24 * 3600.0),
    Spec('stiffness_low', 1400.0, 'stiffness before the step, N/m', low=0.0, high=1e6),
    Spec('stiffness_high', 1900.0, 'stiffness after the step, N/m', low=0.0, high=1e6),
    Spec('trajectory', 'reversals', 'built-in angle trajectory of segment_1',
         choices=tuple(angle_trajectory.TRAJECTORIES)),
    Spec('trajectory_start', 2.0, "from then on the trajectory's first set-point, then the "
         'runs once the arm is ready, s', low=0.0, high=24 * 3600.0),
    Spec('compare_feedforward', True, "run the trajectory twice: paper A's feedforward, then "
         "feedback only (the arm controller's live parameter)"),
    Spec('output_dir', 'scenario_out', 'directory of scenario.png and scenario.csv',
         check=lambda path: '' if path else 'must not be empty'),
    Spec('actuator_params', '', "YAML laid over config/actuator.yaml ('' = defaults)"),
)


def one_in(every, callback):
    """Return a callback that passes on every `every`-th of its calls."""
    count = itertools.count()

    def take(sample):
        if next(count) % every == 0:
            callback(sample)
    return take


class ScenarioNode(Node):

    def __init__(self, **kwargs):
        super().__init__('scenario_node', **kwargs)
        given = self.declare_specs(PARAMETERS)
        self.duration, self.step_time = given['duration'], given['step_time']
        k_low, self.k_high = given['stiffness_low'], given['stiffness_high']
        self.trajectory = angle_trajectory.by_name(given['trajectory'])
        self.trajectory_start = given['trajectory_start']
        self.output_dir = Path(given['output_dir'])
        actuator_params = given['actuator_params'] or None
        realtime.declare(self)  # SCHED_FIFO priority, CPU latency limit: run() applies them
        self.check_parameters()
        k_min, k_max = stiffness_range(load_actuator_params(actuator_params))
        self.k_low = max(k_low, 1.01 * k_min)
        if self.k_low != k_low:
            self.get_logger().warn(f'stiffness_low {k_low:.0f} N/m is below the actuator range '
                                   f'[{k_min:.0f}, {k_max:.0f}] N/m; using {self.k_low:.0f} N/m')
        if not k_min <= self.k_high <= k_max:
            raise BellowsError(f'scenario_node: stiffness_high {self.k_high:.0f} N/m is outside '
                               f'the actuator range [{k_min:.0f}, {k_max:.0f}] N/m')
        self.output_dir.mkdir(parents=True, exist_ok=True)
        self.setpoint_pub = self.publisher(interfaces.STIFFNESS_SETPOINT)
        self.angle_pub = self.publisher(interfaces.PSI_SETPOINT)
        self.series = {name: [] for name in ('stiffness', 'x_c', 'psi', 'psi_setpoint', 'p1', 'p2',
                                             'tau_drive')}
        self.subscription(interfaces.STIFFNESS, lambda m: self._add('stiffness', m.data))
        # When the driver vented the arm (its samples too old to act on: the graph fell behind),
        # a run's tracking error measures the machine, not the controller.
        self.vents = []  # s since the start of each True on bellows/vented
        self.subscription(interfaces.VENTED, self.on_vented)
        # Best effort: the scenario must never hold up the driver's reliable writers (a reader
        # that does not acknowledge makes them block) and may miss samples when it falls behind.
        self.sample_index = interfaces.SampleIndex(interfaces.segment_sample_names(1))
        for topic, callback in ((interfaces.JOINT_STATES, self.on_joint_states),
                                (interfaces.ACTUATOR_JOINT_STATES, self.on_actuator_states),
                                (interfaces.DRIVING_TORQUE, self.on_torque)):
            self.sample_subscription(topic, one_in(SERIES_EVERY, callback), newest_only=True)
        # Until the runs are placed (`ready`): the arm holds the trajectory's first set-point.
        self.hold = angle_trajectory.setpoint(self.trajectory, 0.0)[0]
        self.modes = list(RUNS) if given['compare_feedforward'] else [('as configured', None)]
        self.following = False     # the controller's /diagnostics: it follows the topic
        self.settled_since = None  # s: since then Ψ within READY_TOLERANCE of `hold`, unvented
        self.subscription(interfaces.DIAGNOSTICS, self.on_diagnostics)
        self.runs = []             # (label, feedforward or None = as configured, start s)
        self.switches = []         # (s, feedforward or None = back to the configured one)
        self.controller = AsyncParameterClient(self, interfaces.ARM_CONTROLLER_NODE)
        self.switch_results = []  # (mode, SetParameters future)
        self.configured = None    # GetParameters future: the controller's feedforward before
        self.start_ns = self.get_clock().now().nanoseconds
        self.done = False
        self._last_setpoint, self._ticks = None, 0
        self.create_timer(0.02, self.command)

    def elapsed(self, stamp=None):
        """Seconds since the start, now or at a sample's `stamp` (ns)."""
        ns = self.get_clock().now().nanoseconds if stamp is None else stamp
        return (ns - self.start_ns) * 1e-9

    def _add(self, name, value, stamp=None):
        # Samples carry the time they were taken: a recorder that falls behind (it has the
        # lowest priority in the graph) still puts each where it belongs.
        self.series[name].append((self.elapsed(stamp), value))

    def on_vented(self, msg):
        if msg.data:
            self.vents.append(self.elapsed())
            self.settled_since = None

    def on_diagnostics(self, array):
        name = f'{interfaces.ARM_CONTROLLER_NODE}: {SEGMENT}'
        for status in array.status:
            if status.name == name:
                self.following = any(kv.key == 'source' and kv.value == 'topic'
                                     for kv in status.values)

    def on_joint_states(self, sample):
        layout = self.sample_index(sample.name)
        if layout is not None:
            segment, chain_1, chain_2 = layout
            psi = sample.position[segment]
            self._add('psi', psi, sample.stamp_ns)
            self._add('p1', sample.effort[chain_1], sample.stamp_ns)
            self._add('p2', sample.effort[chain_2], sample.stamp_ns)
            if self.runs:
                return
            if abs(psi - self.hold) > READY_TOLERANCE:
                self.settled_since = None
            elif self.settled_since is None:
                self.settled_since = self.series['psi'][-1][0]

    def held(self, t):
        """Whether Ψ has stayed at the first set-point, unvented, for `READY` s by `t` s."""
        return self.settled_since is not None and t - self.settled_since >= READY

    def ready(self, t):
        """Whether the first run may start at `t` s (module docstring, 2.)."""
        return t >= self.trajectory_start and self.following and self.held(t)

    def place_runs(self, start):
        """Place the runs from `start` s on, and the feedforward switches between them."""
        span = angle_trajectory.duration(self.trajectory) + GAP
        self.runs = [(label, mode, start + k * span) for k, (label, mode) in enumerate(self.modes)]
        self.switches = [(begin - GAP / 2, mode) for _, mode, begin in self.runs[1:]]
        if self.switches:  # and back to what the controller had, once the last run is over
            self.switches.append((self.runs[-1][2] + span - GAP / 2, None))
            self.configured = self.controller.get_parameters(['feedforward'])

    def on_actuator_states(self, sample):
        if AIR_CHAMBER in sample.name:
            self._add('x_c', sample.position[sample.name.index(AIR_CHAMBER)], sample.stamp_ns)

    def on_torque(self, sample):
        if SEGMENT in sample.name:
            self._add('tau_drive', sample.effort[sample.name.index(SEGMENT)], sample.stamp_ns)

    def stiffness_setpoint(self, t):
        return self.k_low if t < self.step_time else self.k_high

    def command(self):
        t = self.elapsed()
        if t >= self.duration:
            self.done = True
            return
        k = self.stiffness_setpoint(t)
        # on change, and at 1 Hz for late joiners
        if k != self._last_setpoint or self._ticks % 50 == 0:
            self.setpoint_pub.publish(self.msg.Float64(data=k))
            self._last_setpoint = k
        self._ticks += 1
        if not self.runs and self.ready(t):
            self.place_runs(t)
        if self.switches and t >= self.switches[0][0]:
            _, mode = self.switches.pop(0)
            if mode is None:  # back to the configured value (when it was read)
                result = self.configured.result() if self.configured.done() else None
                mode = result.values[0].string_value if result and result.values else RUNS[0][1]
            self.switch_results.append((mode, self.controller.set_parameters(
                [Parameter('feedforward', value=mode)])))
        if t >= self.trajectory_start:
            run_start = max((start for _, _, start in self.runs if start <= t), default=t)
            psi_d, psi_dot_d, _ = angle_trajectory.setpoint(self.trajectory, t - run_start)
            setpoint = self.msg.JointState(name=[SEGMENT], position=[psi_d],
                                           velocity=[psi_dot_d])
            setpoint.header.stamp = self.get_clock().now().to_msg()
            self.angle_pub.publish(setpoint)
            self._add('psi_setpoint', psi_d)

    # --- results
    # -----------------------------------------------------------------------------------
    def finish(self):
        """Print the summary, write the CSV and the plot."""
        for line in self.summary():
            print(line, flush=True)
        self.write()
        print(f'wrote {self.output_dir / "scenario.png"} and {self.output_dir / "scenario.csv"}',
              flush=True)

    def summary(self):
        lines = []
        after = [(t - self.step_time,
                  k) for t, k in self.series['stiffness'] if t >= self.step_time]
        if after:
            band = 0.02 * self.k_high
            outside = [t for t, k in after if abs(k - self.k_high) > band]
            overshoot = max(k for _, k in after) - self.k_high
            if abs(after[-1][1] - self.k_high) <= band:
                settled = f'within 2 % after {outside[-1] if outside else 0.0:.2f} s'
            else:  # e.g. a run shorter than the lead screw's travel time
                settled = (f'not within 2 % by the end of the run ({after[-1][0]:.1f} s after '
                           'the step)')
            lines.append(f'stiffness step {self.k_low:.0f} -> {self.k_high:.0f} N/m: {settled}, '
                         f'overshoot {max(0.0, overshoot):.1f} N/m, final {after[-1][1]:.1f} N/m')
        else:
            lines.append('stiffness step: no /actuator/stiffness received')
        lines += self.tracking_summary()
        for name, unit in (('p1', 'Pa'), ('psi', 'rad'), ('tau_drive', 'N·m'), ('x_c', 'm')):
            values = [v for _, v in self.series[name]]
            lines.append(f'{name}: {len(values)} samples' + (
                f', min {min(values):.4g} {unit}, max {max(values):.4g} {unit}' if values else ''))
        return lines

    def tracking_errors(self, start):
        """(t s from `start`, set-point minus measured Ψ rad) of segment_1 over one run."""
        end = start + angle_trajectory.duration(self.trajectory)
        return [(t - start, angle_trajectory.setpoint(self.trajectory, t - start)[0] - psi)
                for t, psi in self.series['psi'] if start <= t <= end]

    def tracking_summary(self):
        """Return the RMS tracking error of each run, and the ratio of the first to the second."""
        refused = [mode for mode, future in self.switch_results
                   if not (future.done() and future.result() is not None
                           and all(r.successful for r in future.result().results))]
        if refused:
            return [f'segment_1 tracking: the arm controller did not take feedforward '
                    f"'{refused[0]}' (is arm_controller_node running?): no comparison"]
        if not self.runs:
            held = self.held(self.elapsed())
            return [f'segment_1 tracking: no run, the arm was not ready in {self.duration:g} s '
                    f'(arm_controller_node following {interfaces.PSI_SETPOINT.name}: '
                    f'{"yes" if self.following else "no"}; Ψ within {READY_TOLERANCE:g} rad of '
                    f'the first set-point for {READY:g} s: {"yes" if held else "no"})']
        rms, lines, spoiled = [], [], False
        length = angle_trajectory.duration(self.trajectory)
        for label, _, start in self.runs:
            run = self.tracking_errors(start)
            errors = [e for _, e in run]
            if not errors or run[-1][0] < 0.95 * length:
                return lines + [f'segment_1 tracking ({label}): the run ended '
                                f'{run[-1][0] if run else 0.0:.1f} s into the {length:g} s '
                                f'trajectory (duration {self.duration:g} s is too short, or no '
                                f'{interfaces.JOINT_STATES.resolved(self.get_namespace())})']
            rms.append(math.sqrt(sum(e * e for e in errors) / len(errors)))
            vents = [t for t in self.vents if start <= t <= start + length]
            lines.append(f'segment_1 tracking, {label} ({len(errors)} samples): RMS error '
                         f'{rms[-1]:.4f} rad' + (
                             f'; the driver vented the arm {len(vents)} times in this run (its '
                             'samples too old to act on: the graph fell behind this machine)'
                             if vents else ''))
            spoiled = spoiled or bool(vents)
        if len(rms) == 2 and spoiled:
            lines.append('feedforward / feedback only: not compared (a run was vented)')
        elif len(rms) == 2:
            lines.append(f'feedforward / feedback only: {rms[0] / rms[1]:.2f} (same trajectory, '
                         'same graph, same gains)')
        return lines

    def write(self):
        with atomic_file(self.output_dir / 'scenario.csv', 'w', newline='') as stream:
            writer = csv.writer(stream)
            writer.writerow(['series', 't', 'value'])
            for name, points in self.series.items():
                writer.writerows((name, f'{t:.4f}', repr(v)) for t, v in points)
        import matplotlib
        matplotlib.use('Agg')
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(4, 1, figsize=(9, 11), sharex=True,
                                 gridspec_kw={'height_ratios': [1, 1, 1.3, 1]})

        def plot(ax, name, scale=1.0, **style):
            points = self.series[name]
            ax.plot([t for t, _ in points], [v * scale for _, v in points], **style)
        plot(axes[0], 'stiffness', label='estimated stiffness')
        ts = [t * 0.1 for t in range(int(self.duration * 10))]
        axes[0].plot(ts, [self.stiffness_setpoint(t) for t in ts], 'k--', label='set-point')
        axes[0].set_ylabel('stiffness (N/m)')
        plot(axes[1], 'p1', 1e-5, label='segment_1 chain 1')
        plot(axes[1], 'p2', 1e-5, label='segment_1 chain 2')
        axes[1].set_ylabel('pressure (bar abs)')
        deg = 180 / math.pi
        # Each run on the trajectory's own time: the angles, then the errors, one over the other.
        first = self.runs[0][2] if self.runs else self.trajectory_start
        trajectory_t = [t * 0.02 for t in range(int(angle_trajectory.duration(self.trajectory)
                                                    / 0.02))]
        axes[2].plot([first + t for t in trajectory_t],
                     [angle_trajectory.setpoint(self.trajectory, t)[0] * deg
                      for t in trajectory_t], color='k', ls='--', lw=1.0, label='Ψ set-point')
        for label, _, start in self.runs:
            psi = [(t - start + first, v * deg) for t, v in self.series['psi']
                   if start <= t <= start + angle_trajectory.duration(self.trajectory)]
            axes[2].plot([t for t, _ in psi], [v for _, v in psi], lw=1.0, label=f'Ψ, {label}')
            errors = self.tracking_errors(start)
            axes[3].plot([first + t for t, _ in errors], [e * deg for _, e in errors], lw=1.0,
                         label=label)
        axes[2].set_ylabel('segment_1 angle (deg)')
        axes[3].set_ylabel('set-point − Ψ (deg)')
        axes[3].set_xlabel("time (s); the runs on the first one's time axis")
        for ax in axes:
            ax.grid(True)
            ax.legend(loc='best')
        fig.tight_layout()
        with atomic_file(self.output_dir / 'scenario.png', 'wb') as stream:
            fig.savefig(stream, format='png', dpi=100)
        plt.close(fig)


def main(args=None):
    return run(ScenarioNode, args)


if __name__ == '__main__':
    raise SystemExit(main())
