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
stiffness_controller_node: stiffness set-point -> chamber compression -> motor duty.

Wiring only; the logic is in `control.stiffness` (set-point, gas-amount correction from the
measured pressure) and `control.pd` (PD on the encoder position).

  /actuator/stiffness_setpoint (Float64, N/m) -> target compression x_c*
  /actuator/joint_states (one message per sample: x_c, x_s, the spring force, the pressure),
      every `control_every`-th sample (200 Hz by default: the lead screw moves 2.3 mm/s at most,
      so a faster loop gains nothing and costs a DDS message per sample):
      PD(x_c*, x_c) -> /actuator/motor_command (Float64, duty -1..1)
  /actuator/stiffness (Float64, N/m): present stiffness from the measured state, every
      `publish_every`-th control step.
The model is config/actuator.yaml with `actuator_params` laid over it (e.g. the doctor's
extended.yaml, buckling included). Where the spring buckles K(x_c) is not monotone: the node uses
the rising branch (`models.stiffness_map`), logs it and its range at start, refuses set-points
outside the range (error, previous target kept) and warns when a leak pushes the held set-point
out of it; /diagnostics carries branch, range and warning.

The doctor live (docs/doctor.md, `doctor.live`): every sample (x_c, x_s, the pressure, the
spring force) goes into a ring buffer; once a second the residuals of the model at its identified
gas amount (measured pressure and force minus (17), (7)-(12)) are compared with their noise floors,
taken from the first `model_health.calibration` seconds, and reported as `model_health` on
/diagnostics. When they leave the floor, the doctor diagnoses the last
`model_health.diagnosis_window` seconds in a separate process (one at a time, killed after
`model_health.time_bound` s) and the status turns WARN naming the cause and its fitted size. The
sample callback only appends a row; its cost is counted (`cost_per_sample_us`).

Parameters: actuator_params (str: YAML over config/actuator.yaml), pd.kp (1/m), pd.kd (s/m),
pd.velocity_cutoff (Hz), pd.duty_max, pd.deadband (m), gas_time_constant (s),
control_every (samples per control step), target_every (control steps between re-computations
of x_c* from the gas estimate), publish_every,
initial_stiffness (N/m; 0 = hold still until the first set-point), model_health.calibration,
model_health.window, model_health.diagnosis_window, model_health.time_bound,
model_health.rediagnose (s: the doctor live), realtime_priority (SCHED_FIFO
priority 1-99 for the node's threads; 0 = normal scheduling), cpu_latency_limit (s: CPU wake-up
latency held while the node runs, 0 = idle CPUs poll, negative = off; runtime/realtime.py).
The PD gains, gas_time_constant, control_every, target_every and publish_every are live: `ros2
param set` takes effect at the next control step (`on_parameters`); the others are read-only.
"""
import dataclasses
import math
import time

from bellows_ros import interfaces

from bellows_ros.config.actuator import load_actuator
from bellows_ros.control.pd import PDController, PDGains
from bellows_ros.control.stiffness import StiffnessSetpoint
from bellows_ros.doctor import live
from bellows_ros.errors import BellowsError
from bellows_ros.hardware.loop_timing import LoopStats
from bellows_ros.nodes import diagnostics
from bellows_ros.runtime import Node, realtime, run
from bellows_ros.runtime.parameters import Spec


# Parameter -> field of PDGains.
_PD_GAINS = {'pd.kp': 'kp', 'pd.kd': 'kd', 'pd.velocity_cutoff': 'velocity_cutoff',
             'pd.duty_max': 'duty_max', 'pd.deadband': 'deadband'}

PARAMETERS = (
    Spec('actuator_params', '', "YAML laid over config/actuator.yaml ('' = defaults)"),
    Spec('pd.kp', 400.0, 'proportional gain on the compression error, 1/m', low=0.0, high=1e6,
         read_only=False),
    Spec('pd.kd', 0.0, 'derivative gain, s/m', low=0.0, high=1e4, read_only=False),
    Spec('pd.velocity_cutoff', 50.0, 'cut-off of the compression-rate filter, Hz', low=0.1,
         high=500.0, read_only=False),
    Spec('pd.duty_max', 0.8, 'largest motor duty', low=0.01, high=1.0, read_only=False),
    Spec('pd.deadband', 2e-5, 'compression error within which the motor rests, m', low=0.0,
         high=1e-3, read_only=False),
    Spec('gas_time_constant', 2.0, 'time constant of the gas-amount estimate, s', low=0.01,
         high=3600.0, read_only=False),
    Spec('control_every', 5, 'samples per control step', low=1, high=100, read_only=False),
    Spec('target_every', 4, 'control steps between re-computations of the target compression',
         low=1, high=1000, read_only=False),
    Spec('publish_every', 2, 'control steps per /actuator/stiffness message', low=1, high=1000,
         read_only=False),
    Spec('initial_stiffness', 0.0, 'stiffness held from the start, N/m (0 = hold still until '
         'the first set-point)', low=0.0, high=1e6),
    # The doctor live (bellows_ros.doctor.live): read once at start.
    Spec('model_health.calibration', 20.0, 'first seconds of samples taken as healthy: noise '
         'floors and limits of the model residuals, s', low=5.0, high=3600.0),
    Spec('model_health.window', 5.0, 'rolling window of the residual RMS, s', low=0.5,
         high=600.0),
    Spec('model_health.diagnosis_window', 20.0, 'last seconds the doctor diagnoses when the '
         'residual leaves its floor, s', low=5.0, high=600.0),
    Spec('model_health.time_bound', 30.0, 'longest a diagnosis may run before it is killed, s',
         low=1.0, high=600.0),
    Spec('model_health.rediagnose', 10.0, 'seconds between diagnoses while the residual stays '
         'out of its floor', low=0.0, high=3600.0),
)


class StiffnessControllerNode(Node):

    def __init__(self, **kwargs):
        super().__init__('stiffness_controller_node', **kwargs)
        given = self.declare_specs(PARAMETERS)
        actuator_params = given['actuator_params'] or None
        gains = PDGains(**{field: given[name] for name, field in _PD_GAINS.items()})
        gas_time_constant = given['gas_time_constant']
        self.control_every, self.target_every = given['control_every'], given['target_every']
        self.publish_every, initial = given['publish_every'], given['initial_stiffness']
        realtime.declare(self)  # SCHED_FIFO priority, CPU latency limit: run() applies them
        self.check_parameters()
        config = load_actuator(actuator_params)
        self.setpoint = StiffnessSetpoint(config.model, gas_time_constant)
        self.live = live.LiveDoctor(
            config, calibration=given['model_health.calibration'],
            window=given['model_health.window'],
            diagnosis_s=given['model_health.diagnosis_window'],
            time_bound=given['model_health.time_bound'],
            rediagnose_s=given['model_health.rediagnose'])
        self.sample_index = interfaces.SampleIndex(interfaces.actuator_sample_names())
        self._health_update_ms = math.nan
        self.pd = PDController(gains)
        k_low, k_high = self.setpoint.range()
        x_low, x_high = self.setpoint.branch()
        self.get_logger().info(f'stiffness range [{k_low:.1f}, {k_high:.1f}] N/m on the rising '
                               f'branch x_c {x_low * 1e3:.2f}-{x_high * 1e3:.2f} mm')
        self._warned = None
        if initial:
            self.setpoint.set_stiffness(initial)
        self.target = None
        self.samples = 0
        self._last_stamp = None
        self._elapsed = 0.0  # s since the last control step
        self.counts = dict.fromkeys(['rejected_setpoints', 'samples_without_pressure',
                                     'samples_without_force'], 0)
        self.stats = LoopStats()
        self.report = diagnostics.LoopReport(self.stats)

        self.motor_pub = self.publisher(interfaces.MOTOR_COMMAND)
        self.stiffness_pub = self.publisher(interfaces.STIFFNESS)
        self.subscription(interfaces.STIFFNESS_SETPOINT, self.on_setpoint)
        # The actuator's own sample topic: the arm's 1 kHz samples never reach this node.
        self.sample_subscription(interfaces.ACTUATOR_JOINT_STATES, self.on_sample)
        self.diagnostics = diagnostics.Updater(self)
        self.diagnostics.setHardwareID('none')  # software: the driver reports the devices
        self.diagnostics.add('control', self.diagnose_control)
        self.diagnostics.add('model_health', self.diagnose_model_health)

    # --- live parameters (ros2 param set): from the next control step -------------------------
    def on_parameters(self, changed):
        gains = {field: changed[name] for name, field in _PD_GAINS.items() if name in changed}
        if gains:  # the rate filter's state is kept: no jump beyond the new gains' own
            self.pd.gains = dataclasses.replace(self.pd.gains, **gains)
        if 'gas_time_constant' in changed:
            self.setpoint.gas_time_constant = changed['gas_time_constant']
        for name in ('control_every', 'target_every', 'publish_every'):
            if name in changed:
                setattr(self, name, changed[name])

    def on_setpoint(self, msg):
        if msg.data == self.setpoint.k_target:
            return  # set-points may be repeated; only a change does anything
        try:
            self.setpoint.set_stiffness(msg.data)
        except BellowsError as exc:  # out of range: keep the previous target, say why
            self.counts['rejected_setpoints'] += 1
            self.get_logger().error(str(exc))
            return
        self.target = self.setpoint.target()
        self.get_logger().info(
            f'stiffness set-point {msg.data:.1f} N/m -> x_c {self.target:.5f} m')

    def on_sample(self, msg):
        start = time.perf_counter()
        layout = self.sample_index(msg.name)
        if layout is None:
            return  # another publisher's joints on the topic
        chamber, spring, gas = layout
        x_c, x_s = msg.position[chamber], msg.position[spring]
        # The load cell's force is the spring's effort, the pressure the chamber's; an absent
        # or unreadable one is NaN (interfaces.py).
        effort = msg.effort
        force = effort[spring] if len(effort) > spring else math.nan
        pressure = effort[gas] if len(effort) > gas else math.nan
        stamp = msg.stamp_ns
        dt = 1e-3 if self._last_stamp is None else max(1e-6, (stamp - self._last_stamp) * 1e-9)
        self._last_stamp = stamp
        if not math.isfinite(pressure):
            self.counts['samples_without_pressure'] += 1
            return
        if math.isfinite(force):
            self.live.sample(stamp * 1e-9, x_c, x_s, pressure, force)
        else:
            self.counts['samples_without_force'] += 1
        self.samples += 1
        self._elapsed += dt
        if self.samples % self.control_every:
            return
        dt, self._elapsed = self._elapsed, 0.0
        step = self.samples // self.control_every
        self.setpoint.update_measurement(x_c, x_s, pressure, dt)
        if self.setpoint.k_target is not None and (self.target is None
                                                   or step % self.target_every == 0):
            self.target = self.setpoint.target()
            if self.setpoint.warning != self._warned:
                self._warned = self.setpoint.warning
                if self._warned:
                    self.get_logger().warn(self._warned)
        duty = 0.0 if self.target is None else self.pd.update(self.target, x_c, dt)
        self.motor_pub.publish(self.msg.Float64(data=duty))
        if step % self.publish_every == 0:
            self.stiffness_pub.publish(self.msg.Float64(data=self.setpoint.estimate()))
        self.stats.record(dt, 0.0, time.perf_counter() - start)

    def diagnose_control(self, stat):
        """Report the control loop: rate, set-point, its reach (range, branch), why it is off."""
        values, rate, _ = self.report.values()
        values.update({k: str(v) for k, v in self.counts.items()})
        values['gas_p_ref'] = f'{self.setpoint.gas:.1f}'
        values['target_x_c'] = 'none' if self.target is None else f'{self.target:.6f}'
        values['stiffness_setpoint'] = str(self.setpoint.k_target)
        k_low, k_high = self.setpoint.range()
        x_low, x_high = self.setpoint.branch()
        values['stiffness_range'] = f'{k_low:.1f}-{k_high:.1f}'
        values['branch_x_c'] = f'rising {x_low:.6f}-{x_high:.6f}'
        values['warning'] = self.setpoint.warning or 'none'
        stat.update(values)
        if rate == 0.0:
            stat.summary(diagnostics.STALE, 'no samples since the last report (no driver '
                         f'publishing {interfaces.ACTUATOR_JOINT_STATES.name}?): not '
                         'controlling')
        elif self.setpoint.warning:
            stat.summary(diagnostics.WARN, f'set-point out of reach: {self.setpoint.warning}')
        else:
            stat.summary(diagnostics.OK, f'controlling at {rate:.0f} Hz')
        return stat

    def diagnose_model_health(self, stat):
        """Report the model's residuals against their floors; WARN with the doctor's verdict."""
        started = time.perf_counter()
        health = self.live.health
        state = self.live.update()
        self._health_update_ms = (time.perf_counter() - started) * 1e3
        diagnostics.add_model_health(stat, health.values(), self.live.cost_us(),
                                     self._health_update_ms)
        verdict = self.live.verdict
        stat.add('diagnosis', live.describe(verdict) if health.out_of_floor else 'none')
        stat.add('diagnosis_s', f"{verdict['seconds']:.2f}" if verdict else 'nan')
        stat.add('diagnoses', self.live.diagnoses)
        stat.add('samples_without_force', self.counts['samples_without_force'])
        if self.live.buffer.count == 0:
            stat.summary(diagnostics.STALE, 'no samples with pressure and spring force (no '
                         f'driver publishing {interfaces.ACTUATOR_JOINT_STATES.name}?): not '
                         'comparing')
        elif state == 'calibrating':
            stat.summary(diagnostics.OK, 'calibrating: taking the noise floors of the first '
                         f'{health.calibration:g} s')
        elif health.out_of_floor:
            worst = health.worst()
            stat.summary(diagnostics.WARN, f'model residual {health.ratios[worst]:.1f} x its '
                         f'noise floor ({worst}, limit {health.limits[worst]:.1f}): '
                         f'{live.describe(verdict)}')
        else:
            stat.summary(diagnostics.OK, 'model within its noise floor')
        return stat


def main(args=None):
    return run(StiffnessControllerNode, args)


if __name__ == '__main__':
    raise SystemExit(main())
