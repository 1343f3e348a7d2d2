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
Backlash: a dead band of width b between the lead-screw nut (what the encoder sees) and the plate.

A play operator: the plate moves only when the nut pushes it. In a record whose chamber never
reverses a play is a constant offset, which the baseline's encoder zero already is.
"""
from bellows_ros.models.actuator_effects.base import (ActuatorEffect, FitVariable, Parameter,
                                                      PlantTerm)
from bellows_ros.models.filters import play, reversals

# m: the smallest reversal of the chamber that shows a play (`structural_reason`)
REVERSAL = 1e-4


class Backlash(ActuatorEffect):
    """A dead band between the nut and the plate."""

    name = 'backlash'
    rank = 4
    summary = 'a dead band of width b between the lead screw (the encoder) and the chamber plate'
    parameters = {'width': Parameter(0.0003, 0.0, 0.01, 'm', 'lead-screw dead band')}
    strength = 'width'
    devices = {'width': ('log', 1e-4, 1e-3)}
    deciding_data = 'the chamber reversing often by more than the play'
    fit = (FitVariable('width_mm', 0.3, 0.0, 3.0),)
    starts = ([1.0], [0.05])
    edges = {
        ('width_mm', 'lower'): ('absent', 'no play'),
        ('width_mm', 'upper'): (
            'bound', 'a play of more than two turns of the lead screw (1.27 mm lead)'),
    }
    judged_by = 'structure'

    def structural_reason(self, record):
        if reversals(record['x_c'], REVERSAL) >= 1:
            return None
        return ('the air-chamber compression never reverses by 0.1 mm; backlash shows only at '
                'reversals')

    def to_si(self, raw):
        return {'width': raw['width_mm'] * 1e-3}

    def plate(self, x_c, values):
        return play(x_c, values['width'])

    def plant_term(self, values):
        return _Play(0.5 * values['width'])


class _Play(PlantTerm):
    def __init__(self, half):
        self.half = half

    def plate(self, nut, x_c):
        if nut - x_c > self.half:
            return nut - self.half
        if x_c - nut > self.half:
            return nut + self.half
        return x_c


EFFECT = Backlash()
