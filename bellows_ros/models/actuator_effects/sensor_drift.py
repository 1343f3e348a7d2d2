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
Sensor drift: the pressure sensor's zero moves with its temperature.

A piezoresistive sensor's offset has a temperature coefficient (0.01-0.1 % of full scale per
kelvin in datasheets); while the sensor warms after power-on, or the rig around it warms, its zero
drifts. Within a record the sensor's temperature changes about linearly, so the reading is
p + r t, with t from the record's start. Only the reading changes, not the gas or the force:
the force output is what tells a drifting zero from a leak. Paper B's model assumes an ideal
sensor.
"""
import numpy as np

from bellows_ros.models.actuator_effects.base import (ActuatorEffect, FitVariable, Parameter,
                                                      PlantTerm)

# Pa/s: a 1 MPa sensor at 0.1 % of full scale per kelvin, warming at 1 K/s: no sensor's zero
# moves faster, even at power-on.
MAX_RATE = 1e3


class SensorDrift(ActuatorEffect):
    """A zero of the pressure sensor that moves at a constant rate."""

    name = 'sensor_drift'
    rank = 10
    summary = "the pressure sensor's zero drifting with its temperature: p + r t"
    parameters = {'rate': Parameter(5.0, -MAX_RATE, MAX_RATE, 'Pa/s',
                                    "rate at which the pressure sensor's zero moves")}
    in_service = True   # a sensor warms and ages on the rig
    strength = 'rate'
    # 0.01-0.1 % of a 30-700 kPa sensor's full scale per kelvin, at 0.005-0.05 K/s (a sensor
    # settling after power-on, a rig in the sun): about 0.2 to 30 Pa/s, either sign.
    devices = {'rate': ('log', 0.2, 30.0)}
    deciding_data = 'a long record that returns to the same chamber and spring positions'
    fit = (FitVariable('rate_pa_s', 0.0, -MAX_RATE, MAX_RATE),)
    starts = ([20.0], [-20.0])
    edges = {
        ('rate_pa_s', 'lower'): (
            'bound', "a zero falling faster than 1 kPa/s: faster than any sensor's warm-up"),
        ('rate_pa_s', 'upper'): (
            'bound', "a zero rising faster than 1 kPa/s: faster than any sensor's warm-up"),
    }

    def to_si(self, raw):
        return {'rate': raw['rate_pa_s']}

    def sensor(self, p, dt, values):
        return p + values['rate'] * dt * np.arange(len(p))

    def plant_term(self, values):
        return _Drift(values['rate'])


class _Drift(PlantTerm):
    def __init__(self, rate):
        self.rate = rate

    def start(self, plant, previous=None):
        # The zero moves from where it stands: a new rate goes on from the offset reached.
        self._offset = previous.offset(plant.t) if previous is not None else 0.0
        self._since = plant.t

    def offset(self, t):
        return self._offset + self.rate * (t - self._since)

    def sensor(self, p, dt, t):
        return p + self.offset(t)


EFFECT = SensorDrift()
