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

"""Simulated actuator: drive, sensors, effects switched and refused (each effect: its own test)."""
from actuator_runs import DT, PARAMS, PLANT, run, SIGMA_P
import numpy as np
import pytest

from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator import evaluate
from bellows_ros.models.actuator_plant import (ACTUATOR_EFFECTS, ActuatorPlant, effect_parameters,
                                               model_params, STRENGTHS)
from bellows_ros.papers.actuator_experiments import actuator_record


def test_effect_names_are_the_registrys_and_keep_the_papers_effects():
    from bellows_ros.models.actuator_effects import NAMES
    assert ACTUATOR_EFFECTS == NAMES
    assert {'air_leak', 'heat_exchange', 'wall_bulging', 'sensor_lag', 'backlash',
            'buckling'} <= set(NAMES)


def test_unknown_effect_or_parameter_is_named():
    with pytest.raises(ParameterError, match="'air_leek'"):
        ActuatorPlant(PARAMS, PLANT, {'air_leek': {}})
    with pytest.raises(ParameterError, match="'tau'"):
        ActuatorPlant(PARAMS, PLANT, {'sensor_lag': {'tau': 0.1}})
    with pytest.raises(ParameterError, match="'conductance'"):
        ActuatorPlant(PARAMS, PLANT, {'air_leak': {'conductance': -1.0}})
    with pytest.raises(ParameterError, match="'pressure_nois'"):
        ActuatorPlant(PARAMS, PLANT, noise={'pressure_nois': 1.0})


def test_no_effects_plant_agrees_with_model_to_the_noise():
    plant = ActuatorPlant(PARAMS, PLANT, seed=3, x_c0=0.0)
    model = model_params(PARAMS)
    samples = []
    for duty in (1.0, -0.6, 0.8, 0.0):
        samples += run(plant, 1.5, duty, x_s=lambda t: 0.01 * (1 - np.cos(2 * t)))
    p_model = np.array([evaluate(model, s.x_c, s.x_s)[0] for s in samples])
    f_model = np.array([evaluate(model, s.x_c, s.x_s)[1] for s in samples])
    p_res = np.array([s.p for s in samples]) - p_model
    f_res = np.array([s.f for s in samples]) - f_model
    assert 0.8 * SIGMA_P < p_res.std() < 1.3 * SIGMA_P
    assert abs(p_res.mean()) < 1.0
    sigma_f = PLANT.sensors.force_noise
    assert 0.8 * sigma_f < f_res.std() < 1.3 * sigma_f
    # The pressure really moved: the comparison is not between two constants.
    assert np.ptp(p_model) > 5000.0


@pytest.mark.parametrize('effect', sorted(STRENGTHS))
def test_every_strength_switches_its_effect_on_and_off_while_running(effect):
    defaults = effect_parameters(PLANT, [effect])[effect]
    plant = ActuatorPlant(PARAMS, PLANT, seed=3, x_c0=0.030)
    run(plant, 0.05, x_s=0.001)
    plant.set_strengths({effect: defaults[STRENGTHS[effect]]})
    run(plant, 0.05, x_s=0.001)
    assert plant.effects == {effect: defaults}          # its other parameters from the YAML
    plant.set_strengths({effect: 0.0})
    run(plant, 0.05, x_s=0.001)
    assert plant.effects == {} and plant.temperature == plant.t_ambient


def test_a_strength_the_plant_cannot_use_is_refused_and_nothing_changes():
    plant = ActuatorPlant(PARAMS, PLANT, {'air_leak': {'conductance': 1e-10}}, seed=1)
    for bad in ({'air_leak': -1.0}, {'air_leak': float('inf')}, {'draught': 1.0}):
        with pytest.raises(ParameterError, match='air_leak|draught'):
            plant.set_strengths(bad)
    plant.step(DT, 0.0)
    assert plant.effects == {'air_leak': {'conductance': 1e-10}}


def test_drive_speed_encoder_end_stops_and_self_locking():
    plant = ActuatorPlant(PARAMS, PLANT, noise=False, x_c0=0.036)
    run(plant, 1.0, 1.0, x_s=0.0)
    x1 = plant.x_nut
    run(plant, 1.0, 1.0, x_s=0.0)
    speed = plant.x_nut - x1
    assert 0.85 * plant.max_speed < speed <= plant.max_speed
    sample = plant.step(DT, 0.0, 0.0)
    assert (abs(plant.x_from_counts(sample.encoder_counts) - plant.x_nut)
            <= PLANT.drive.metres_per_count)
    # Not back-drivable: once the rotor has coasted to rest, the gas load (here well above
    # ambient) cannot push the nut back at zero duty.
    run(plant, 0.5, 0.0, x_s=0.0)
    held = plant.x_nut
    assert plant.pressure > 110e3
    run(plant, 1.0, 0.0, x_s=0.0)
    assert plant.x_nut == held
    # End stop.
    top = ActuatorPlant(PARAMS, PLANT, noise=False, x_c0=PARAMS.chamber.x_max - 0.001)
    samples = run(top, 1.0, 1.0, x_s=0.0)
    assert samples[-1].at_upper_stop and not samples[0].at_upper_stop
    assert samples[-1].x_c == PARAMS.chamber.x_max


def test_experiment_record_is_seeded_and_shaped_like_the_paper():
    a = actuator_record(PARAMS, PLANT, seed=11, duration=6.0)
    b = actuator_record(PARAMS, PLANT, seed=11, duration=6.0)
    c = actuator_record(PARAMS, PLANT, seed=12, duration=6.0)
    assert list(a) == ['t', 'x_c', 'x_s', 'p', 'f']
    assert all(np.array_equal(a[k], b[k]) for k in a)
    assert not np.array_equal(a['p'], c['p'])
    assert len(a['t']) == 6000 and np.all(np.diff(a['t']) > 0)
    # x_c is the encoder reading: a whole number of counts.
    counts = a['x_c'] / PLANT.drive.metres_per_count
    assert np.allclose(counts, np.round(counts), atol=1e-6)
    assert np.ptp(a['x_s']) > 0.005 and np.ptp(a['x_c']) > 0.001
