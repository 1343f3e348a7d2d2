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

"""Identification: model parameters from a record (CSV or bag) of a segment or of the actuator."""
__all__ = [
    'segment',             # paper A's driving-torque model, eqs. 30-33; the Fig. 10 calibration
    'actuator',            # paper B's actuator model
    'measured_stiffness',  # the stiffness a record measured, per spring cycle
    'blas',                # one BLAS thread for the fits
]
