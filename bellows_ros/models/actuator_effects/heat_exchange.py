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
Heat exchange: the gas heats on compression and relaxes to ambient through the walls.

Polytropic compression with heat capacity ratio γ (adiabatic over each step, T V^(γ-1) = const),
first-order relaxation to ambient with time constant τ_th:
d ln T/dt = -(γ - 1) d ln V/dt - (ln T - ln T_a)/τ_th (linearised in T/T_a - 1). Paper B assumes
"no energy loss and temperature variation" (isothermal gas): this is what a device adds.
"""
import math

import numpy as np

from bellows_ros.models.actuator import total_volume
from bellows_ros.models.actuator_effects.base import (ActuatorEffect, FitVariable, Parameter,
                                                      PlantTerm)
from bellows_ros.models.filters import relax
from bellows_ros.models.limits import TIME_CONSTANT


class HeatExchange(ActuatorEffect):
    """Polytropic gas relaxing to ambient temperature with time constant τ_th."""

    name = 'heat_exchange'
    rank = 1
    summary = ('polytropic compression (γ) with first-order relaxation of the gas temperature to '
               'ambient (τ_th)')
    parameters = {
        'time_constant': Parameter(1.0, *TIME_CONSTANT, 's', 'wall heat transfer'),
        # 1 (isothermal) to 5/3 (a monatomic gas)
        'gamma': Parameter(1.4, 1.0, 1.67, '1', 'heat capacity ratio of air'),
        't_ambient': Parameter(293.15, 200.0, 400.0, 'K', 'ambient temperature',
                               'was it written in °C?'),
    }
    strength = 'time_constant'
    devices = {'time_constant': ('log', 0.3, 10.0), 'gamma': ('u', 1.3, 1.4)}
    deciding_data = 'fast chamber steps followed by holds of several seconds'
    # τ_th >= 0.1 s: heat through silicone walls into ~0.1 L of air is slow; a faster
    # "relaxation" would only mimic a sensor lag.
    fit = (FitVariable('log10_time_constant', 0.0, -1.0, 2.5),
           FitVariable('gamma', 1.4, 1.0, 1.67))
    starts = ([-0.7, 1.4], [1.3, 1.4])
    edges = {
        ('log10_time_constant', 'lower'): (
            'range', 'set so that heat exchange is not a second sensor lag, not by the walls'),
        ('log10_time_constant', 'upper'): (
            'limit', 'adiabatic gas: no heat crosses the walls within the record'),
        ('gamma', 'lower'): ('absent', 'isothermal gas (gamma 1)'),
        ('gamma', 'upper'): ('bound', 'a monatomic gas (5/3); air is 1.4'),
    }

    def check(self, values):
        if values['time_constant'] <= 0.0:
            return "parameter 'time_constant' must be > 0"
        return None

    def to_si(self, raw):
        return {'time_constant': 10.0 ** raw['log10_time_constant'], 'gamma': raw['gamma']}

    def temperature(self, temperature, volume, dt, values):
        return temperature * np.exp(relax(-(values['gamma'] - 1.0) * np.log(volume), dt,
                                          values['time_constant']))

    def plant_term(self, values):
        return _Heat(values['time_constant'], values['gamma'], values['t_ambient'])


class _Heat(PlantTerm):
    def __init__(self, time_constant, gamma, t_ambient):
        self.time_constant, self.gamma, self.t_ambient = time_constant, gamma, t_ambient
        self._decay = (None, 1.0)

    def start(self, plant, previous=None):
        plant.t_ambient = self.t_ambient
        if previous is None:
            plant.temperature = self.t_ambient
        self._volume = total_volume(plant.params, plant.x_c, plant.x_s, plant.pressure)

    def temperature(self, plant, dt):
        if self._decay[0] != dt:
            self._decay = (dt, math.exp(-dt / self.time_constant))
        # Volume at the new geometry (E_V at the last pressure; the pressure solve after it is
        # exact), needed only for the adiabatic temperature change.
        volume = total_volume(plant.params, plant.x_c, plant.x_s, plant.pressure)
        t = plant.temperature * (self._volume / volume) ** (self.gamma - 1.0)
        plant.temperature = self.t_ambient + (t - self.t_ambient) * self._decay[1]
        self._volume = volume


EFFECT = HeatExchange()
