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
Buckling: the spring loses force once its load index x_s/x_cr + (P - P_atm)/p_cr passes 1.

`models.actuator.buckling_force`: stiffness loss k_b, critical pressure p_cr, critical
compression x_cr, onset width from the YAML (`actuator.buckling`). The plant takes the YAML's
buckling with its stiffness loss times `scale`; without it the force is paper B's (7)-(12)
alone, the doctor's force baseline. The doctor fits the onset in decades within the physical
bounds of `actuator.buckling.bounds`: from an onset at ambient pressure or at the start of the
travel to one the other variable alone sets.
"""
import dataclasses

import numpy as np

from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator import (Buckling, buckling_force, NO_BUCKLING, scaled_buckling,
                                         without_buckling)
from bellows_ros.models.actuator_effects.base import ActuatorEffect, FitVariable, Parameter

# The fit's variables: (name, the `Buckling` field, its SI factor); all in decades (log10).
_VARIABLES = (('log10_stiffness_loss_kn', 'stiffness_loss', 1e3),
              ('log10_critical_pressure_kpa', 'critical_pressure', 1e3),
              ('log10_critical_compression_mm', 'critical_compression', 1e-3))
# The smallest stiffness loss fitted, N/m (`fit`: 1e-5 kN/m); the YAML's lower bound 0 is no
# buckling, which a fit in decades reaches as this.
K_B_FLOOR = 0.01
ONSET_WIDTH = 0.15   # of the critical load, where the YAML has no actuator.buckling


class SpringBuckling(ActuatorEffect):
    """The spring buckling under pressure and compression."""

    name = 'buckling'
    rank = 5
    summary = ('the spring loses stiffness k_b once x_s/x_cr + (P - P_atm)/p_cr passes 1 '
               '(`actuator.buckling_force`)')
    parameters = {'scale': Parameter(1.0, 0.0, 100.0, '1',
                                     'multiplies actuator.buckling.stiffness_loss')}
    in_service = True
    strength = 'scale'
    # The physical ranges: the bounds of config/actuator.yaml actuator.buckling.bounds
    # (docs/effects.md; bench/devices.py caps k_b where a spring would lose more than it carries).
    devices = {'stiffness_loss': ('log', 300.0, 17000.0),
               'critical_compression': ('log', 1e-4, 1.0),
               'critical_pressure': ('log', 1e2, 1.1e6)}
    deciding_data = 'the spring cycled past the fitted onset at several pressures (gas amounts)'
    # The fallbacks of `actuator.buckling.bounds` (`fit_variables`), the same physical ranges
    # (docs/doctor.md, "Where every range comes from"). The onset spans four decades, from one at
    # ambient pressure (p_cr 0.1 kPa) or at the start of the travel (x_cr 0.1 mm) to one the
    # other variable alone sets. k_b too: at such an onset the loss in the pressure, k_b x_cr /
    # p_cr per Pa, is newtons per kPa with k_b of a few N/m, where a spring that carries tens of
    # newtons ends.
    fit = (FitVariable('log10_stiffness_loss_kn', 0.3, -5.0, 1.23),
           FitVariable('log10_critical_pressure_kpa', 1.4, -1.0, 3.04),
           FitVariable('log10_critical_compression_mm', 1.3, -1.0, 3.0))
    edges = {
        ('log10_stiffness_loss_kn', 'lower'): (
            'absent', 'no buckling: a stiffness loss of 0.01 N/m, 0.4 mN over the whole travel'),
        ('log10_stiffness_loss_kn', 'upper'): (
            'bound', "the axial stiffness of the spring's straight wall tube: no loss is larger"),
        ('log10_critical_pressure_kpa', 'lower'): (
            'limit', 'the onset lies at ambient pressure: the spring buckles as soon as the gas '
                     'is above ambient, compressed or not (buckling from the start of the record '
                     'wherever it is above ambient)'),
        ('log10_critical_pressure_kpa', 'upper'): (
            'limit', 'the pressure does not move the onset: the compression alone sets it'),
        ('log10_critical_compression_mm', 'lower'): (
            'limit', 'the onset lies at the start of the travel: the spring is buckled from the '
                     'start of the record wherever it is compressed'),
        ('log10_critical_compression_mm', 'upper'): (
            'limit', 'the compression does not move the onset: the pressure alone sets it'),
    }
    judged_by = 'onset'
    standing = True
    baseline_text = ('no buckling', "the model's own buckling")

    def model_params(self, params, values):
        if values is None:
            return without_buckling(params)
        if params.buckling is None:
            raise ParameterError("effect 'buckling': the parameters have no actuator.buckling "
                                 'section')
        return scaled_buckling(params, values['scale'])

    def held_by(self, params):
        return params.buckling is not NO_BUCKLING and params.buckling.stiffness_loss > 0.0

    def fit_variables(self, params):
        """`fit` with the bounds of `actuator.buckling.bounds` where the YAML has them."""
        bounds = (dict(params.buckling.bounds)
                  if params is not None and params.buckling is not None else {})
        variables = []
        for (name, start, low, high), (_, si, factor) in zip(self.fit, _VARIABLES):
            if si in bounds:
                floor = K_B_FLOOR if si == 'stiffness_loss' else 1e-12
                low, high = (float(np.log10(max(v, floor) / factor)) for v in bounds[si])
            variables.append(FitVariable(name, min(max(start, low), high), low, high))
        return variables

    def own_start(self, params):
        """Return the model's own buckling as the fit's variables {name: value}."""
        b = params.buckling
        return self.from_si({si: max(getattr(b, si), K_B_FLOOR if i == 0 else 0.0)
                             for i, (_, si, _) in enumerate(_VARIABLES)})

    def to_si(self, raw):
        return {si: 10.0 ** raw[name] * factor for name, si, factor in _VARIABLES}

    def from_si(self, si):
        return {name: float(np.log10(si[key] / factor)) for name, key, factor in _VARIABLES}

    def force(self, known, params, x_s, p_gas, values):
        b = params.buckling if values is None else self.of(params, values)
        return known + buckling_force(b, x_s, p_gas, np.exp)[0]

    def of(self, params, values):
        """Return the `Buckling` of fitted `values` (SI), with the onset width of `params`."""
        width = params.buckling.onset_width if params.buckling is not None else ONSET_WIDTH
        return Buckling(values['stiffness_loss'], values['critical_pressure'],
                        values['critical_compression'], width)

    def extended(self, model, params, values):
        if params.buckling is None:
            return model
        return dataclasses.replace(model, buckling=dataclasses.replace(
            params.buckling, **{si: values[si] for _, si, _ in _VARIABLES}))

    def flat(self, values):
        return {'scale': 1.0}

    def device(self, params, drawn):
        """Put a drawn device's onset into `params.buckling`; the plant's effect is its scale."""
        shape = {si: drawn[si] for _, si, _ in _VARIABLES}
        params = dataclasses.replace(params, buckling=dataclasses.replace(
            params.buckling, bounds=(), **shape))
        return params, {'scale': 1.0}


EFFECT = SpringBuckling()
