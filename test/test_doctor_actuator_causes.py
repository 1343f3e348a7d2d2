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
The actuator's baseline and causes as models the doctor fits (doctor/actuator_causes.py).

Short records with known parameters: paper B's static physics without E_V or buckling evaluated
on a chamber and spring cycle (the baseline must fit it exactly, gas, tube, encoder zero and
material force), and the plant with a sensor lag. Each effect's own conformance (its fit
variables, bounds, a change of the prediction) is held by test_actuator_effects.py; here, what this
module builds around the effects: the fit, the noise floors and scaled outputs, the linear solve,
what a record can show, the extended file.
"""
import dataclasses

import numpy as np
import pytest

from bellows_ros.config.actuator import (load_actuator, load_actuator_params,
                                         load_actuator_plant_params, params_to_flat)
from bellows_ros.doctor import actuator_causes, checks, scoring
from bellows_ros.models.actuator import evaluate_array
from bellows_ros.models.actuator_geometry import P_ATM
from bellows_ros.models.actuator_plant import model_params
from bellows_ros.papers.actuator_experiments import actuator_record

CONFIG = load_actuator()
PLANT = load_actuator_plant_params()
DT = 5e-3           # the doctor's fit rate for the actuator (FIT_RATE 200 Hz)


def cycled(params, offset=0.0, seconds=8.0):
    """
    Return a noise-free record of `params` without E_V or buckling: the baseline's physics.

    The chamber cycled ±20 mm, the spring 0-12 mm; the encoder reads the plate `offset` (m) low.
    """
    t = np.arange(0.0, seconds, DT)
    x_c = 0.02 * np.sin(2 * np.pi * t / 4.0) + 0.01
    x_s = 0.006 * (1.0 - np.cos(2 * np.pi * t / 3.0))
    p, f, _ = evaluate_array(model_params(params), x_c, x_s)     # (17), (7)-(12)
    return checks.Record('actuator', 'cycle', DT, {'t': t, 'x_c': x_c - offset, 'x_s': x_s,
                                                   'p': p, 'f': f})


def fit(record, causes, scales):
    model = actuator_causes.build_model(record, CONFIG.model, causes, scales=scales)
    result = scoring.fit(model, actuator_causes.measured(record, scales),
                         np.ones(len(record), bool))
    return model.physical(result.theta, result.linear), result


def test_the_baseline_refits_gas_tube_encoder_zero_and_material_force_exactly():
    truth = dataclasses.replace(CONFIG.model, v_tube=1.8e-5, p_ref=1.02e5)
    record = cycled(truth, offset=4e-4)
    values, result = fit(record, (), {'p': 10.0, 'f': 0.01})
    base = values['baseline']
    assert base['p_ref'] == pytest.approx(1.02e5, rel=1e-6)            # Pa
    assert base['v_tube'] == pytest.approx(1.8e-5, rel=1e-6)           # m³
    assert base['x_c_offset'] == pytest.approx(4e-4, abs=1e-8)         # m
    assert base['f_mts'] == pytest.approx(list(truth.f_mts), rel=1e-6)  # F_MTS (12)
    assert base['e_f_c1'] == pytest.approx(truth.e_f[0], rel=1e-6)     # E_F's C1 (11)
    assert base['force_zero'] == pytest.approx(0.0, abs=1e-6)
    assert result.cost < 1e-12


def test_the_first_guess_of_the_gas_is_the_mean_p_v():
    # isothermal and sealed: P V = p_ref V_ref at every row when V_tube is the nominal one
    truth = dataclasses.replace(CONFIG.model, p_ref=1.02e5)
    guess = actuator_causes.initial_guess(cycled(truth), CONFIG.model)
    assert guess == {'p_ref_kpa': pytest.approx(102.0, rel=1e-9),
                     'v_tube_ml': pytest.approx(CONFIG.model.v_tube / 1e-6),
                     'x_c_offset_mm': 0.0}


@pytest.fixture(scope='module')
def lagged():
    """Return the plant with a 50 ms pressure sensor lag, 10 s, at the doctor's 200 Hz."""
    data = actuator_record(CONFIG.model, PLANT, {'sensor_lag': {'time_constant': 0.05}}, seed=3,
                           duration=10.0)
    full = checks.checked_record(checks.as_table(data, 'actuator', 'bench'), 'actuator')
    floors = actuator_causes.noise_floors(full)
    return full.decimated(5), {name: floor / np.sqrt(5) for name, floor in floors.items()}


def test_a_fit_with_the_lag_recovers_its_time_constant(lagged):
    record, scales = lagged
    values, result = fit(record, ('sensor_lag',), scales)
    assert values['sensor_lag']['time_constant'] == pytest.approx(0.05, rel=0.05)
    assert result.prediction.shape == (2, len(record))      # pressure and force rows
    _, baseline = fit(record, (), scales)
    assert baseline.cost > 10 * result.cost


def test_noise_floors_and_the_outputs_in_them():
    rng = np.random.default_rng(5)
    t = np.arange(20000) * 1e-3
    ramps = 40.0 * np.abs((t % 2.0) - 1.0)              # N, ramped at 40 N/s by the machine
    record = checks.Record('actuator', 'x', 1e-3, {
        't': t, 'x_c': 0 * t, 'x_s': 0 * t, 'p': P_ATM + rng.normal(0.0, 20.0, t.size),
        'f': ramps + rng.normal(0.0, 0.03, t.size)})
    floors = actuator_causes.noise_floors(record)
    assert floors['p'] == pytest.approx(20.0, rel=0.05)
    assert floors['f'] == pytest.approx(0.03, rel=0.05)
    assert actuator_causes.noise_floors(dict(record.columns, f=ramps))['f'] == pytest.approx(
        1e-6 * 40.0)                                     # noise-free: 1e-6 of its span
    y = actuator_causes.measured(record, {'p': 20.0, 'f': 0.03})
    np.testing.assert_allclose(y, [record['p'] / 20.0, record['f'] / 0.03])


def test_the_material_force_is_solved_on_the_training_rows_only():
    rng = np.random.default_rng(1)
    columns = np.column_stack([np.ones(500), rng.uniform(0, 0.01, 500), rng.uniform(0, 1e3, 500)])
    coef = np.array([0.5, 1200.0, 2e-3])
    known = rng.normal(0.0, 1.0, 500)
    f = known + columns @ coef
    train = np.arange(500) < 300
    f[~train] += 1e3                                    # rows it must not see
    np.testing.assert_allclose(actuator_causes.solve_force(known, columns, f, train), coef,
                               rtol=1e-9)


def test_what_the_baseline_can_absorb_is_projected_out():
    rng = np.random.default_rng(2)
    jacobian = rng.normal(size=(200, 3))
    inside = jacobian @ np.array([1.0, -2.0, 0.5])
    beside = rng.normal(size=200)
    beside -= jacobian @ np.linalg.lstsq(jacobian, beside, rcond=None)[0]
    np.testing.assert_allclose(actuator_causes.beyond_baseline(inside, jacobian), 0.0,
                               atol=1e-10)
    np.testing.assert_allclose(actuator_causes.beyond_baseline(inside + beside, jacobian), beside,
                               atol=1e-10)


def test_a_record_that_never_reaches_an_onset_cannot_show_buckling(lagged):
    record, scales = lagged
    still = checks.Record('actuator', 'x', record.dt, dict(
        record.columns, x_s=0 * record['x_s'], p=np.minimum(record['p'], P_ATM - 500.0)))
    buckling = actuator_causes.BY_NAME['buckling']
    assert actuator_causes.buckling_profile(still, CONFIG.model, scales['f'], (), buckling) == []
    reason = actuator_causes.identifiability(still, CONFIG.model, scales)['buckling']
    total = actuator_causes.PROFILE_COMPRESSIONS * actuator_causes.PROFILE_PRESSURES
    assert 'spring 0.0-0.0 mm' in reason and f'0 of {total} onsets' in reason
    assert 'needs 5' in reason
    # where the spring is cycled, the onsets it reaches, best first, each with a k_b in range
    onsets = actuator_causes.buckling_profile(record, CONFIG.model, scales['f'], (), buckling)
    k_max = 10.0 ** buckling.fit_variables(CONFIG.model)[0].upper * 1e3
    assert onsets and [o.improvement for o in onsets] == sorted(
        (o.improvement for o in onsets), reverse=True)
    for onset in onsets:
        load = record['x_s'] / onset.critical_compression + (
            record['p'] - P_ATM) / onset.critical_pressure
        assert load.min() < 1.0 < load.max()
        assert 0.0 <= onset.stiffness_loss <= k_max


def test_a_chamber_that_never_reverses_cannot_show_backlash():
    record = cycled(CONFIG.model)
    ramp = checks.Record('actuator', 'x', DT, dict(
        record.columns, x_c=np.linspace(-0.01, 0.03, len(record))))
    reasons = actuator_causes.identifiability(ramp, CONFIG.model, {'p': 10.0, 'f': 0.01})
    assert set(reasons) == set(actuator_causes.CAUSES)
    assert 'never reverses' in reasons['backlash']


def test_names_of_the_baseline_and_what_a_pinned_fit_means():
    assert actuator_causes.edge_kind('sensor_lag', 'no such variable', 'upper') == (
        'range', 'a bound of the fit, not of physics')
    assert actuator_causes.baseline_name() == actuator_causes.BASELINE
    kept = actuator_causes.baseline_name(('wall_bulging',))
    assert kept != actuator_causes.BASELINE and "the model's own E_V" in kept
    assert set(actuator_causes.standing_physics(CONFIG.model)) == {'wall_bulging', 'buckling'}
    assert actuator_causes.standing_physics(model_params(CONFIG.model)) == ()


def test_the_extended_file_holds_the_refitted_gas_and_the_fitted_effect():
    values = {'baseline': {'p_ref': 1.02e5, 'v_tube': 1.8e-5, 'x_c_offset': 0.0},
              'sensor_lag': {'time_constant': 0.05}}
    flat = actuator_causes.extended_flat(CONFIG, ('sensor_lag',), values)
    assert flat['actuator.gas.p_ref'] == 1.02e5 and flat['actuator.gas.v_tube'] == 1.8e-5
    assert flat['actuator.effects.sensor_lag.time_constant'] == 0.05
    # the offline doctor's baseline keeps no E_V nor buckling: neither does the file
    assert not any(flat['actuator.air_chamber.e_v'])
    assert flat['actuator.buckling.stiffness_loss'] == 0.0
    # the live doctor's keeps the model's own (standing) physics
    standing = actuator_causes.extended_flat(CONFIG, ('sensor_lag',), values,
                                             actuator_causes.STANDING)
    model = params_to_flat(CONFIG.model, CONFIG.plant)
    assert standing['actuator.air_chamber.e_v'] == model['actuator.air_chamber.e_v']
    assert standing['actuator.buckling.stiffness_loss'] == pytest.approx(
        CONFIG.model.buckling.stiffness_loss)


# The doctor's vectorised effects against the plant's per-step ones, same parameters (E_V: the
# YAML's, whose two pressure-only terms the doctor carries as one).
PLANT_AND_DOCTOR = [
    ('air_leak', {'conductance': 1e-10}, {'conductance': 1e-10}),
    ('heat_exchange', {'time_constant': 0.5}, {'time_constant': 0.5, 'gamma': 1.4}),
    ('sensor_lag', {'time_constant': 0.05}, {'time_constant': 0.05}),
    ('backlash', {'width': 6e-4}, {'width': 6e-4}),
    ('wall_bulging', {'scale': 1.0}, None),
]


@pytest.mark.parametrize('effect, plant_values, doctor_values', PLANT_AND_DOCTOR,
                         ids=[row[0] for row in PLANT_AND_DOCTOR])
def test_doctor_effects_follow_the_plant(effect, plant_values, doctor_values):
    from bellows_ros.doctor.actuator_causes import predict
    from bellows_ros.models.actuator import without_buckling, without_bulging
    from bellows_ros.models.actuator_plant import ActuatorPlant
    params = without_buckling(load_actuator_params())
    if doctor_values is None:
        c, s = params.chamber.e_v, params.spring.e_v
        doctor_values = {'e_q': c[2] + s[2], 'e_dq_chamber': c[4], 'e_dq_spring': s[4],
                         'e_dd_chamber': c[3], 'e_dd_spring': s[3]}
    dt = 1e-3
    t = np.arange(0.0, 6.0, dt)
    nut = 0.03 + 0.012 * np.sin(np.pi * t) ** 3            # ramps, holds, reversals
    x_s = 0.01 * (1.0 - np.cos(0.7 * np.pi * t))

    def plant(effects):
        model = ActuatorPlant(params, PLANT, effects, noise=False, x_c0=nut[0])
        return np.array([model.step_nut(dt, a, x_s_imposed=b).p for a, b in zip(nut, x_s)])
    nominal = without_bulging(params)
    base = {'baseline': {'p_ref': nominal.p_ref, 'v_tube': nominal.v_tube, 'x_c_offset': 0.0}}
    measured = plant({effect: plant_values})
    size = np.max(np.abs(measured - plant(None)))
    assert size > 300.0                                      # Pa: the effect is there to follow
    doctor = predict(nominal, (effect,), dict(base, **{effect: doctor_values}), nut, x_s, dt)
    assert np.max(np.abs(doctor - measured)) < 0.05 * size
