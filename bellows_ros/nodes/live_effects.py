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
Live effect strengths of a simulated device node: `effect.<effect>.<key>` parameters.

Both simulated devices offer them the same way: a change is checked against the plant (a value
the plant cannot use is refused with its reason, as `ros2 param set` shows), then handed to
every plant, whose own 1 kHz loop takes it at its next step.
"""
from bellows_ros.errors import ParameterError
from bellows_ros.models import effect_strengths


class LiveEffectStrengths:
    """
    Mixin of a simulated device node whose plants take live effect strengths.

    The node sets `strength_table` (its plant's {effect: strength parameter}, `STRENGTHS`) and
    `start_strengths` (what nan stands for) and says which plants take them (`effect_plants`).
    """

    strength_table: dict

    def effect_plants(self):
        """Return the plants that take new strengths (the first one checks them)."""
        raise NotImplementedError

    def given_strengths(self, values):
        """Return {effect: strength} of `effect.*` parameter values; nan = the start value."""
        return effect_strengths.from_parameters(values, self.strength_table, self.start_strengths)

    def parameter_problem(self, changes):
        """Say why the plants cannot take new strengths ('' when they can), e.g. no YAML."""
        try:
            self.effect_plants()[0].effects_for(self.given_strengths(changes))
        except ParameterError as error:
            return str(error)
        return ''

    def on_parameters(self, changed):
        """Hand new strengths to every plant: its loop takes them at its next step."""
        strengths = self.given_strengths(changed)
        if strengths:
            plants = self.effect_plants()
            for plant in plants:
                plant.set_strengths(strengths)
            on = ', '.join(f'{e} {v:g}' for e, v in plants[0].strengths().items() if v)
            self.get_logger().info(f"effect strengths from the next step: {on or 'none'}")
