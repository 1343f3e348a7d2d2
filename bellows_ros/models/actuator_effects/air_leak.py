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
Air leak: the sealed gas escapes through a restriction to ambient.

Laminar flow, volume flow C (P - P_atm) at the chamber pressure, so the gas amount N = P V
(at ambient temperature) follows dN/dt = -C P (P - P_atm) T_amb/T.
"""
from bellows_ros.models.actuator_effects.base import (ActuatorEffect, FitVariable, Parameter,
                                                      PlantTerm)
from bellows_ros.models.actuator_geometry import P_ATM
from bellows_ros.models.filters import recurrence


class AirLeak(ActuatorEffect):
    """Volume flow C (P - P_atm) out of the sealed gas."""

    name = 'air_leak'
    rank = 0
    summary = 'volume flow C (P - P_atm) out of the sealed gas: dN/dt = -C P (P - P_atm)'
    parameters = {
        # up to a wide-open 4 mm orifice: ~1e-6 m³/s per Pa near ambient
        'conductance': Parameter(1e-11, 0.0, 1e-6, 'm³/(s·Pa)',
                                 'leak volume flow per pressure difference'),
    }
    in_service = True
    strength = 'conductance'
    devices = {'conductance': ('log', 1e-12, 3e-11)}
    deciding_data = 'long holds (tens of s) with the pressure well away from ambient'
    fit = (FitVariable('log10_conductance', -11.0, -15.0, -7.0),)
    starts = ([-9.5], [-12.5])
    edges = {
        ('log10_conductance', 'lower'): (
            'absent', 'no leak: the gas would take > 10^5 s to escape a 0.1 L chamber'),
        ('log10_conductance', 'upper'): (
            'limit', 'the chamber is vented: its gas reaches ambient within ~10 ms, a fit sample'),
    }

    def to_si(self, raw):
        return {'conductance': 10.0 ** raw['log10_conductance']}

    def amount(self, amount, temperature, volume, dt, values, n0):
        # N_{k+1} = N_k - dt C P_k (N_k T_k / V_k - P_atm), with N relative to N_0; the flow's
        # pressure factor P_k is taken from the sealed gas (second order in the leak).
        flow = dt * values['conductance'] * n0 * temperature / volume
        return amount * recurrence(1.0 - flow * temperature / volume, flow * P_ATM / n0, 1.0)

    def plant_term(self, values):
        return _Leak(values['conductance'])


class _Leak(PlantTerm):
    def __init__(self, conductance):
        self.conductance = conductance

    def gas(self, plant, dt):
        p = plant.pressure
        plant.gas_amount -= (dt * p * self.conductance * (p - P_ATM) * plant.t_ambient
                             / plant.temperature)


EFFECT = AirLeak()
