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

"""Contact hysteresis (models/segment_effects/contact_hysteresis.py): paper A's Fig. 10 loop."""
import pytest

from bellows_ros.config.segment import load_segment_params, load_segment_plant_params
from bellows_ros.models.segment_plant import FULL_MODEL, NO_NOISE
from bellows_ros.papers.segment_experiments import fig10_record

PLANT = load_segment_plant_params()


@pytest.fixture(scope='module')
def params():
    return load_segment_params()


def test_fig10_record_shows_the_hysteresis_only_with_contact_hysteresis(params):
    record, before, after = fig10_record(params, PLANT, FULL_MODEL, NO_NOISE)
    assert record['psi'][before] == pytest.approx(record['psi'][after], abs=1e-12)
    assert -record['tau_ext'][after] > 1.1 * -record['tau_ext'][before]
    baseline, before, after = fig10_record(params, PLANT, {}, NO_NOISE)
    assert baseline['tau_ext'][after] == pytest.approx(baseline['tau_ext'][before], abs=1e-9)
