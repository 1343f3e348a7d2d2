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
The papers' experiments on the simulated devices: excitation programmes and the records they give.

Paper A's quasi-static and dynamic sweeps and its Fig. 10 scenario on the simulated segment, paper
B's chamber and spring programmes and volume test on the simulated actuator. Identification and
the doctor are tested on these records; `python -m bellows_ros.papers.fig10` shows Fig. 10.
"""
__all__ = [
    'segment_experiments',   # paper A: quasi_static_record, dynamic_record, fig10_record
    'actuator_experiments',  # paper B: actuator_record, volume_test_series
    'fig10',                 # paper A's Fig. 10 reproduced, with a plot
]
