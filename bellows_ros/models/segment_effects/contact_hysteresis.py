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
Contact hysteresis: the actuator torque is paper A's membrane-contact torque A(29).

With the no-slip strain memory of Algorithm 1 instead of the previous model's pressure
polynomial A(34): the torque on the way back differs from the way out. No parameters: it is a
choice of torque model, so it has no live strength.
"""
import numpy as np

from bellows_ros.models.filters import reversals
from bellows_ros.models.segment import actuator_regressor
from bellows_ros.models.segment_effects.base import SegmentEffect


class ContactHysteresis(SegmentEffect):
    """Membrane-contact torque A(29) with Algorithm 1's strain memory."""

    name = 'contact_hysteresis'
    rank = 0
    summary = "A(34)'s pressure polynomial -> membrane-contact torque A(29), Algorithm 1's memory"
    paper_a = True
    torque = 'tau_drive'
    deciding_data = 'several angle reversals with a chain held pressurised'
    owned = ('actuator.',)
    extra_columns = 4     # θ_a's 8 coefficients for the polynomial's 4

    def regressors(self, blocks, data, values):
        sa1, sa2 = data.contact()
        columns = actuator_regressor(data.psi, data.ps1, data.ps2, sa1, sa2)
        return {**blocks, 'pressure': (columns, [f'actuator.theta[{k}]' for k in range(8)])}

    def structural_reason(self, record, ambient):
        p1, p2 = record['p1'], record['p2']
        turns = reversals(record['psi'], np.radians(1.0))
        if turns >= 2 and max(p1.max(), p2.max()) > ambient + 2e4:
            return None
        return (f'the angle reverses only {turns} time(s) or no chain is pressurised; the '
                'contact memory shows only on a return path')


EFFECT = ContactHysteresis()
