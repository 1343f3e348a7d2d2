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
arm_controller_node: angle tracking of the arm's segments, PID plus model-based feedforward.

Wiring only; the logic is in `control.angle_tracking` (PID, feedforward through the pressure
allocation of `control.pressure_allocation`) and `control.angle_trajectory` (built-in set-points).

  /joint_states (one message per 1 kHz sample: Ψ, Ψ̇ and the chain pressures): every sample
      steps each segment's own paper-A model (its contact memory, Algorithm 1); every
      `control_every`-th sample a command goes out:
  /bellows/pressure_command (JointState, effort = chain pressures, Pa abs, names
      `segment_i/chain_j`), inside the driver's limits [p0, p_max] of config/segment.yaml, at
      1 kHz / control_every — well inside the command watchdog of the interface contract
      (`interfaces.COMMAND_WATCHDOG`, which every driver's `hardware.arm_bus.command_timeout`
      meets): with no samples there is no command, and the driver vents the arm.
  /arm/psi_setpoint (JointState by segment name: position = Ψ_d rad, velocity = Ψ̇_d rad/s if
      given): from its first message on, a segment follows the topic instead of its trajectory.
  ~/joint_trajectory (trajectory_msgs/JointTrajectory, joint names `segment_i`): as
      ros2_controllers' joint_trajectory_controller takes it (`control.joint_trajectory`: its
      checks, its interpolation, a new trajectory replacing the rest of the old one from its
      start time); a message it refuses is logged with the reason and counted. Its times are on
      the samples' clock (ROS time); a header.stamp of zero means the latest sample's stamp.
  ~/state (control_msgs/JointTrajectoryControllerState, every STATE_PERIOD s of samples): per
      segment the reference (Ψ_d, Ψ̇_d, Ψ̈_d), the measured Ψ, Ψ̇, the error, the torque asked for.
  /bellows/vented (Bool, latched, from the driver): while True the chambers are held vented and
      commands may not take; every command then restarts the trackers from the measured angle,
      so the move back after the vent (`resume_speed`) starts where the segment fell. A gap in
      this node's own commands longer than the watchdog counts as a vent too (`restarts`).
  /diagnostics: per segment the tracking error (RMS and largest since the last report), the
      set-point, saturated commands, plus the loop timing and the age of the samples when a
      command is due (`sample_age_*_us`: their latency plus any backlog).

Before any set-point a segment holds the angle it had at the first sample (or follows the
built-in `trajectory`, started `trajectory_delay` s after the first sample, on sample stamps).
The newest command decides: a set-point ends a segment's joint trajectory, a joint trajectory
takes over from its start time.

Parameters: segments (int array), feedforward ('paper_a' | 'previous' | 'none' = feedback only),
trajectory ('' | 'reversals' | 'sweep'), trajectory_delay (s), pid.kp (N·m/rad), pid.ki
(N·m/(rad·s)), pid.kd (N·m·s/rad), pid.velocity_cutoff (Hz), pid.integral_limit (N·m),
feedforward_lead (s: the valves' lag the feedforward anticipates, 0 = none), co_contraction (Pa
above ambient on both chains), control_every (samples per command), params_file (str: YAML over
config/segment.yaml, e.g. identified parameters and the arm's segment.dynamics),
max_sample_age (s: no command from a sample older than this),
resume_speed (rad/s: after a vent, the set-point moves back from the measured angle at this
peak speed), realtime_priority, cpu_latency_limit (runtime/realtime.py). The gains (pid.*),
feedforward, feedforward_lead, co_contraction, max_sample_age and resume_speed are live:
`ros2 param set` takes effect at the next command (resume_speed: at the next move back; one under
way keeps its speed), with the integral and the contact memory kept
(`AngleTracker.retune`); a co-contraction that would lift the base pressure above p_max is refused
with the reason.
"""
from collections import deque
import math
import time

import numpy as np
from rclpy.time import Time

from bellows_ros import interfaces
from bellows_ros.config.segment import load_segment_params
from bellows_ros.control import angle_trajectory, joint_trajectory
from bellows_ros.control.angle_tracking import (AngleTracker, check_gains, FEEDFORWARDS,
                                                TrackingGains)
from bellows_ros.errors import ParameterError
from bellows_ros.hardware.can_protocol import dbc_segments
from bellows_ros.hardware.loop_timing import LoopStats
from bellows_ros.nodes import diagnostics
from bellows_ros.nodes.arm_sample import ArmSampleReader
from bellows_ros.runtime import Node, realtime, run
from bellows_ros.runtime.node import stamp_ns
from bellows_ros.runtime.parameters import Spec

SAMPLE_PERIOD = interfaces.SAMPLE_PERIOD  # s, the arm's sampling (the devices' 1 kHz clock)
STATE_PERIOD = 0.02   # s of sample time between ~/state messages (50 Hz)


PARAMETERS = (
    Spec('segments', [1], 'the arm segments to control (numbers on the CAN bus)', low=1,
         high=dbc_segments(), items=(1, dbc_segments()), unique=True),
    Spec('feedforward', 'paper_a', "model inverted as feedforward ('none' = feedback only)",
         choices=FEEDFORWARDS, read_only=False),
    Spec('trajectory', '', "built-in set-point trajectory ('' = hold, or /arm/psi_setpoint)",
         choices=('', *angle_trajectory.TRAJECTORIES)),
    Spec('trajectory_delay', 1.0, 'start of the built-in trajectory after the first sample, s',
         low=0.0, high=3600.0),
    Spec('pid.kp', 20.0, 'proportional gain, N·m/rad', low=0.0, high=1e4, read_only=False),
    Spec('pid.ki', 200.0, 'integral gain, N·m/(rad·s)', low=0.0, high=1e5, read_only=False),
    Spec('pid.kd', 1.0, 'derivative gain, N·m·s/rad', low=0.0, high=1e3, read_only=False),
    Spec('pid.velocity_cutoff', 20.0, 'cut-off of the angle-rate filter, Hz', low=0.1,
         high=500.0, read_only=False),
    Spec('pid.integral_limit', 20.0, 'bound of the integral term, N·m', low=0.0, high=1e3,
         read_only=False),
    Spec('feedforward_lead', 0.05, 'valve lag the feedforward anticipates, s (0 = none)',
         low=0.0, high=1.0, read_only=False),
    Spec('co_contraction', 0.0, 'pressure above ambient on both chains, Pa', low=0.0,
         high=6.5e5, read_only=False),
    Spec('control_every', 5, 'samples per pressure command (a command at least every quarter '
         'of the command watchdog)', low=1,
         high=int(interfaces.COMMAND_WATCHDOG / 4 / SAMPLE_PERIOD)),
    Spec('params_file', '', "YAML laid over config/segment.yaml ('' = defaults)"),
    Spec('max_sample_age', 0.02, 'no command from a sample older than this, s', low=1e-3,
         high=1.0, read_only=False),
    Spec('resume_speed', 0.5, 'peak speed of the move back to the set-point after a vent, rad/s',
         low=0.01, high=10.0, read_only=False),
)


class SegmentLoop:
    """One segment's tracker, its set-point source and its error statistics."""

    def __init__(self, segment, tracker, trajectory):
        self.name = interfaces.segment_joint(segment)
        self.chains = (interfaces.chain_chamber(segment, 1), interfaces.chain_chamber(segment, 2))
        self.tracker = tracker
        self.trajectory = trajectory
        self.origin = None          # s, sample time at which the built-in trajectory starts
        self.topic_setpoint = None  # (Ψ_d, Ψ̇_d) from /arm/psi_setpoint
        self.path = None            # control.joint_trajectory.Path from ~/joint_trajectory
        self.hold = None            # Ψ at the first sample
        self.setpoint = (math.nan, 0.0, 0.0)
        self.measured = (math.nan, math.nan)  # Ψ, Ψ̇ of the latest command's sample
        self.tau = math.nan         # N·m, the torque the latest command asked for
        self.squares, self.count, self.largest, self.saturated = 0.0, 0, 0.0, 0
        self.resume = None          # (start s, offset rad, duration s) of the move back

    def desired(self, now, later=0.0):
        """
        Return (Ψ_d, Ψ̇_d, Ψ̈_d) at sample time `now` s, or `later` s after it.

        The source's set-point (`source_setpoint`), plus, while the segment resumes after a vent,
        the offset from where it was then, fading out along a half-cosine (`begin_resume`).
        """
        psi, psi_dot, psi_ddot = self.source_setpoint(now, later)
        if self.resume is not None:
            start, offset, duration = self.resume
            x = (now + later - start) / duration
            if x < 1.0:
                w = math.pi / duration
                phase = math.pi * max(x, 0.0)
                psi += 0.5 * offset * (1.0 + math.cos(phase))
                psi_dot -= 0.5 * offset * w * math.sin(phase)
                psi_ddot -= 0.5 * offset * w * w * math.cos(phase)
        return psi, psi_dot, psi_ddot

    def begin_resume(self, now, psi, speed):
        """
        Start from the measured angle `psi` rad at sample time `now` s, back to the source's.

        After a vent the segment rests wherever it fell; the set-point it should be at is a step
        away, and the gains' step response overshoots by more than half the step
        (bench_results/0.1.0/notebook.md, 2026-11-26). So the set-point starts at `psi` and the
        offset fades out in a half-cosine whose peak speed is `speed` rad/s, as the built-in
        trajectory's moves do and as joint_trajectory_controller starts from the present state.
        """
        offset = psi - self.source_setpoint(now)[0]
        duration = abs(offset) * math.pi / (2.0 * speed)
        self.resume = (now, offset, duration) if duration > 0.0 else None

    def source_setpoint(self, now, later=0.0):
        """
        Return (Ψ_d, Ψ̇_d, Ψ̈_d) of the set-point source at sample time `now` s, or `later` after.

        A joint trajectory from its start on; before it (or without one) the topic set-point,
        extrapolated with its velocity, else the built-in trajectory, else the held angle.
        """
        t = now + later
        if self.path is not None and t >= self.path.start:
            return self.path.sample(t)
        if self.topic_setpoint is not None:
            psi, psi_dot = self.topic_setpoint
            return psi + later * psi_dot, psi_dot, 0.0
        if self.trajectory is not None and t >= self.origin:
            return angle_trajectory.setpoint(self.trajectory, t - self.origin)
        return self.hold, 0.0, 0.0

    def source(self, now):
        """Name what the segment follows at sample time `now` s (for /diagnostics)."""
        if self.path is not None and now >= self.path.start:
            return 'joint_trajectory'
        return ('topic' if self.topic_setpoint is not None else
                'trajectory' if self.trajectory is not None else 'hold')


class ArmControllerNode(Node):

    def __init__(self, **kwargs):
        super().__init__(interfaces.ARM_CONTROLLER_NODE, **kwargs)
        given = self.declare_specs(PARAMETERS)
        segments, feedforward = given['segments'], given['feedforward']
        trajectory, self.delay = given['trajectory'], given['trajectory_delay']
        lead = given['feedforward_lead']
        self.control_every, params_file = given['control_every'], given['params_file'] or None
        max_age = given['max_sample_age']
        realtime.declare(self)  # SCHED_FIFO priority, CPU latency limit: run() applies them
        self.check_parameters()
        path = angle_trajectory.by_name(trajectory) if trajectory else None
        self.watchdog_ns = round(interfaces.COMMAND_WATCHDOG * 1e9)
        self.params = params = load_segment_params(params_file)
        gains = self._gains(given)
        self.lead = lead
        self.loops = [SegmentLoop(i, AngleTracker(params, gains, feedforward), path)
                      for i in segments]
        self.feedforward = feedforward
        self.max_age_ns = round(max_age * 1e9)
        self.resume_speed = given['resume_speed']
        self.samples = 0
        self.first_stamp = self.last_stamp = None
        self.counts = dict.fromkeys(['commands', 'stale_skipped', 'restarts', 'rejected_samples',
                                     'rejected_setpoints', 'trajectories',
                                     'rejected_trajectories'], 0)
        self.trajectory_start = None  # s, start of the latest joint trajectory (its progress)
        self.last_state = None        # ns, stamp of the latest ~/state
        self.last_command = None
        self.driver_vented = False   # bellows/vented: the driver holds the chambers vented
        self.restarting = False      # the last command restarted the trackers (a vent lasts)
        self.stats = LoopStats()
        self.ages = deque(maxlen=1000)  # s, age of the sample at each command (or skip)
        self.report = diagnostics.LoopReport(self.stats)
        self.reader = ArmSampleReader(segments, 2.0 * params.p_max)

        self.command_pub = self.publisher(interfaces.PRESSURE_COMMAND)
        self.state_pub = None
        if self.msg.JointTrajectoryControllerState is not None:
            self.state_pub = self.publisher(interfaces.TRAJECTORY_STATE)
        else:  # no control_msgs wheel on PyPI (runtime/messages.py)
            self.get_logger().info('control_msgs is not installed: ~/state is not published')
        # The newest samples only: a command acts on the present (interfaces.md, "QoS").
        self.sample_subscription(interfaces.JOINT_STATES, self.control, newest_only=True)
        self.subscription(interfaces.PSI_SETPOINT, self.on_setpoint)
        self.subscription(interfaces.JOINT_TRAJECTORY, self.on_trajectory)
        self.subscription(interfaces.VENTED, self.on_vented)
        self.diagnostics = diagnostics.Updater(self)
        self.diagnostics.setHardwareID('none')  # software: the driver reports the devices
        self.diagnostics.add(ArmControllerTask(self))
        self.get_logger().info(
            f"tracking {', '.join(loop.name for loop in self.loops)}, feedforward {feedforward}"
            + (f', trajectory {trajectory}' if trajectory else ''))

    def _gains(self, values):
        return TrackingGains(values['pid.kp'], values['pid.ki'], values['pid.kd'],
                             values['pid.velocity_cutoff'], values['pid.integral_limit'],
                             self.params.p0 + values['co_contraction'],
                             values['feedforward_lead'])

    # --- live parameters (ros2 param set): from the next command ---------------------------------
    def parameter_problem(self, changed):
        """Say what the Specs cannot know: the co-contraction must stay within p_max."""
        try:
            check_gains(self._gains({**self.parameters, **changed}), self.params,
                        'arm_controller_node')
        except ParameterError as error:
            return str(error)
        return ''

    def on_parameters(self, changed):
        gains = self._gains(self.parameters)
        self.lead, self.feedforward = gains.lead, self.parameters['feedforward']
        self.max_age_ns = round(self.parameters['max_sample_age'] * 1e9)
        self.resume_speed = self.parameters['resume_speed']
        for loop in self.loops:
            loop.tracker.retune(gains, self.feedforward)

    # --- inputs ---------------------------------------------------------------------------------
    def on_setpoint(self, msg):
        for loop in self.loops:
            if loop.name not in msg.name:
                continue
            i = msg.name.index(loop.name)
            psi = msg.position[i] if i < len(msg.position) else math.nan
            psi_dot = msg.velocity[i] if i < len(msg.velocity) else 0.0
            if not (math.isfinite(psi) and math.isfinite(psi_dot)):
                self.counts['rejected_setpoints'] += 1
                continue
            loop.topic_setpoint = (psi, psi_dot)
            loop.path = None  # the newest command decides

    def on_vented(self, msg):
        self.driver_vented = bool(msg.data)

    def on_trajectory(self, msg):
        try:
            taken = self._take_trajectory(msg)
        except joint_trajectory.TrajectoryError as error:
            self.counts['rejected_trajectories'] += 1
            self.get_logger().error(f'joint trajectory refused: {error}')
            return
        self.counts['trajectories'] += 1
        self.get_logger().info(f"joint trajectory for {', '.join(taken)}")

    def _take_trajectory(self, msg):
        """Check a JointTrajectory and hand each named segment its new path; the names."""
        points = [joint_trajectory.Point(stamp_ns(p.time_from_start) * 1e-9, p.positions,
                                         p.velocities, p.accelerations, p.effort)
                  for p in msg.points]
        knots = joint_trajectory.parse(msg.joint_names, points,
                                       [loop.name for loop in self.loops])
        if self.last_stamp is None:
            raise joint_trajectory.TrajectoryError("no sample yet: the segments' angles are "
                                                   'unknown')
        # The controller's present is its latest sample: the paths run on sample stamps.
        now = self.last_stamp * 1e-9
        start = joint_trajectory.start_time(stamp_ns(msg.header.stamp) * 1e-9, now,
                                            points[-1].time_from_start)
        for loop in self.loops:
            if loop.name in knots:
                # From the source's set-point: a resumption's fading offset stays on top of the
                # new path as it was on the old one, so the set-point does not jump.
                loop.path = joint_trajectory.splice(knots[loop.name], start, now,
                                                    loop.source_setpoint, loop.path)
        self.trajectory_start = start
        return list(knots)

    # --- the loop -------------------------------------------------------------------------------
    def control(self, msg):
        start = time.perf_counter()
        if self.loops[0].name not in msg.name:
            return  # another publisher's joints on the topic
        stamp = msg.stamp_ns
        inputs = self.reader.rows(msg)
        if inputs is None:
            self.counts['rejected_samples'] += 1
            return
        if self.first_stamp is None:
            self.first_stamp = stamp
            for loop, row in zip(self.loops, inputs):
                loop.hold = row[0]
                loop.origin = stamp * 1e-9 + self.delay
        dt = SAMPLE_PERIOD if self.last_stamp is None else (stamp - self.last_stamp) * 1e-9
        self.last_stamp = stamp
        for loop, (psi, psi_dot, p1, p2) in zip(self.loops, inputs):
            loop.tracker.observe(psi, psi_dot, p1, p2, dt)
        self.samples += 1
        if (self.samples - 1) % self.control_every:
            return
        # A command from an old sample (a backlog after a stall) would act on a state long gone,
        # which destabilises the loop; none is sent, and if that persists the driver vents.
        now = self.get_clock().now().nanoseconds
        self.ages.append((now - stamp) * 1e-9)
        if now - stamp > self.max_age_ns:
            self.counts['stale_skipped'] += 1
            return
        t = stamp * 1e-9
        # Vented (the driver says so, or this node's commands stopped for longer than the
        # driver's watchdog waits): the segment rests where it fell. Start again from there,
        # at every command for as long as the vent lasts, so that none of the integral or the
        # set-point from before it is left when the driver takes commands again.
        vented = self.driver_vented or (self.last_command is not None
                                        and now - self.last_command > self.watchdog_ns)
        if vented:
            self.counts['restarts'] += not self.restarting
            for loop, row in zip(self.loops, inputs):
                loop.tracker.restart()
                loop.begin_resume(t, row[0], self.resume_speed)
        self.restarting = vented
        self.last_command = now
        names, efforts = [], []
        for loop, row in zip(self.loops, inputs):
            psi_d, psi_dot_d, psi_ddot_d = loop.setpoint = loop.desired(t)
            out = loop.tracker.command(psi_d, psi_dot_d, psi_ddot_d, row[0],
                                       self.control_every * SAMPLE_PERIOD,
                                       loop.desired(t, self.lead))
            names.extend(loop.chains)
            efforts.extend((out.p1, out.p2))
            loop.measured, loop.tau = row[:2], out.tau
            error = psi_d - row[0]
            loop.squares += error * error
            loop.count += 1
            loop.largest = max(loop.largest, abs(error))
            loop.saturated += out.saturated
        command = self.msg.JointState(name=names, effort=efforts)
        command.header.stamp = Time(nanoseconds=stamp).to_msg()
        self.command_pub.publish(command)
        self.counts['commands'] += 1
        if self.state_pub is not None and (
                self.last_state is None or stamp - self.last_state >= STATE_PERIOD * 1e9 - 1):
            self.last_state = stamp
            self.publish_state(command.header.stamp, t)
        self.stats.record(dt * self.control_every, 0.0, time.perf_counter() - start)

    def publish_state(self, stamp, now):
        """~/state as joint_trajectory_controller fills it: reference, feedback, error, output."""
        point = self.msg.JointTrajectoryPoint
        reference = point(positions=[loop.setpoint[0] for loop in self.loops],
                          velocities=[loop.setpoint[1] for loop in self.loops],
                          accelerations=[loop.setpoint[2] for loop in self.loops])
        if self.trajectory_start is not None and now > self.trajectory_start:
            since = round((now - self.trajectory_start) * 1e9)
            reference.time_from_start = self.msg.Duration(sec=since // 1_000_000_000,
                                                          nanosec=since % 1_000_000_000)
        feedback = point(positions=[loop.measured[0] for loop in self.loops],
                         velocities=[loop.measured[1] for loop in self.loops])
        error = point(positions=[r - f for r, f in zip(reference.positions, feedback.positions)],
                      velocities=[r - f for r, f in zip(reference.velocities,
                                                        feedback.velocities)])
        state = self.msg.JointTrajectoryControllerState(
            joint_names=[loop.name for loop in self.loops], reference=reference,
            feedback=feedback, error=error, output=point(effort=[loop.tau for loop in self.loops]),
            speed_scaling_factor=1.0)
        state.header.stamp = stamp
        self.state_pub.publish(state)


class ArmControllerTask(diagnostics.DiagnosticTaskGroup):
    """
    One status per segment loop ("arm_controller_node: segment_<i>"): tracking and timing.

    The node's shared numbers (rate, sample age, counters) are taken once per report and repeated
    in each segment's status, so that each reads on its own.
    """

    def __init__(self, node):
        super().__init__('segments')
        self.node = node
        self.reported_rejected = self.reported_stale = 0

    def statuses(self):
        node = self.node
        values, rate, _ = node.report.values()
        values.update({k: str(v) for k, v in node.counts.items()})
        p50 = math.nan
        if node.ages:  # how late the samples reach the controller (latency and backlog)
            ages = np.array(node.ages)
            p50, p99 = np.percentile(ages, [50, 99])
            values.update(sample_age_p50_us=f'{p50 * 1e6:.0f}',
                          sample_age_p99_us=f'{p99 * 1e6:.0f}',
                          sample_age_max_us=f'{ages.max() * 1e6:.0f}')
            node.ages.clear()
        values['feedforward'] = node.feedforward
        now = node.last_stamp * 1e-9 if node.last_stamp is not None else -math.inf
        rejected = node.counts['rejected_samples'] - self.reported_rejected
        self.reported_rejected = node.counts['rejected_samples']
        stale = node.counts['stale_skipped'] - self.reported_stale
        self.reported_stale = node.counts['stale_skipped']
        out = []
        for loop in node.loops:
            stat = diagnostics.DiagnosticStatusWrapper(name=loop.name)
            stat.update(values)
            rms = math.sqrt(loop.squares / loop.count) if loop.count else math.nan
            stat.update({'error_rms': f'{rms:.5f}', 'error_max': f'{loop.largest:.5f}',
                         'setpoint': f'{loop.setpoint[0]:.5f}', 'saturated': str(loop.saturated),
                         'source': loop.source(now)})
            if loop.path is not None:  # progress: how long until the trajectory's end
                stat.add('trajectory_remaining_s', f'{max(0.0, loop.path.end - now):.3f}')
            if rate == 0.0 and stale:
                # Samples come, but too late to act on: the driver's watchdog vents the arm.
                stat.summary(diagnostics.ERROR, f'every sample too old to act on ({stale} '
                             f'skipped, age p50 {p50 * 1e3:.1f} ms > max_sample_age): not '
                             'controlling')
            elif rate == 0.0:
                stat.summary(diagnostics.STALE, 'no samples since the last report (no driver '
                             f'publishing {interfaces.JOINT_STATES.name}?): not controlling')
            else:
                stat.summary(diagnostics.OK, f'tracking {stat.get("source")}, error RMS '
                             f'{rms:.4f} rad')
                if loop.saturated:
                    stat.mergeSummary(diagnostics.WARN, f'pressure saturated in {loop.saturated}'
                                      ' commands')
                if rejected:
                    stat.mergeSummary(diagnostics.WARN, f'{rejected} samples rejected')
            loop.squares, loop.count, loop.largest, loop.saturated = 0.0, 0, 0.0, 0
            out.append(stat)
        return out


def main(args=None):
    return run(ArmControllerNode, args)


if __name__ == '__main__':
    raise SystemExit(main())
