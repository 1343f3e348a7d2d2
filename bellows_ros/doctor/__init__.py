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
The model doctor: what the simulation gets wrong on measured data, its physical cause, the gain.

`diagnosis.diagnose` is the entry point (docs/doctor.md); the causes of each device are the
effects of `models.segment_effects` and `models.actuator_effects` (docs/effects.md), built into
models by `segment_causes` and `actuator_causes`; `live` runs the doctor beside the nodes.
`checks` and `scoring` are its internals.
"""
__all__ = [
    'diagnosis',        # the decision procedure: diagnose(system, table, config)
    'segment_causes',   # the segment's baseline and candidate causes
    'actuator_causes',  # the actuator's baseline and candidate causes
    'report',           # the report as data: report.json, details.json, report.md
    'plots',            # before/after plots of a diagnosis
    'live',             # the doctor live: model against measurement, rolling, for the nodes
]
