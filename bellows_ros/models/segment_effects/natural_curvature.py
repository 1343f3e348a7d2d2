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
Natural curvature: a pressure-dependent rest angle Ψ_j0(p) of A(4) and the stiffness k_s,p of A(3).

Ψ_j0(p) = σ_j c_Ψ0,p tanh(c_Ψ0 p_scl,j): c_Ψ0 and c_Ψ0,p are fitted (nonlinear), k_s and k_s,p
by least squares. c_Ψ0,p ≥ 0: the sign of the natural curvature is set by the mirrored chains.
"""
from bellows_ros.models.segment import restoring_regressor
from bellows_ros.models.segment_effects.base import (FitVariable, pressure_span, SegmentEffect,
                                                     SegmentParameter)


class NaturalCurvature(SegmentEffect):
    """Ψ_j0(p) (4) and k_s,p (3)."""

    name = 'natural_curvature'
    rank = 2
    summary = 'a pressure-dependent rest angle Ψ_j0(p) A(4) and the stiffness k_s,p A(3)'
    parameters = {'c_psi0': SegmentParameter('restoring_c_psi0', 'restoring.c_psi0'),
                  'c_psi0_p': SegmentParameter('restoring_c_psi0_p', 'restoring.c_psi0_p'),
                  'k_sp': SegmentParameter('restoring_k_sp', 'restoring.k_sp')}
    strength = 'c_psi0_p'
    off = {'restoring_c_psi0_p': 0.0, 'restoring_k_sp': 0.0}
    paper_a = True
    deciding_data = 'the chain pressures stepped over many levels, 0 to > 1 bar gauge'
    fit = (FitVariable('c_psi0', 3.0, 0.1, 30.0), FitVariable('c_psi0_p', 0.3, 0.0, 1.5))
    starts = ([1.0, 0.1], [10.0, 0.6], [20.0, 0.8])
    owned = ('restoring.k_sp',)
    extra_columns = 1

    def regressors(self, blocks, data, values):
        columns = restoring_regressor(data.psi, data.ps1, data.ps2, values['c_psi0'],
                                      values['c_psi0_p'])
        return {**blocks, 'restoring': (columns, ['restoring.k_s', 'restoring.k_sp'])}

    def to_si(self, raw):
        return {'restoring.c_psi0': float(raw['c_psi0']),
                'restoring.c_psi0_p': float(raw['c_psi0_p'])}

    def structural_reason(self, record, ambient):
        spread = pressure_span(record)
        if spread > 5e4:
            return None
        return (f'the chain pressures span only {spread:.0f} Pa; a pressure-dependent rest angle '
                'needs a wider range')


EFFECT = NaturalCurvature()
