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
Sensor drift (models/actuator_effects/sensor_drift.py), held three ways.

The plant, the doctor's model, and the doctor naming it from records that hide it.
"""
import dataclasses

import numpy as np
import pytest

from bellows_ros.config.actuator import load_actuator
from bellows_ros.doctor.actuator_causes import predict
from bellows_ros.doctor.diagnosis import diagnose
from bellows_ros.models.actuator_plant import ActuatorPlant
from bellows_ros.papers.actuator_experiments import actuator_record

CONFIG = load_actuator()


def _run(plant, steps, duty=0.5):
    return [plant.step(1e-3, duty if (k // 200) % 2 else -duty, x_s_imposed=0.004)
            for k in range(steps)]


def test_the_reading_drifts_and_the_gas_and_force_do_not():
    plain = ActuatorPlant(CONFIG.model, CONFIG.plant, noise=False)
    drifting = ActuatorPlant(CONFIG.model, CONFIG.plant, {'sensor_drift': {'rate': 40.0}},
                             noise=False)
    a, b = _run(plain, 2000), _run(drifting, 2000)
    assert [s.f for s in a] == [s.f for s in b]                 # the force never sees it
    assert plain.pressure == drifting.pressure                   # nor the gas
    offsets = np.array([y.p - x.p for x, y in zip(a, b)])
    t = np.array([s.t for s in b])
    assert offsets == pytest.approx(40.0 * t, abs=1e-6)          # Pa: r t


def test_a_new_rate_goes_on_from_the_offset_reached():
    plant = ActuatorPlant(CONFIG.model, CONFIG.plant, {'sensor_drift': {'rate': 40.0}},
                          noise=False)
    _run(plant, 1000)
    before = plant.step(1e-3, 0.0, x_s_imposed=0.004)
    plant.set_strengths({'sensor_drift': -10.0})
    after = plant.step(1e-3, 0.0, x_s_imposed=0.004)
    # 40 Pa/s for 1.001 s, then -10 Pa/s for one step: no jump at the switch
    assert after.p - plant.pressure == pytest.approx(40.0 * before.t - 10.0 * 1e-3, abs=1e-6)
    plant.set_strengths({'sensor_drift': 0.0})
    assert plant.step(1e-3, 0.0, x_s_imposed=0.004).p == plant.pressure   # off: no offset


def test_the_doctors_model_follows_the_plant():
    params = CONFIG.model
    plain = ActuatorPlant(params, CONFIG.plant, noise=False)
    drifting = ActuatorPlant(params, CONFIG.plant, {'sensor_drift': {'rate': -25.0}},
                             noise=False)
    measured = np.array([s.p for s in _run(drifting, 3000)])
    reference = np.array([s.p for s in _run(plain, 3000)])
    base = {'baseline': {'p_ref': params.p_ref, 'v_tube': params.v_tube, 'x_c_offset': 0.0}}
    shift = predict(params, ('sensor_drift',), {**base, 'sensor_drift': {'rate': -25.0}},
                    np.zeros(3000), np.zeros(3000), 1e-3)
    shift = shift - predict(params, (), base, np.zeros(3000), np.zeros(3000), 1e-3)
    # the model's drift starts at its first row, the plant's one step before it
    assert shift == pytest.approx(measured - reference + 25.0 * 1e-3, abs=1e-6)


def _record(effects, seed):
    rng = np.random.default_rng(seed)
    params = dataclasses.replace(CONFIG.model, v_tube=rng.uniform(1.0e-5, 2.5e-5),
                                 p_ref=rng.uniform(97e3, 106e3))
    return actuator_record(params, CONFIG.plant, effects, seed=seed, duration=30.0)


def _fitted(found, cause):
    score = found.candidates[cause].score
    return score.model.physical(score.full.theta, score.full.linear)[cause]


@pytest.mark.slow
@pytest.mark.parametrize('seed, rate', [(301, 8.0), (302, -4.0), (303, 2.0)])
def test_the_doctor_names_a_hidden_drift_and_its_rate(seed, rate):
    """A zero drifting by 60-240 Pa over 30 s, sensor noise 15 Pa: named, its rate found."""
    found = diagnose('actuator', _record({'sensor_drift': {'rate': rate}}, seed), CONFIG)
    assert found.causes == ['sensor_drift']
    assert found.gain > 0.2
    assert _fitted(found, 'sensor_drift')['rate'] == pytest.approx(rate, rel=0.1)


@pytest.mark.slow
def test_a_leak_is_not_taken_for_a_drift():
    """Both move the pressure reading; only the leak moves the force with it."""
    found = diagnose('actuator', _record({'air_leak': {'conductance': 5e-12}}, 304), CONFIG)
    assert found.causes == ['air_leak']
    assert found.candidates['sensor_drift'].identifiable
