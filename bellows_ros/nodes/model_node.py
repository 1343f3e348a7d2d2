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
model_node: paper A's driving torque for every sample of every configured segment.

Event-driven (no timer): the driver publishes each sample as one `/joint_states` message (Ψ, Ψ̇,
chain pressures); for each, every segment's `SegmentModel.step(psi, psi_dot, p1, p2)` runs once
(its strain memory carries from sample to sample, Algorithm 1) and the node publishes

  /bellows/driving_torque   effort = τ_drive per segment (2), N·m, stamped with the sample's stamp
  /bellows/external_torque  effort = τ_ext = M Ψ̈ + C Ψ̇ + N(Ψ) − τ_drive (2), N·m (quasi-static
                            unless segment.dynamics.* are set), same stamp.

Parameters: segments (int array, which segments to evaluate), params_file (str: identified
parameters from `bellows identify`, laid over config/segment.yaml; '' = defaults),
latency_budget (s: a torque published later than this after its sample's stamp is counted `late`),
realtime_priority (int: SCHED_FIFO priority 1-99 for the node's threads, 0 = normal scheduling),
cpu_latency_limit (s: CPU wake-up latency held while the node runs, 0 = idle CPUs poll, negative =
off; runtime/realtime.py).
A sample with a non-finite value or a pressure outside [0, 2 p_max] is rejected and counted; a
sample late by more than latency_budget is evaluated and counted `late`; samples that never
arrived (a gap in the stamps, which are on the devices' 1 ms time base) are counted `missed`.

Model health (docs/doctor.md, "The doctor live"; `live.segment_health`): the arm has no torque
sensor, so with no load on it τ_ext is the model's residual (model error plus noise). Every
sample's τ_ext goes into a preallocated ring buffer (all the 1 kHz path does; its cost is counted,
`cost_per_sample_us`); once a second the diagnostics update compares each segment's τ_ext over the
last `model_health.window` s with its noise floor, offset and limit, all taken from the first
`model_health.calibration` s, and reports `model_health` on /diagnostics: WARN naming the segments
whose residual left its floor and by how much (no diagnosis: naming a segment's cause live would
need a torque sensor). Both parameters are read once at start.
"""
import time

from bellows_ros import interfaces

from bellows_ros.config.segment import load_segment_params
from bellows_ros.doctor import live
from bellows_ros.hardware.can_protocol import dbc_segments
from bellows_ros.hardware.loop_timing import LoopStats
from bellows_ros.models.derivatives import rate
from bellows_ros.models.segment import external_torque, SegmentModel
from bellows_ros.nodes import diagnostics
from bellows_ros.nodes.arm_sample import ArmSampleReader
from bellows_ros.runtime import Node, realtime, run
from bellows_ros.runtime.joint_state_cdr import JointStateWriter
from bellows_ros.runtime.parameters import Spec


PARAMETERS = (
    Spec('segments', [1, 2, 3, 4], 'the arm segments to evaluate (numbers on the CAN bus)',
         low=1, high=dbc_segments(), items=(1, dbc_segments()), unique=True),
    Spec('params_file', '', "identified parameters laid over config/segment.yaml ('' = "
         'defaults)'),
    Spec('latency_budget', 0.002, 'a torque published later than this after its sample is '
         'counted late, s', low=1e-4, high=1.0, read_only=False),
    # Model health (bellows_ros.doctor.live): read once at start (the limits hold for this window).
    Spec('model_health.calibration', 20.0, 'first seconds of samples taken as healthy: noise '
         'floors, offsets and limits of the external torque estimates, s', low=5.0, high=3600.0),
    Spec('model_health.window', 5.0, 'rolling window of the external torque RMS, s', low=0.5,
         high=600.0),
)
# The ring buffer between the sample path and the 1 Hz comparison: this many seconds of samples
# at up to HEALTH_RATE Hz (samples older than that at an update are not compared).
HEALTH_BUFFER_S = 10.0
HEALTH_RATE = 2000.0
# s: a longer stamp gap is a pause of the samples (a driver stopped or restarted), not samples
# lost: the longest a queue of the contract's depth could have held and dropped.
MAX_MISSED_GAP = interfaces.SAMPLE_DEPTH * interfaces.SAMPLE_PERIOD


class ModelNode(Node):

    def __init__(self, **kwargs):
        super().__init__('model_node', **kwargs)
        given = self.declare_specs(PARAMETERS)
        segments = given['segments']
        params_file, latency_budget = given['params_file'] or None, given['latency_budget']
        realtime.declare(self)  # SCHED_FIFO priority, CPU latency limit: run() applies them
        self.check_parameters()
        self.params = load_segment_params(params_file)
        self.names = [interfaces.segment_joint(i) for i in segments]
        # Both torque topics: the segments' joints, effort only, sent serialized.
        self.torque_writer = JointStateWriter(self.names, position=False, velocity=False)
        self.models = [SegmentModel(self.params) for _ in segments]
        self.previous_psi_dot = [None] * len(segments)
        self.psi_ddot = [0.0] * len(segments)
        self.health = live.segment_health(self.names, given['model_health.calibration'],
                                          given['model_health.window'])
        self.health_buffer = live.RingBuffer(int(HEALTH_BUFFER_S * HEALTH_RATE),
                                             ('t', *self.names))
        self.health_cost = live.SampleCost()
        self._health_read = 0
        self._health_update_ms = float('nan')
        self.counts = dict.fromkeys(['evaluated', 'rejected', 'late', 'missed'], 0)
        self.stats = LoopStats()
        self.report = diagnostics.LoopReport(self.stats)
        self.latency = []
        self.latency_budget_ns = round(latency_budget * 1e9)
        self.reported = dict.fromkeys(['rejected', 'missed'], 0)
        self._last_stamp = None      # of the last evaluated sample (Ψ̈'s time step)
        self._last_received = None   # of the last sample received, evaluated or rejected
        self.reader = ArmSampleReader(segments, 2.0 * self.params.p_max)

        self.drive_pub = self.publisher(interfaces.DRIVING_TORQUE)
        self.external_pub = self.publisher(interfaces.EXTERNAL_TORQUE)
        self.sample_subscription(interfaces.JOINT_STATES, self.evaluate)
        self.diagnostics = diagnostics.Updater(self)
        self.diagnostics.setHardwareID('none')  # software: no device of its own
        self.diagnostics.add('driving torque', self.diagnose_evaluation)
        # The delay from a sample's stamp to its torque's publication, against latency_budget.
        self.latency_status = diagnostics.TimeStampStatus(
            lambda: self.get_clock().now().nanoseconds * 1e-9, max_acceptable=latency_budget,
            name='latency')
        self.diagnostics.add(self.latency_status)
        self.diagnostics.add('model_health', self.diagnose_model_health)
        self.get_logger().info(f"evaluating {', '.join(self.names)}"
                               + (f' with {params_file}' if params_file else ''))

    def on_parameters(self, changed):
        """Take a live latency_budget (ros2 param set) from the next torque on."""
        if 'latency_budget' in changed:
            self.latency_budget_ns = round(changed['latency_budget'] * 1e9)
            self.latency_status.max_acceptable = changed['latency_budget']

    # --- the model -------------------------------------------------------------------------------
    def evaluate(self, msg):
        start = time.perf_counter()
        if self.names[0] not in msg.name:
            return  # another publisher's joints on the topic
        stamp = msg.stamp_ns
        self._count_missed(stamp)
        inputs = self.reader.rows(msg)
        if inputs is None:
            self.counts['rejected'] += 1
            return
        drive = [model.step(psi, psi_dot, p1, p2).tau_drive
                 for model, (psi, psi_dot, p1, p2) in zip(self.models, inputs)]
        # The driving torque is what a controller waits for: it goes out before τ_ext is computed,
        # and the latency is taken at its publication (docs/nodes.md, "Timing").
        self.drive_pub.publish(self.torque_writer.serialize(stamp, effort=drive))
        now = self.get_clock().now().nanoseconds  # on the node clock
        latency = now - stamp
        self.latency.append(latency)
        self.latency_status.tick(stamp * 1e-9, now * 1e-9)
        if latency > self.latency_budget_ns:
            self.counts['late'] += 1
        self.counts['evaluated'] += 1
        dt = None if self._last_stamp is None else (stamp - self._last_stamp) * 1e-9
        self._last_stamp = stamp
        external = self.publish_external(stamp, inputs, drive, dt or 0.0)
        started = time.perf_counter()
        self.health_buffer.append((stamp * 1e-9, *external))
        self.health_cost.add(time.perf_counter() - started)
        self.stats.record(dt or 0.0, 0.0, time.perf_counter() - start)

    def _count_missed(self, stamp):
        """
        Count the samples between the previous one and `stamp` that never arrived.

        Lost before this node, or dropped by a queue that overflowed: the strain memory steps
        over them (docs/nodes.md, "When the CPU is short"). A rejected sample arrived.
        """
        if self._last_received is not None:
            gap = (stamp - self._last_received) * 1e-9
            if 1.5 * interfaces.SAMPLE_PERIOD < gap <= MAX_MISSED_GAP:
                self.counts['missed'] += round(gap / interfaces.SAMPLE_PERIOD) - 1
        self._last_received = stamp

    def publish_external(self, stamp, inputs, drive, dt):
        """Publish τ_ext (2) per segment on /bellows/external_torque, return it; Ψ̈ from Ψ̇'s."""
        external = []
        for i, ((psi, psi_dot, _, _), tau_drive) in enumerate(zip(inputs, drive)):
            psi_ddot = self.psi_ddot[i] = rate(psi_dot, self.previous_psi_dot[i], dt,
                                               self.psi_ddot[i])
            self.previous_psi_dot[i] = psi_dot
            external.append(float(external_torque(self.params, psi, psi_dot, psi_ddot, tau_drive)))
        self.external_pub.publish(self.torque_writer.serialize(stamp, effort=external))
        return external

    def diagnose_evaluation(self, stat):
        """Report the evaluation: rate, counts, latency percentiles; what is wrong."""
        values, rate, _ = self.report.values()
        values.update({k: str(v) for k, v in self.counts.items()})
        if self.latency:
            ordered = sorted(self.latency)
            values['latency_p50_us'] = f'{ordered[len(ordered) // 2] * 1e-3:.1f}'
            values['latency_p99_us'] = f'{ordered[int(0.99 * (len(ordered) - 1))] * 1e-3:.1f}'
            self.latency = []
        stat.update(values)
        rejected = self.counts['rejected'] - self.reported['rejected']
        missed = self.counts['missed'] - self.reported['missed']
        self.reported.update(rejected=self.counts['rejected'], missed=self.counts['missed'])
        if rate == 0.0:
            stat.summary(diagnostics.STALE, 'no samples since the last report (no driver '
                         f'publishing {interfaces.JOINT_STATES.name}?)')
            return stat
        stat.summary(diagnostics.OK, f'evaluating {rate:.0f} samples/s')
        if rejected:
            stat.mergeSummary(diagnostics.WARN, f'{rejected} samples rejected (non-finite, or '
                              'a pressure outside [0, 2 p_max])')
        if missed:
            stat.mergeSummary(diagnostics.WARN, f'{missed} samples never arrived (gaps in the '
                              'stamps)')
        return stat

    def diagnose_model_health(self, stat):
        """Report each segment's τ_ext against its healthy floor; WARN: which left it, how far."""
        started = time.perf_counter()
        rows, self._health_read = self.health_buffer.since(self._health_read)
        health = self.health
        state = health.update(rows)
        self._health_update_ms = (time.perf_counter() - started) * 1e3
        diagnostics.add_model_health(stat, health.values(), self.health_cost.take(),
                                     self._health_update_ms)
        if self.health_buffer.count == 0:
            stat.summary(diagnostics.STALE, 'no samples evaluated (no driver publishing '
                         f'{interfaces.JOINT_STATES.name}?): not comparing')
        elif state == 'calibrating':
            stat.summary(diagnostics.OK, 'calibrating: taking the noise floors of the first '
                         f'{health.calibration:g} s')
        elif health.out_of_floor:
            out = sorted((n for n in health.outputs if health.ratios[n] > health.limits[n]),
                         key=lambda n: -health.ratios[n] / health.limits[n]) or [health.worst()]
            stat.summary(diagnostics.WARN, 'external torque left its noise floor: ' + ', '.join(
                f'{n} {health.ratios[n]:.1f} x its floor (limit {health.limits[n]:.1f}), '
                f'{health.mean[n]:+.3g} N·m from its healthy level' for n in out))
        else:
            stat.summary(diagnostics.OK, 'external torque within its noise floor')
        return stat


def main(args=None):
    return run(ModelNode, args)


if __name__ == '__main__':
    raise SystemExit(main())
