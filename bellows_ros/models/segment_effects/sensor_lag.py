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
Sensor lag: the pressure sensors lag the chambers with a time constant τ.

The plant lags its measured pressures (first order); the doctor feeds the model the pressures
the sensors lag behind, p + τ dp/dt (the inverse of the first-order lag), dp/dt a centred
Savitzky-Golay derivative.
"""
import numpy as np

from bellows_ros.models.segment_effects.base import (FitVariable, pressure_span, SegmentEffect,
                                                     SegmentParameter)

# Samples of the centred Savitzky-Golay derivative dp/dt at the fit rate: 50 ms at 100 Hz. A
# 9-sample (90 ms) window smoothed the bench's fastest pressure steps (~50 ms) so much that
# 0.037 N·m of structure stayed behind (test seed 203: 0.0367 -> 0.0246 N·m with 5 samples).
RATE_WINDOW = 5


class SensorLag(SegmentEffect):
    """First-order lag of the measured chain pressures."""

    name = 'sensor_lag'
    rank = 3
    summary = 'the pressure sensors as first-order lags with time constant τ'
    parameters = {'tau': SegmentParameter('sensor_lag_tau', 'plant.sensor_lag_tau', 0.0)}
    strength = 'tau'
    switched_by_effect = True
    deciding_data = 'pressure steps faster than the lag, sampled at >= 10 x 1/tau'
    fit = (FitVariable('log10_tau', -1.5, -2.5, 0.0),)
    starts = ([-2.3], [-0.8])

    def check(self, values):
        if values.get('tau', 1.0) < 0:
            return "parameter 'tau' must be >= 0"
        return None

    def plant_lag(self, values, plant):
        return values.get('tau', plant.sensor_lag_tau)

    def pressures(self, p1, p2, dt, values):
        from scipy.signal import savgol_filter   # here: the plant imports the effects, not this
        tau = 10.0 ** values['log10_tau']
        return tuple(p + tau * savgol_filter(p, RATE_WINDOW, 2, deriv=1, delta=dt)
                     for p in (p1, p2))

    def to_si(self, raw):
        return {'tau': float(10.0 ** raw['log10_tau'])}

    def label(self, name):
        return self.parameters[name].name if name in self.parameters else name

    def structural_reason(self, record, ambient):
        p1, p2, dt = record['p1'], record['p2'], record.dt
        rate = np.abs(np.gradient(p1, dt)) + np.abs(np.gradient(p2, dt))
        if pressure_span(record) > 5e4 and np.percentile(rate, 99) > 1e5:
            return None
        return 'the pressures never change fast, so a lag of the sensors cannot be seen'


EFFECT = SensorLag()
