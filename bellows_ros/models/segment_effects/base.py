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
What an effect of paper A's segment is: the contract every effect module implements.

The doctor's segment baseline is paper A's previous model A(34) with constant friction and no
natural curvature; the plant without effects is that baseline. An effect switches on one piece of
the missing physics, in the plant (its parameters set in `SegmentParams`, or the plant's own
lag) and in the doctor's linear regression (the pressures it is fed, the regressor blocks it
swaps or extends, the nonlinear variables it fits). The registry
(`segment_effects.EFFECTS`) is every module of this package; no other module names an effect.

The doctor's regression has three blocks, {'pressure', 'restoring', 'friction'}: each a
(columns, labels) pair, labels the YAML names below `segment.` of the coefficients. The baseline's
are A(34)'s pressure polynomial, k_s and c_f; each effect in `rank` order may replace its block.
"""
import abc
from typing import NamedTuple

import numpy as np

from bellows_ros.models.actuator_effects.base import FitVariable

__all__ = ['FitVariable', 'SegmentEffect', 'SegmentParameter', 'pressure_span']


def pressure_span(record):
    """Return the larger of the two chains' pressure spans over `record`, Pa."""
    return max(float(np.ptp(record['p1'])), float(np.ptp(record['p2'])))


class SegmentParameter(NamedTuple):
    """An `--effect` parameter: the field it sets and its YAML name below `segment.`."""

    field: str           # of SegmentParams (or of SegmentPlantParams, `plant.*` names)
    name: str            # YAML name below `segment.`, whose range config/ranges.py holds
    low: float = None    # lowest value an `--effect` or a live strength takes; None: the YAML's

    @property
    def in_plant(self):
        """Whether it sets the simulated plant's own parameter, not the model's physics."""
        return self.name.startswith('plant.')


class SegmentEffect(abc.ABC):
    """One piece of paper A's physics beyond the baseline: plant, regression, fit, docs."""

    name = ''
    rank = 0
    summary = ''           # one line of physics
    parameters = {}        # {--effect parameter: SegmentParameter}
    strength = None        # the parameter that is its live strength (0 = off); None: a choice
    off = {}               # {SegmentParams field: value} of the physics without it
    paper_a = False        # part of paper A's full physics (`FULL_MODEL`)
    torque = None          # the model output that is the driving torque with it ('tau_drive')
    switched_by_effect = False  # the plant needs `--effect NAME` to have the fitted physics
    deciding_data = ''
    fit = ()               # FitVariables of the nonlinear fit
    starts = ()            # other starts when it is the cause added last
    owned = ()             # prefixes of the regression's labels it owns in the report
    extra_columns = 0      # linear columns it adds to the baseline's regression

    # --- the plant ------------------------------------------------------------------------

    def check(self, values):
        """Return an error message for `--effect` values {parameter: float} together, or None."""
        return None

    def plant_lag(self, values, plant):
        """Return the lag (s) of the measured pressures it puts in the plant, 0 for none."""
        return 0.0

    # --- the doctor -----------------------------------------------------------------------

    def pressures(self, p1, p2, dt, values):
        """Return what the model is fed for the measured p1, p2 (Pa) sampled every dt s."""
        return p1, p2

    def regressors(self, blocks, data, values):
        """Return `blocks` with this effect's; `data`: psi, psi_dot, ps1, ps2, params, contact."""
        return blocks

    def to_si(self, raw):
        """Fit variables {name: value} -> the report's parameters {label: SI value}."""
        return {}

    def label(self, name):
        """Return the YAML name below `segment.` of a report label of this effect."""
        return name

    def structural_reason(self, record, ambient):
        """Why `record` cannot separate the effect (or None): gauge pressures from `ambient`."""
        return None
