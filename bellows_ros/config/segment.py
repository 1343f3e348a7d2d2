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
Segment parameters: config/segment.yaml (and a user's file over it) -> one object per layer.

The one file keeps its layout; its `segment.` section splits into the driving-torque model's
`SegmentParams` (everything but the two groups below), the simulated segment's
`SegmentPlantParams` (`segment.plant.*`) and identification's `SegmentIdentifyParams`
(`segment.identify.*`). Each is checked as it is built; a name none of them has is an error.
"""
from dataclasses import dataclass, fields
from typing import NamedTuple

from bellows_ros.config import ranges
from bellows_ros.errors import ParameterError
from bellows_ros.io import params as param_files
from bellows_ros.models.segment import check_params, SegmentParams, UNDOTTED
from bellows_ros.models.segment_effects import BY_NAME
from bellows_ros.models.segment_plant import (check_plant_params, PLANT_DOTTED,
                                              SegmentPlantParams)


@dataclass(frozen=True)
class SegmentIdentifyParams:
    """`segment.identify.*`: input_cutoff, Hz, zero-phase low-pass of the inputs (0 = off)."""

    input_cutoff: float

    def flat(self):
        """Return flat ROS 2 names (`segment.identify.input_cutoff`) -> values."""
        return {f'segment.identify.{f.name}': getattr(self, f.name) for f in fields(self)}


class SegmentConfig(NamedTuple):
    """The three parameter objects of one segment file."""

    model: SegmentParams
    plant: SegmentPlantParams
    identify: SegmentIdentifyParams

    def flat(self):
        """All of them as flat ROS 2 names, for `params.write_file` (a complete segment file)."""
        return {**self.model.flat(), **self.plant.flat(), **self.identify.flat()}


def effect_range(effect, key):
    """
    `Range` of the segment's `--effect effect:key=...`, or None for a parameter with none.

    Each effect parameter is the YAML parameter it sets, so it has that one's range
    (config/ranges.py), from its effect's lowest value where it has one (a strength is never
    negative: 0 = off).
    """
    parameter = BY_NAME[effect].parameters.get(key) if effect in BY_NAME else None
    if parameter is None:
        return None
    rule = ranges.RANGES['segment.' + parameter.name]
    return rule if parameter.low is None else rule._replace(low=max(rule.low, parameter.low))


def load_segment(params_path=None):
    """
    `config/segment.yaml` with `params_path` (if any) laid over it -> `SegmentConfig`.

    Unknown or missing names raise ParameterError; so do physically inadmissible values (μ_k ≤ 0,
    γ_k ≤ 2, p_max ≤ p0, non-positive geometry, a negative noise or lag).
    """
    flat = param_files.section(ranges.load('segment', params_path), 'segment')
    source = params_path or param_files.default_file('segment')
    return segment_from_flat(flat, source)


def segment_from_flat(flat, source='parameters'):
    """Build `SegmentConfig` from the names below `segment.` (`ogden.mu`, `plant.noise.p`, ...)."""
    plant_names = {dotted: name for name, dotted in PLANT_DOTTED.items()}
    model, plant, identify = {}, {}, {}
    for name, value in flat.items():
        group, _, rest = name.partition('.')
        if group == 'plant' and rest in plant_names:
            plant[plant_names[rest]] = value
        elif group == 'identify' and rest in {f.name for f in fields(SegmentIdentifyParams)}:
            identify[rest] = value
        elif name in UNDOTTED:
            model[UNDOTTED[name]] = value
        else:
            raise ParameterError(f"{source}: unknown parameter 'segment.{name}'")
    result = SegmentConfig(
        param_files.build(SegmentParams, model, source),
        param_files.build(SegmentPlantParams, plant, f'{source}: segment.plant'),
        param_files.build(SegmentIdentifyParams, identify, f'{source}: segment.identify'))
    check_params(result.model, source)
    check_plant_params(result.plant, source)
    if result.identify.input_cutoff < 0:
        raise ParameterError(f"{source}: parameter 'segment.identify.input_cutoff' must be >= 0")
    return result


def load_segment_params(params_path=None):
    """Return the driving-torque model's `SegmentParams` of `load_segment(params_path)`."""
    return load_segment(params_path).model


def load_segment_plant_params(params_path=None):
    """Return the simulated segment's `SegmentPlantParams` of `load_segment(params_path)`."""
    return load_segment(params_path).plant


def load_segment_identify_params(params_path=None):
    """Return identification's `SegmentIdentifyParams` of `load_segment(params_path)`."""
    return load_segment(params_path).identify
