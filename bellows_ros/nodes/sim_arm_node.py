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
sim_arm_node: the simulated soft arm on a CAN bus (python-can; udp_multicast between processes).

Runs one paper-A segment plant per segment (`models.segment_plant.SegmentPlant`) inside the
simulated arm (`hardware.sim_arm_bus`), which speaks the arm's CAN protocol (config/arm.dbc). The
driver joins the same bus exactly as it joins the robot's.

Node parameters:
  can.interface, can.channel (str): the python-can bus (udp_multicast + an IPv4 group for a
      simulation across processes).
  n_segments (int), segment_params (str: YAML over config/segment.yaml),
  effects (string array): contact_hysteresis, pressure_friction, natural_curvature, sensor_lag
      ([''] = the baseline plant), seed (int),
  load_torque (N·m, live): constant external torque on every segment (0 = free); a change
      (`ros2 param set`) takes effect at the next plant step.
  effect.<effect>.<parameter> (live): the strength of each effect on every segment
      (`segment_plant.STRENGTHS`: pressure_friction c_fp N·m, natural_curvature c_psi0_p rad,
      sensor_lag tau s), 0 = off, nan = as `effects` and segment_params say; a change
      (`ros2 param set`) takes effect at the next plant step, the strain memories carry on.
  clock_rate (Hz): /clock publication rate when use_sim_time is on (the node is then the clock).
  realtime_priority (int): SCHED_FIFO priority for the node's threads, 1-99; 0 = normal
      scheduling (runtime/realtime.py).
  cpu_latency_limit (s): CPU wake-up latency held while the node runs, 0 = idle CPUs poll;
      negative = off (runtime/realtime.py).
"""

import math

from rclpy.time import Time

from bellows_ros.config.segment import effect_range, load_segment
from bellows_ros.errors import BellowsError
from bellows_ros.hardware.arm_bus import open_can
from bellows_ros.hardware.can_protocol import dbc_segments
from bellows_ros.hardware.sim_arm_bus import SimArmBus
from bellows_ros.models import effect_strengths
from bellows_ros.models.segment_plant import SEGMENT_EFFECTS, SegmentPlant, STRENGTHS
from bellows_ros.nodes import diagnostics
from bellows_ros.nodes.live_effects import LiveEffectStrengths
from bellows_ros.runtime import Node, realtime, run
from bellows_ros.runtime.parameters import Spec


def _strength_spec(effect, key):
    # The range the CLI's --effect takes too (config/ranges.py, one home).
    rule = effect_range(effect, key)
    return Spec(effect_strengths.parameter_name(effect, key), math.nan,
                f'strength of the {effect} effect on every segment ({key}, {rule.unit}); 0 = off, '
                'nan = as effects and segment_params say', low=rule.low, high=rule.high,
                read_only=False)


PARAMETERS = (
    Spec('can.interface', 'udp_multicast', 'python-can interface of the simulated bus'),
    Spec('can.channel', '239.74.163.2', 'python-can channel (udp_multicast: an IPv4 multicast '
         'group)'),
    Spec('n_segments', 4, 'segments of the simulated arm', low=1, high=dbc_segments()),
    Spec('segment_params', '', "YAML laid over config/segment.yaml ('' = defaults)"),
    Spec('effects', [''], "physical effects of the plant ([''] = the baseline plant)",
         choices=('', *SEGMENT_EFFECTS), unique=True),
    Spec('seed', 1, 'seed of the sensor noise', low=0, high=2 ** 32 - 1 - dbc_segments()),
    Spec('load_torque', 0.0, 'constant external torque on every segment, N·m', low=-100.0,
         high=100.0, read_only=False),
    Spec('clock_rate', 100.0, '/clock messages per second when use_sim_time is on', low=1.0,
         high=1000.0),
    # One live strength per effect that has one (`segment_plant.STRENGTHS`).
    *(_strength_spec(effect, key) for effect, key in STRENGTHS.items()),
)


class SimArmNode(LiveEffectStrengths, Node):
    strength_table = STRENGTHS

    def __init__(self, **kwargs):
        super().__init__('sim_arm_node', **kwargs)
        given = self.declare_specs(PARAMETERS)
        interface, channel = given['can.interface'], given['can.channel']
        n_segments, segment_params = given['n_segments'], given['segment_params'] or None
        effects, seed = [e for e in given['effects'] if e], given['seed']
        self.load_torque, clock_rate = given['load_torque'], given['clock_rate']
        realtime.declare(self)  # SCHED_FIFO priority, CPU latency limit: run() applies them
        self.check_parameters()
        params, plant, _ = load_segment(segment_params)
        self.plants = [SegmentPlant(params, plant, effects=effects, seed=seed + i)
                       for i in range(n_segments)]
        self.start_strengths = self.plants[0].strengths()  # what nan stands for
        given_strengths = {effect: value for effect, value in self.given_strengths(given).items()
                           if value != self.start_strengths[effect]}
        if given_strengths:
            for segment in self.plants:
                segment.set_strengths(given_strengths)  # from the first step
        self.sim_time = self.get_parameter('use_sim_time').value
        if self.sim_time:
            self.clock_pub = self.create_publisher(self.msg.Clock, '/clock', 10)
            self._clock_every = max(1, round(1.0 / (clock_rate * 1e-3)))
        self._ticks = 0
        try:
            bus = open_can(interface, channel)
        except Exception as exc:  # python-can raises interface-specific errors
            raise BellowsError(
                f'sim_arm_node: cannot open CAN bus {interface}:{channel} ({exc})') from None
        self.sim = SimArmBus(bus, self.step, n_segments=n_segments, vent_pressure=params.p0)
        self.sim.start()
        self.link = f'{interface}:{channel}'
        self.report = diagnostics.LoopReport(self.sim.stats)
        self.diagnostics = diagnostics.Updater(self)
        self.diagnostics.setHardwareID(self.link)  # the CAN interface and channel
        self.diagnostics.add('plant', self.diagnose_plant)
        self.get_logger().info(f'simulated arm ({n_segments} segments) on {self.link}, effects: '
                               f"{', '.join(effects) or 'none'}")

    def on_parameters(self, changed):
        """Take a live load torque (read by `step`, one float) and effect strengths."""
        if 'load_torque' in changed:
            self.load_torque = changed['load_torque']
            self.get_logger().info(f'load torque {self.load_torque:g} N·m from the next step')
        super().on_parameters(changed)

    def effect_plants(self):
        """Return the segment plants: every segment takes the same strengths."""
        return self.plants

    def step(self, dt, setpoints):
        """One step of every segment plant with the valves' set-points (SimArmBus's 1 kHz loop)."""
        measured = []
        for i, plant in enumerate(self.plants):
            sample = plant.step(dt, setpoints[2 * i], setpoints[2 * i + 1],
                                tau_load=self.load_torque)
            measured.append((sample.p1, sample.p2, sample.psi))
        self._ticks += 1
        if self.sim_time and self._ticks % self._clock_every == 0:
            now = Time(seconds=self.plants[0].t).to_msg()
            self.clock_pub.publish(self.msg.Clock(clock=now))
        return measured

    def diagnose_plant(self, stat):
        """Report the simulated arm's 1 kHz bus loop and each segment's angle."""
        values, rate, new_misses = self.report.values()
        values.update(self.sim.health())
        for i, plant in enumerate(self.plants):
            values[f'segment_{i + 1}.psi'] = f'{plant.psi:.4f}'
        # The strengths the plants step with (taken at their last step: 0 = off).
        in_use = self.plants[0].strengths(in_use=True)
        values.update({effect_strengths.parameter_name(effect, key): format(in_use[effect], 'g')
                       for effect, key in STRENGTHS.items()})
        stat.update(values)
        return diagnostics.loop_summary(stat, rate, new_misses)

    def close(self):
        self.sim.close()


def main(args=None):
    return run(SimArmNode, args)


if __name__ == '__main__':
    raise SystemExit(main())
