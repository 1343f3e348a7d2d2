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
Sensor lag: the pressure sensor reads through a first-order lag with time constant τ.

A sensor behind a tube, or a filtered one: only the pressure reading changes, not the gas or
the force.
"""
import math

from bellows_ros.models.actuator_effects.base import (ActuatorEffect, FitVariable, Parameter,
                                                      PlantTerm)
from bellows_ros.models.filters import lag
from bellows_ros.models.limits import TIME_CONSTANT


class SensorLag(ActuatorEffect):
    """First-order lag of the pressure sensor."""

    name = 'sensor_lag'
    rank = 3
    summary = 'the pressure sensor as a first-order lag with time constant τ'
    parameters = {'time_constant': Parameter(0.05, 0.0, TIME_CONSTANT[1], 's',
                                             'pressure sensor first-order lag')}
    in_service = True
    strength = 'time_constant'
    devices = {'time_constant': ('log', 0.005, 0.15)}
    deciding_data = 'fast chamber steps sampled at >= 10 x 1/tau'
    fit = (FitVariable('log10_time_constant', -1.5, -3.5, 0.5),)
    starts = ([-2.5], [-0.5])
    edges = {
        ('log10_time_constant', 'lower'): (
            'absent', 'no lag: 0.3 ms is below the fastest sample (1 ms)'),
        ('log10_time_constant', 'upper'): (
            'bound', 'a 3 s pressure reading: slower than any sensor behind a tube of a rig'),
    }

    def to_si(self, raw):
        return {'time_constant': 10.0 ** raw['log10_time_constant']}

    def sensor(self, p, dt, values):
        return lag(p, dt, values['time_constant'])

    def plant_term(self, values):
        return _Lag(values['time_constant'])


class _Lag(PlantTerm):
    def __init__(self, time_constant):
        self.time_constant = time_constant
        self._gain = (None, 1.0)

    def start(self, plant, previous=None):
        # A change of strength keeps the reading where it is; a new lag starts at the pressure.
        self._reading = previous._reading if previous is not None else plant.pressure

    def sensor(self, p, dt, t):
        if self._gain[0] != dt:
            self._gain = (dt, 1.0 - math.exp(-dt / self.time_constant)
                          if self.time_constant > 0.0 else 1.0)
        self._reading += (p - self._reading) * self._gain[1]
        return self._reading


EFFECT = SensorLag()
