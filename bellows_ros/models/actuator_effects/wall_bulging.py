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
Wall bulging: the bellows' walls bulge under pressure, paper B's augmented volume (5, 6).

V = V_geo + E_V(Δh, P). The plant takes the YAML's E_V times `scale`; the doctor fits the terms
of the full cubic that a pressure record can separate: q, d q (both bellows) and d² (both
bellows). Without it the volumes are purely geometric (4), the doctor's baseline.
"""
import dataclasses

from bellows_ros.models.actuator import scaled_bulging, without_bulging
from bellows_ros.models.actuator_effects.base import ActuatorEffect, FitVariable, Parameter

ML = 1e-6   # m³ per mL: volumes are fitted in mL so that all parameters are O(1)
_TERMS = ('e_q', 'e_dq_chamber', 'e_dq_spring', 'e_dd_chamber', 'e_dd_spring')


class WallBulging(ActuatorEffect):
    """The volume error E_V (5, 6) on top of the geometric volume (4)."""

    name = 'wall_bulging'
    rank = 2
    summary = "paper B's augmented volume (5, 6): V = V_geo + E_V(Δh, P)"
    parameters = {'scale': Parameter(1.0, 0.0, 100.0, '1',
                                     'multiplies the E_V coefficients of both bellows')}
    strength = 'scale'
    switched_by_effect = False
    devices = {'scale': ('u', 0.3, 2.0)}
    deciding_data = 'sealed runs at several gas amounts over a wide pressure range'
    fit = tuple(FitVariable(f'{term}_ml', 0.0, -200.0, 200.0) for term in _TERMS)
    edges = {(f'{term}_ml', side): (
        'bound', "a bulge larger than the bellows' own volume over the range of a record")
        for term in _TERMS for side in ('lower', 'upper')}
    standing = True
    baseline_text = ('geometric volume (no E_V)', "the model's own E_V")

    def model_params(self, params, values):
        return without_bulging(params) if values is None else scaled_bulging(params,
                                                                             values['scale'])

    def volumes(self, params, values):
        return bulged(params, values)

    def held_by(self, params):
        return bool(params.chamber.bulging or params.spring.bulging)

    def to_si(self, raw):
        return {name[:-3]: value * ML for name, value in raw.items()}

    def extended(self, model, params, values):
        return bulged(model, values)

    def flat(self, values):
        return {'scale': 1.0}


def bulged(params, e):
    """
    `params` with fitted E_V terms (m³) placed in both bellows' coefficient vectors (5).

    `e`: {'e_q': ..., 'e_dd_spring': ...}, m³.
    """
    chamber = [0.0] * 10
    spring = [0.0] * 10
    chamber[2], chamber[4], chamber[3] = e['e_q'], e['e_dq_chamber'], e['e_dd_chamber']  # (5)
    spring[4], spring[3] = e['e_dq_spring'], e['e_dd_spring']
    return dataclasses.replace(params,
                               chamber=dataclasses.replace(params.chamber, e_v=tuple(chamber)),
                               spring=dataclasses.replace(params.spring, e_v=tuple(spring)))


EFFECT = WallBulging()
