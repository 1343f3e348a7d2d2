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
The effect contract (models/actuator_effects/base.py), run against every effect of the registry.

Each test holds one promise that the plant, the doctor, the ranges or the benches rely on when
they iterate over `EFFECTS` without naming an effect. A new effect module is held to all of them
by being there.
"""
import math
from pathlib import Path
import pkgutil

from code_rules import missing_from_section, names_in_conditions
import numpy as np
import pytest

from bellows_ros.config.actuator import load_actuator
from bellows_ros.doctor import actuator_causes
from bellows_ros.models import actuator_effects
from bellows_ros.models.actuator_effects import BY_NAME, EFFECTS, NAMES
from bellows_ros.models.actuator_effects.base import ActuatorEffect, PlantTerm
from bellows_ros.models.actuator_plant import ActuatorPlant

CONFIG = load_actuator()
ROOT = Path(__file__).resolve().parents[1]
KINDS = {'limit', 'absent', 'bound', 'range'}
each = pytest.mark.parametrize('effect', EFFECTS, ids=NAMES)


def test_the_registry_is_every_module_of_the_package():
    modules = {m.name for m in pkgutil.iter_modules(actuator_effects.__path__)} - {'base'}
    assert set(NAMES) == modules
    assert len({e.rank for e in EFFECTS}) == len(EFFECTS)       # one order, no ties
    assert all(isinstance(e, ActuatorEffect) for e in EFFECTS)


@each
def test_its_parameters_have_a_default_inside_their_range_and_a_strength(effect):
    assert effect.parameters and effect.summary and effect.deciding_data
    for name, p in effect.parameters.items():
        assert p.low <= p.default <= p.high and p.unit and p.meaning, name
    assert effect.strength in effect.parameters   # the live strength; 0 switches it off


@each
def test_every_fit_bound_says_what_a_fit_pinned_there_means(effect):
    variables = effect.fit_variables(CONFIG.model)
    assert [v.name for v in variables] == [v.name for v in effect.fit]
    for name, start, lower, upper in variables:
        assert lower < upper and lower <= start <= upper, name
        for side in ('lower', 'upper'):
            assert effect.edges[name, side][0] in KINDS, (name, side)
    assert set(effect.edges) == {(v.name, s) for v in effect.fit for s in ('lower', 'upper')}
    assert all(len(start) == len(effect.fit) for start in effect.starts)
    assert effect.judged_by in ('profile', 'onset', 'structure')


@each
def test_its_fit_variables_give_finite_physical_parameters(effect):
    for pick in (lambda v: v.start, lambda v: v.lower, lambda v: v.upper):
        values = effect.to_si({v.name: pick(v) for v in effect.fit})
        assert values and all(math.isfinite(x) for x in values.values())
        # An effect judged by its onset profiles in SI and starts its fit from there.
        if effect.judged_by == 'onset':
            raw = {v.name: pick(v) for v in effect.fit}
            assert effect.from_si(values) == pytest.approx(raw, rel=1e-12, abs=1e-12)


def _plant_run(plant, steps=1500):
    """Pressure and force of `plant` over reversals, holds and a spring cycle."""
    rows = []
    for k in range(steps):
        duty = (0.9, 0.0, -0.9, 0.0)[(k // 150) % 4]
        sample = plant.step(1e-3, duty, x_s_imposed=0.012 * math.sin(math.pi * k / 1500) ** 2)
        rows.append((sample.p, sample.f))
    return np.array(rows)


def _plant(effects=None):
    return ActuatorPlant(CONFIG.model, CONFIG.plant, effects, noise=False, seed=0)


@each
def test_the_plant_steps_it_and_its_strength_0_is_the_baseline(effect):
    baseline = _plant()
    on = _plant([effect.name])
    assert np.max(np.abs(_plant_run(on) - _plant_run(baseline))) > 0.0   # the plant has it
    term = effect.plant_term(CONFIG.plant.effect_defaults()[effect.name])
    assert term is None or (isinstance(term, PlantTerm) and term.hooks())
    # Switched off while running: the next step is the baseline's physics (the state carries on).
    on.set_strengths({effect.name: 0.0})
    assert on.strengths()[effect.name] == 0.0
    _plant_run(on, 1)
    assert on.effects == {} and on.params == baseline.params
    assert on.temperature == on.t_ambient


@each
def test_the_doctors_model_of_it_changes_the_prediction(effect):
    x_c = 0.02 * np.sin(np.linspace(0.0, 6.0 * np.pi, 2000)) ** 2 - 0.005
    x_s = 0.012 * np.sin(np.linspace(0.0, 3.0 * np.pi, 2000)) ** 2
    params = CONFIG.model
    base = {'baseline': {'p_ref': params.p_ref, 'v_tube': params.v_tube, 'x_c_offset': 0.0}}
    # three quarters of each variable's way up its bounds, past the effect's 'absent' edges
    values = effect.to_si({v.name: 0.25 * v.lower + 0.75 * v.upper
                           for v in effect.fit_variables(params)})
    p0, g0 = actuator_causes.predict_state(params, (), base, x_c, x_s, 5e-3)
    p1, g1 = actuator_causes.predict_state(params, (effect.name,), {**base, effect.name: values},
                                           x_c, x_s, 5e-3)
    f0 = actuator_causes.force_columns(params, (), base, x_s, g0)[0]
    f1 = actuator_causes.force_columns(params, (effect.name,), {**base, effect.name: values},
                                       x_s, g1)[0]
    assert np.max(np.abs(p1 - p0)) + np.max(np.abs(f1 - f0)) > 0.0
    assert np.all(np.isfinite(p1)) and np.all(np.isfinite(f1))


@each
def test_the_doctor_says_whether_a_record_can_show_it(effect):
    record = actuator_causes_record()
    reasons = actuator_causes.identifiability(record, CONFIG.model,
                                              actuator_causes.noise_floors(record))
    assert set(reasons) == set(NAMES)
    assert reasons[effect.name] is None or reasons[effect.name].strip()


def actuator_causes_record():
    from bellows_ros.doctor import checks
    from bellows_ros.papers.actuator_experiments import actuator_record
    record = actuator_record(CONFIG.model, CONFIG.plant, None, seed=3, duration=8.0)
    table = checks.as_table(record, 'actuator', 'conformance')
    return checks.checked_record(table, 'actuator', 1).decimated(5)


@each
def test_the_benches_draw_it_within_its_parameters(effect):
    from bellows_ros.bench import devices
    device = devices.draw_actuator(5, [effect.name])
    assert set(device.drawn[effect.name]) == set(effect.devices)
    assert set(device.effects[effect.name]) <= set(effect.parameters)
    ActuatorPlant(device.params, device.plant, device.effects, noise=False)   # the plant takes it


@each
def test_its_docs_section_names_its_parameters_and_fit(effect):
    text = (ROOT / 'docs' / 'effects.md').read_text()
    names = (*effect.parameters, *(v.name for v in effect.fit))
    assert missing_from_section(text, f'## `{effect.name}`', names) == []


def test_the_docs_have_no_section_of_an_effect_that_is_not_there():
    text = (ROOT / 'docs' / 'effects.md').read_text()
    sections = {line[4:-1] for line in text.splitlines() if line.startswith('## `')}
    assert sections == set(NAMES)


# Where the effects are iterated over, never named (issue 31): the plant, the doctor, the live
# doctor, the ranges, the report and the benches.
ITERATING = ['bellows_ros/models/actuator_plant.py', 'bellows_ros/doctor/actuator_causes.py',
             'bellows_ros/doctor/report.py', 'bellows_ros/doctor/live.py',
             'bellows_ros/doctor/diagnosis.py', 'bellows_ros/doctor/checks.py',
             'bellows_ros/config/ranges.py', 'bellows_ros/config/actuator.py',
             *sorted(str(p.relative_to(ROOT)) for p in (ROOT / 'bellows_ros/bench').glob('*.py'))]


@pytest.mark.parametrize('path', ITERATING)
def test_no_effect_name_decides_a_branch(path):
    assert names_in_conditions((ROOT / path).read_text(), set(NAMES)) == []


def test_the_branch_rule_sees_a_name_in_a_condition():
    source = "if 'air_leak' in causes:\n    pass\nx = [c for c in y if c == 'backlash']\n"
    assert names_in_conditions(source, set(NAMES)) == [(1, 'air_leak'), (3, 'backlash')]


def test_an_effect_is_found_by_name_and_rank():
    assert BY_NAME[NAMES[0]] is EFFECTS[0]
    assert [e.rank for e in EFFECTS] == sorted(e.rank for e in EFFECTS)


def test_each_kind_of_drawn_device_has_seeds_of_its_own():
    from bellows_ros.bench import doctor_devices
    assert set(doctor_devices.SEED_BLOCKS) == set(doctor_devices.KINDS)
    assert len(set(doctor_devices.SEED_BLOCKS.values())) == len(doctor_devices.SEED_BLOCKS)
