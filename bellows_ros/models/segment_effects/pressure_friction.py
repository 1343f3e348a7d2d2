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


"""Pressure friction: friction that grows with the bearing load, c_f,p of A(5)."""
import numpy as np

from bellows_ros.models.filters import reversals
from bellows_ros.models.segment import friction_regressor
from bellows_ros.models.segment_effects.base import (pressure_span, SegmentEffect,
                                                     SegmentParameter)


class PressureFriction(SegmentEffect):
    """Adds c_f,p (5) to the constant friction c_f."""

    name = 'pressure_friction'
    rank = 1
    summary = 'adds c_f,p of A(5): friction that grows with the bearing load'
    parameters = {'c_fp': SegmentParameter('friction_c_fp', 'friction.c_fp', 0.0)}
    strength = 'c_fp'
    off = {'friction_c_fp': 0.0}
    paper_a = True
    deciding_data = 'motion in both directions at several held pressures'
    owned = ('friction.c_fp',)
    extra_columns = 1

    def regressors(self, blocks, data, values):
        columns = friction_regressor(data.psi_dot, data.ps1, data.ps2, data.params.friction_c_vel)
        return {**blocks, 'friction': (columns, ['friction.c_f', 'friction.c_fp'])}

    def structural_reason(self, record, ambient):
        psi, dt = record['psi'], record.dt
        moving = float(np.mean(np.abs(np.gradient(psi, dt)) > np.radians(0.5)))
        if pressure_span(record) > 5e4 and moving > 0.02 and reversals(psi, np.radians(1.0)) >= 2:
            return None
        return 'friction needs motion in both directions at several pressures'


EFFECT = PressureFriction()
