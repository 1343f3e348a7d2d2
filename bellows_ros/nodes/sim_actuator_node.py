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
sim_actuator_node: the simulated actuator board behind a pseudo-terminal.

Runs paper B's actuator plant (`models.actuator_plant.ActuatorPlant`) inside the simulated board
(`hardware.sim_actuator_board`), which speaks the board's serial protocol on a pty whose symlink is
`port`. The driver opens that path exactly as it opens the real board's /dev/serial/by-id link.

Node parameters:
  port (str): the symlink to create (the driver's actuator.port).
  actuator_params (str): YAML laid over config/actuator.yaml ('' = defaults); also holds the
      effects' parameters (actuator.effects.*).
  hardware_params (str): YAML laid over config/hardware.yaml (the drive train: motor, gearbox,
      lead screw, encoder; the board's end-stop margin).
  effects (string array): plant effects to switch on (air_leak, heat_exchange, wall_bulging,
      sensor_lag, backlash, buckling); [''] = none.
  effect.<effect>.<parameter> (live): the strength of each effect (`STRENGTHS`: air_leak
      conductance m³/(s·Pa), heat_exchange time_constant s, wall_bulging scale, sensor_lag
      time_constant s, backlash width m, buckling scale), 0 = off, nan = as `effects` and
      actuator_params say; a change (`ros2 param set`) takes effect at the next plant step, and
      can switch an effect on or off while the plant runs (a leak appears mid-run).
  seed (int): sensor noise seed.
  x_c0 (m): initial chamber compression (design point when NaN).
  spring.amplitude (m), spring.period (s): the spring is moved sinusoidally between 0 and
      `amplitude` (a test machine); 0 = spring free at x_s = 0.
  clock_rate (Hz): /clock publication rate when use_sim_time is on.
  realtime_priority (int): SCHED_FIFO priority for the node's threads, 1-99; 0 = normal
      scheduling (runtime/realtime.py).
  cpu_latency_limit (s): CPU wake-up latency held while the node runs, 0 = idle CPUs poll;
      negative = off (runtime/realtime.py).
With use_sim_time the node is the clock source: it publishes the plant's time on /clock.
"""
import math

from rclpy.time import Time

from bellows_ros.config.actuator import effect_range, load_actuator
from bellows_ros.config.hardware import actuator_board_config
from bellows_ros.hardware.sim_actuator_board import SimActuatorBoard
from bellows_ros.models import effect_strengths
from bellows_ros.models.actuator_plant import (ACTUATOR_EFFECTS, ActuatorPlant, effect_parameters,
                                               STRENGTHS, strengths_of, with_strengths)
from bellows_ros.nodes import diagnostics
from bellows_ros.nodes.live_effects import LiveEffectStrengths
from bellows_ros.runtime import Node, realtime, run
from bellows_ros.runtime.parameters import Spec


def _strength_spec(effect, key):
    # The physical range of the YAML's value, as the CLI's --effect takes it (the effect's own),
    # and 0 = off.
    rule = effect_range(effect, key)
    return Spec(effect_strengths.parameter_name(effect, key), math.nan,
                f'strength of the {effect} effect ({key}, {rule.unit}); 0 = off, nan = as effects '
                'and actuator_params say', low=min(0.0, rule.low), high=rule.high,
                read_only=False)


PARAMETERS = (
    Spec('port', '/tmp/bellows_actuator', "the pty symlink to create (the driver's "
         'actuator.port)', check=lambda port: '' if port else 'must not be empty'),
    Spec('actuator_params', '', "YAML laid over config/actuator.yaml ('' = defaults)"),
    Spec('hardware_params', '', "YAML laid over config/hardware.yaml ('' = defaults)"),
    Spec('effects', [''], "physical effects of the plant ([''] = the baseline plant)",
         choices=('', *ACTUATOR_EFFECTS), unique=True),
    Spec('seed', 1, 'seed of the sensor noise', low=0, high=2 ** 32 - 1),
    Spec('x_c0', math.nan, "initial air-chamber compression, m (nan = the model's reference)",
         low=-0.1, high=0.1),
    Spec('spring.amplitude', 0.0, 'amplitude of the imposed spring motion, m', low=0.0,
         high=0.05),
    Spec('spring.period', 4.0, 'period of the imposed spring motion, s', low=0.01, high=3600.0),
    Spec('clock_rate', 100.0, '/clock messages per second when use_sim_time is on', low=1.0,
         high=1000.0),
    # One live strength per effect (`actuator_plant.STRENGTHS`): `ros2 param set` switches it.
    *(_strength_spec(effect, key) for effect, key in STRENGTHS.items()),
)


class SimActuatorNode(LiveEffectStrengths, Node):
    strength_table = STRENGTHS

    def __init__(self, **kwargs):
        super().__init__('sim_actuator_node', **kwargs)
        given = self.declare_specs(PARAMETERS)
        port, actuator_params = given['port'], given['actuator_params'] or None
        hardware_params = given['hardware_params'] or None
        effects, seed = [e for e in given['effects'] if e], given['seed']
        x_c0, clock_rate = given['x_c0'], given['clock_rate']
        self.amplitude, self.spring_period = given['spring.amplitude'], given['spring.period']
        realtime.declare(self)  # SCHED_FIFO priority, CPU latency limit: run() applies them
        self.check_parameters()
        params, plant = load_actuator(actuator_params, hardware_params)
        chosen = effect_parameters(plant, effects)
        self.start_strengths = strengths_of(chosen)  # what nan stands for
        chosen = with_strengths(chosen, self.given_strengths(given))
        effects = list(chosen)
        self.plant = ActuatorPlant(params, plant, effects=chosen, seed=seed,
                                   x_c0=None if math.isnan(x_c0) else x_c0)
        self.sim_time = self.get_parameter('use_sim_time').value
        if self.sim_time:
            self.clock_pub = self.create_publisher(self.msg.Clock, '/clock', 10)
            self._clock_every = max(1, round(1.0 / (clock_rate * 1e-3)))
        self._ticks = 0
        self.end_stop_hits = 0
        self.x_c_seen = [math.inf, -math.inf]
        config = actuator_board_config(hardware_params, actuator_params)
        self.board = SimActuatorBoard(self.step, config=config, link_path=port)
        self.board.start()
        self.report = diagnostics.LoopReport(self.board.stats)
        self.diagnostics = diagnostics.Updater(self)
        self.diagnostics.setHardwareID(self.board.port)  # the board's serial port
        self.diagnostics.add('plant', self.diagnose_plant)
        self.get_logger().info(f'simulated actuator board on {self.board.port}, effects: '
                               f"{', '.join(effects) or 'none'}")

    def effect_plants(self):
        """Return the plant that takes live effect strengths."""
        return [self.plant]

    def step(self, dt, duty):
        """Step the plant once (called by the board's 1 kHz loop)."""
        x_s = None
        if self.amplitude > 0:
            phase = 2 * math.pi * self.plant.t / self.spring_period
            x_s = 0.5 * self.amplitude * (1 - math.cos(phase))
        sample = self.plant.step(dt, duty, x_s_imposed=x_s)
        self.end_stop_hits += sample.at_lower_stop or sample.at_upper_stop
        self.x_c_seen = [min(self.x_c_seen[0], sample.x_c), max(self.x_c_seen[1], sample.x_c)]
        self._ticks += 1
        if self.sim_time and self._ticks % self._clock_every == 0:
            now = Time(seconds=self.plant.t).to_msg()
            self.clock_pub.publish(self.msg.Clock(clock=now))
        return sample

    def diagnose_plant(self, stat):
        """Report the simulated board's 1 kHz loop and the plant's state."""
        values, rate, new_misses = self.report.values()
        values.update(self.board.health())
        values.update(x_c=f'{self.plant.x_nut:.6f}', gas_p_ref=f'{self.plant.gas:.1f}',
                      pressure=f'{self.plant.pressure:.1f}', duty=f'{self.board.duty:.3f}',
                      x_c_min_seen=f'{self.x_c_seen[0]:.6f}',
                      x_c_max_seen=f'{self.x_c_seen[1]:.6f}',
                      end_stop_hits=str(self.end_stop_hits), t_plant=f'{self.plant.t:.3f}')
        # The effect strengths the plant steps with (taken at its last step: 0 = off).
        effects = self.plant.effects
        values.update({effect_strengths.parameter_name(effect, key):
                       format(effects.get(effect, {}).get(key, 0.0), 'g')
                       for effect, key in STRENGTHS.items()})
        stat.update(values)
        return diagnostics.loop_summary(stat, rate, new_misses)

    def close(self):
        self.board.close()


def main(args=None):
    return run(SimActuatorNode, args)


if __name__ == '__main__':
    raise SystemExit(main())
