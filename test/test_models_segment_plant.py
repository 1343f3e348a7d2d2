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

"""The simulated segment: effects switched and refused, valve lag, noise, motion."""
import math

import numpy as np
import pytest

from bellows_ros.config.segment import load_segment_params, load_segment_plant_params
from bellows_ros.errors import ParameterError
from bellows_ros.models.segment import SegmentModel
from bellows_ros.models.segment_plant import (FULL_MODEL, NO_NOISE, plant_physics, SEGMENT_EFFECTS,
                                              SegmentPlant, STRENGTHS)
from bellows_ros.papers.segment_experiments import quasi_static_record, run_plant

PLANT = load_segment_plant_params()


@pytest.fixture(scope='module')
def params():
    return load_segment_params()


def test_effect_vocabulary_is_the_registrys_and_keeps_paper_as():
    from bellows_ros.models.segment_effects import NAMES
    assert SEGMENT_EFFECTS == NAMES
    assert {'contact_hysteresis', 'pressure_friction', 'natural_curvature',
            'sensor_lag'} <= set(NAMES)
    assert set(FULL_MODEL) == {'contact_hysteresis', 'pressure_friction', 'natural_curvature'}


@pytest.mark.parametrize('effects, message', [
    ({'air_leak': {}}, "unknown segment effect 'air_leak'"),
    ({'sensor_lag': {'tau_s': 0.1}}, "'sensor_lag': unknown parameter 'tau_s'"),
    ({'contact_hysteresis': {'gain': 1.0}}, "'contact_hysteresis': unknown parameter 'gain'"),
    ({'pressure_friction': {'c_fp': float('nan')}}, "'c_fp' is not finite"),
])
def test_unknown_effects_and_parameters_are_named(params, effects, message):
    with pytest.raises(ParameterError, match=message.replace('(', r'\(')):
        SegmentPlant(params, PLANT, effects)


def test_unknown_noise_key_is_named(params):
    with pytest.raises(ParameterError, match="'torque'"):
        SegmentPlant(params, PLANT, noise={'torque': 0.1})


def _bench(params, effects, n=6000, dt=1e-3):
    t = np.arange(1, n + 1) * dt
    psi = 1.0 * np.sin(2 * np.pi * 0.25 * t)
    cmd1 = np.where(t > 0.5, 4.5e5, params.p0)
    cmd2 = np.where(t > 3.0, 2.5e5, params.p0)
    return run_plant(SegmentPlant(params, PLANT, effects, NO_NOISE), dt, cmd1, cmd2, psi)


def test_baseline_plant_is_the_previous_model_without_the_missing_physics(params):
    record = _bench(params, {})
    physics = params.replace(friction_c_fp=0.0, restoring_k_sp=0.0, restoring_c_psi0_p=0.0)
    model = SegmentModel(physics)
    expected = [model.step(a, b, c, d).tau_prev for a, b, c, d in
                zip(record['psi'], record['psi_dot'], record['p1'], record['p2'])]
    np.testing.assert_allclose(record['tau_motion'] - record['tau_ext'], expected, atol=1e-9)


def test_each_effect_changes_the_measured_torque_and_full_model_is_paper_a(params):
    base = _bench(params, {})
    for name in FULL_MODEL:
        changed = _bench(params, {name: {}})
        assert np.max(np.abs(changed['tau_ext'] - base['tau_ext'])) > 0.2, name
    full = _bench(params, FULL_MODEL)
    model = SegmentModel(params)
    expected = [model.step(a, b, c, d).tau_drive for a, b, c, d in
                zip(full['psi'], full['psi_dot'], full['p1'], full['p2'])]
    np.testing.assert_allclose(full['tau_motion'] - full['tau_ext'], expected, atol=1e-9)


def test_effect_parameters_override_the_yaml(params):
    physics = plant_physics(params, {'pressure_friction': {'c_fp': 2.5},
                                     'natural_curvature': {'k_sp': -3.0}})
    assert physics.friction_c_fp == 2.5 and physics.restoring_k_sp == -3.0
    assert physics.restoring_c_psi0_p == params.restoring_c_psi0_p
    assert plant_physics(params, {}).restoring_c_psi0_p == 0.0


def test_a_strength_set_mid_run_takes_over_at_the_next_step_on_the_same_strain_memory(params):
    # Imposed angle and pressures that load and unload the membranes: the strain memories then
    # hold a history (hysteresis) that a reset would lose.
    n, switch, dt = 4000, 2000, 1e-3
    t = np.arange(1, n + 1) * dt
    psi = 1.0 * np.sin(2 * np.pi * 0.5 * t)
    cmd1 = np.where(t > 0.3, 4.5e5, params.p0)
    cmd2 = np.where(t > 1.2, 2.5e5, params.p0)
    plant = SegmentPlant(params, PLANT, ['contact_hysteresis', 'natural_curvature'], NO_NOISE)
    assert plant.strengths() == {'pressure_friction': 0.0, 'sensor_lag': 0.0,
                                 'natural_curvature': params.restoring_c_psi0_p}
    drive, states = [], []
    for i in range(n):
        if i == switch:
            plant.set_strengths({'pressure_friction': 2.5, 'natural_curvature': 0.0})
            assert 'pressure_friction' not in plant.effects  # not before the next step
        plant.step(dt, cmd1[i], cmd2[i], psi_imposed=psi[i])
        drive.append(plant.tau_drive)
        states.append((plant.psi, plant.psi_dot, plant.p1, plant.p2))  # what the model saw
    assert plant.effects == {'contact_hysteresis': {}, 'pressure_friction': {'c_fp': 2.5}}
    assert plant.strengths()['pressure_friction'] == 2.5
    # The memories do not depend on friction or natural curvature: a model of each physics run
    # from the start gives the plant's torque before and after the switch, bit for bit.
    before = SegmentModel(plant_physics(params, {'natural_curvature': {}}))
    after = SegmentModel(plant_physics(params, {'pressure_friction': {'c_fp': 2.5}}))
    both = np.array([(before.step(*state).tau_drive, after.step(*state).tau_drive)
                     for state in states])
    np.testing.assert_array_equal(drive, np.where(np.arange(n) < switch, both[:, 0], both[:, 1]))
    assert np.max(np.abs(both[switch:, 0] - both[switch:, 1])) > 0.1  # the switch mattered


@pytest.mark.parametrize('effect', sorted(STRENGTHS))
def test_each_strength_switches_its_effect_on_and_off_while_running(params, effect):
    plant = SegmentPlant(params, PLANT, noise=NO_NOISE)
    plant.step(1e-3, 3e5, params.p0, psi_imposed=0.1)
    plant.set_strengths({effect: 0.01})
    plant.step(1e-3, 3e5, params.p0, psi_imposed=0.1)
    assert plant.effects == {effect: {STRENGTHS[effect]: 0.01}}
    plant.set_strengths({effect: 0.0})
    plant.step(1e-3, 3e5, params.p0, psi_imposed=0.1)
    assert plant.effects == {} and plant.strengths() == dict.fromkeys(STRENGTHS, 0.0)
    with pytest.raises(ParameterError, match='contact_hysteresis'):
        plant.set_strengths({'contact_hysteresis': 1.0})
    with pytest.raises(ParameterError, match='tau'):
        plant.set_strengths({'sensor_lag': -1.0})


def test_pressures_follow_commands_through_the_valve_lag(params):
    plant = SegmentPlant(params, PLANT, noise=NO_NOISE)
    tau = PLANT.valve_tau
    samples = [plant.step(1e-3, 5e5, params.p0,
                          psi_imposed=0.0) for _ in range(int(round(tau / 1e-3)))]
    # after one time constant: 1 - 1/e of the step
    assert samples[-1].p1 == pytest.approx(params.p0 + (5e5 - params.p0) * (1 - math.exp(-1)),
                                           rel=1e-3)
    for _ in range(int(10 * tau / 1e-3)):
        sample = plant.step(1e-3, 5e5, params.p0, psi_imposed=0.0)
    assert sample.p1 == pytest.approx(5e5, rel=1e-4)


def test_noise_has_the_configured_spread_and_seed_repeats(params):
    def run(seed):
        plant = SegmentPlant(params, PLANT, seed=seed)
        return np.array([plant.step(1e-3, params.p0, params.p0,
                                    psi_imposed=0.0) for _ in range(4000)])
    first, again, other = run(3), run(3), run(4)
    np.testing.assert_array_equal(first, again)
    assert not np.array_equal(first, other)
    std = first.std(axis=0)  # columns t psi psi_dot p1 p2 tau_ext
    assert std[1] == pytest.approx(PLANT.noise_psi, rel=0.1)
    assert std[3] == pytest.approx(PLANT.noise_p, rel=0.1)
    assert std[5] == pytest.approx(PLANT.noise_tau, rel=0.1)


def test_free_motion_settles_where_the_torques_balance(params):
    # vented chains: τ_drive = τ_s = 2 k_s Ψ, so a load of 1 N·m holds Ψ = -1/(2 k_s)
    plant = SegmentPlant(params, PLANT, FULL_MODEL, NO_NOISE)
    for _ in range(20000):  # friction (c_f < 0) slows the creep near rest: time constant ≈ 1.7 s
        sample = plant.step(1e-3, params.p0, params.p0, tau_load=1.0)
    assert abs(sample.psi_dot) < 1e-5
    assert sample.psi == pytest.approx(-1.0 / (2 * params.restoring_k_s), rel=1e-3)


def test_free_pressurised_segment_is_stable_and_rests_on_its_end_stop(params):
    plant = SegmentPlant(params, PLANT, FULL_MODEL, NO_NOISE)
    for _ in range(8000):
        sample = plant.step(1e-3, 4e5, params.p0, tau_load=0.0)
    assert math.isfinite(sample.psi) and abs(sample.psi_dot) < 1e-3
    # chain 1 bends the segment towards positive Ψ until the end stop carries τ_drive
    assert PLANT.psi_limit < sample.psi < PLANT.psi_limit + 0.1


def test_quasi_static_record_has_the_design_columns_and_is_cheap(params):
    record = quasi_static_record(params, PLANT, FULL_MODEL, None, seed=2, duration=10.0)
    assert set(record) >= {'t', 'psi', 'p1', 'p2', 'tau_ext', 'psi_dot'}
    assert len(record['t']) == 10000 and np.all(np.diff(record['t']) > 0)
    assert record['p1'].max() <= params.p_max and record['psi'].std() > 0.1


def test_a_late_real_time_caller_gets_the_same_motion(params):
    """A CPU-starved simulator passes one long dt; the stiff end stop must not make it bounce."""
    on_time = SegmentPlant(params, PLANT, effects=FULL_MODEL, noise=NO_NOISE)
    late = SegmentPlant(params, PLANT, effects=FULL_MODEL, noise=NO_NOISE)
    for _ in range(1000):      # pressurise chain 1 and let the segment run onto its end stop
        on_time.step(1e-3, 4e5, 101325.0)
        late.step(1e-3, 4e5, 101325.0)
    worst = 0.0
    for _ in range(200):       # then 4 s at 20 ms a call, against 1 ms a call
        for _ in range(20):
            on_time.step(1e-3, 4e5, 101325.0)
        late.step(20e-3, 4e5, 101325.0)
        worst = max(worst, abs(late.psi - on_time.psi))
    assert abs(late.psi) <= PLANT.psi_limit + 0.05
    assert worst < 1e-6
