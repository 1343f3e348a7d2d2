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
The segment's effect contract (models/segment_effects/base.py), run against every effect.

Each test holds one promise that the plant, the doctor, the ranges or the report rely on when
they iterate over `EFFECTS` without naming an effect.
"""
import dataclasses
from pathlib import Path
import pkgutil

from code_rules import missing_from_section, names_in_conditions
import numpy as np
import pytest

from bellows_ros.config.ranges import RANGES
from bellows_ros.config.segment import effect_range, load_segment, segment_from_flat
from bellows_ros.doctor import checks, segment_causes
from bellows_ros.models import segment_effects
from bellows_ros.models.segment import SegmentParams
from bellows_ros.models.segment_effects import EFFECTS, NAMES
from bellows_ros.models.segment_plant import SegmentPlant, SegmentPlantParams, STRENGTHS
from bellows_ros.papers.segment_experiments import dynamic_record, quasi_static_record

CONFIG = load_segment()
ROOT = Path(__file__).resolve().parents[1]
MODEL_FIELDS = {f.name for f in dataclasses.fields(SegmentParams)}
PLANT_FIELDS = {f.name for f in dataclasses.fields(SegmentPlantParams)}
each = pytest.mark.parametrize('effect', EFFECTS, ids=NAMES)


def test_the_registry_is_every_module_of_the_package():
    modules = {m.name for m in pkgutil.iter_modules(segment_effects.__path__)} - {'base'}
    assert set(NAMES) == modules and len({e.rank for e in EFFECTS}) == len(EFFECTS)


@each
def test_its_parameters_are_fields_and_yaml_parameters_with_a_range(effect):
    assert effect.summary and effect.deciding_data
    for key, parameter in effect.parameters.items():
        assert parameter.field in MODEL_FIELDS | PLANT_FIELDS, key
        assert 'segment.' + parameter.name in RANGES, key
        rule = effect_range(effect.name, key)
        assert rule.low >= (parameter.low if parameter.low is not None else rule.low)
    assert effect.strength is None or effect.strength in effect.parameters
    assert set(effect.off) <= MODEL_FIELDS
    assert (effect.name in STRENGTHS) == bool(effect.strength)


@each
def test_its_fit_starts_inside_its_bounds(effect):
    for name, start, lower, upper in effect.fit:
        assert lower < upper and lower <= start <= upper, name
    assert all(len(start) == len(effect.fit) for start in effect.starts)
    values = effect.to_si({v.name: v.start for v in effect.fit})
    assert all(np.isfinite(list(values.values())))


def _bench(effects, record=quasi_static_record, duration=6.0):
    return record(CONFIG.model, CONFIG.plant, effects, None, seed=7, duration=duration)


@each
def test_the_plant_has_it_and_its_strength_0_is_off(effect):
    with_it = _bench([effect.name], dynamic_record, 3.0)
    without = _bench(None, dynamic_record, 3.0)
    assert any(np.max(np.abs(with_it[name] - without[name])) > 0.0
               for name in ('p1', 'p2', 'tau_ext'))
    if effect.strength:
        plant = SegmentPlant(CONFIG.model, CONFIG.plant, [effect.name], seed=0)
        plant.set_strengths({effect.name: 0.0})
        assert plant.strengths()[effect.name] == 0.0
        plant.step(1e-3, CONFIG.model.p0, CONFIG.model.p0, psi_imposed=0.0)
        assert plant.effects == {}


@pytest.fixture(scope='module')
def record():
    full_physics = [e.name for e in EFFECTS]
    table = checks.as_table(_bench(full_physics), 'segment', 'conformance')
    full = checks.checked_record(table, 'segment', 1)
    segment_causes.add_columns(full, CONFIG.model, CONFIG.identify.input_cutoff)
    return full.decimated(10), full


@each
def test_the_doctors_regression_holds_it_and_the_file_goes_back(effect, record):
    decimated, full = record
    contact = segment_causes.ContactLengths(CONFIG.model, full, 10)
    model = segment_causes.build_model(decimated, CONFIG.model, (effect.name,), contact=contact)
    theta = np.asarray(model.x0, float)
    y, linear = model.predict(theta, np.ones(len(decimated), bool))
    assert len(linear) == model.n_linear and np.all(np.isfinite(y))
    values = model.physical(theta, linear)
    assert sum(len(part) for part in values.values()) == len(linear) + len(
        effect.to_si({v.name: v.start for v in effect.fit}))
    flat = segment_causes.extended_flat(CONFIG, (effect.name,), values)
    segment_from_flat({k[len('segment.'):]: v for k, v in flat.items()}, 'extended.yaml')


@each
def test_the_doctor_says_whether_a_record_can_separate_it(effect, record):
    reasons = checks.identifiability(record[0], CONFIG.model.p0)
    assert set(reasons) == set(NAMES)
    assert reasons[effect.name] is None or reasons[effect.name].strip()


@each
def test_its_docs_section_names_its_parameters_and_fit(effect):
    text = (ROOT / 'docs' / 'effects.md').read_text()
    names = (*effect.parameters, *(v.name for v in effect.fit))
    assert missing_from_section(text, f'## segment: `{effect.name}`', names) == []


ITERATING = ['bellows_ros/models/segment_plant.py', 'bellows_ros/doctor/segment_causes.py',
             'bellows_ros/doctor/checks.py', 'bellows_ros/doctor/report.py',
             'bellows_ros/config/segment.py', 'bellows_ros/config/ranges.py',
             *sorted(str(p.relative_to(ROOT)) for p in (ROOT / 'bellows_ros/bench').glob('*.py'))]


@pytest.mark.parametrize('path', ITERATING)
def test_no_effect_name_decides_a_branch(path):
    assert names_in_conditions((ROOT / path).read_text(), set(NAMES)) == []
