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

"""Simulated actuator: drive, sensors, and each physical effect moving the data its way."""
import numpy as np
import pytest

from bellows_ros.config.actuator import load_actuator_params, load_actuator_plant_params
from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator import evaluate, gas_amount
from bellows_ros.models.actuator_geometry import P_ATM
from bellows_ros.models.actuator_plant import (ACTUATOR_EFFECTS, ActuatorPlant, effect_parameters,
                                               model_params, STRENGTHS)
from bellows_ros.papers.actuator_experiments import actuator_record

PLANT = load_actuator_plant_params()

PARAMS = load_actuator_params()
SIGMA_P = PLANT.sensors.pressure_noise
DT = 1e-3


def run(plant, seconds, duty=0.0, x_s=None):
    """Step `plant` for `seconds`; x_s is a constant or a function of plant time."""
    out = []
    for _ in range(int(round(seconds / DT))):
        target = x_s(plant.t) if callable(x_s) else x_s
        out.append(plant.step(DT, duty, x_s_imposed=target))
    return out


def fast_spring_step(t, start=0.5, rise=0.05, amplitude=0.012):
    return amplitude * min(max((t - start) / rise, 0.0), 1.0)


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


@pytest.mark.parametrize('x_c0', [0.040, -0.020])
def test_air_leak_decays_pressure_towards_ambient(x_c0):
    plant = ActuatorPlant(PARAMS, PLANT, {'air_leak': {'conductance': 2e-10}}, seed=1, x_c0=x_c0)
    sealed = ActuatorPlant(PARAMS, PLANT, seed=1, x_c0=x_c0)
    p_start = plant.pressure
    samples = run(plant, 8.0, x_s=0.0)
    reference = run(sealed, 8.0, x_s=0.0)
    first = np.mean([s.p for s in samples[:500]])
    last = np.mean([s.p for s in samples[-500:]])
    assert abs(last - P_ATM) < 0.8 * abs(first - P_ATM)            # closer to ambient
    assert np.sign(last - P_ATM) == np.sign(p_start - P_ATM)      # but does not cross it
    assert abs(np.mean([s.p for s in reference[-500:]]) - sealed.pressure) < 5.0
    assert (plant.gas < PARAMS.p_ref) == (p_start > P_ATM)        # gas left, or came in


def test_a_leak_switched_on_mid_run_takes_over_at_the_next_step_with_continuous_state():
    plant = ActuatorPlant(PARAMS, PLANT, seed=1, x_c0=0.040)
    sealed = ActuatorPlant(PARAMS, PLANT, seed=1, x_c0=0.040)
    run(plant, 0.2, x_s=0.0)
    run(sealed, 0.2, x_s=0.0)
    gas, x_c, p = plant.gas, plant.x_nut, plant.pressure
    assert plant.pressure > P_ATM + 1e4 and plant.strengths()['air_leak'] == 0.0
    plant.set_strengths({'air_leak': 2e-9})
    # Nothing changes until the plant steps: the swap happens in the stepping thread.
    assert (plant.gas, plant.x_nut, plant.pressure, plant.effects) == (gas, x_c, p, {})
    assert plant.strengths()['air_leak'] == 2e-9
    plant.step(DT, 0.0, x_s_imposed=0.0)
    sealed.step(DT, 0.0, x_s_imposed=0.0)
    # One step of the leak: the gas falls by dN = dt P c (P - P_atm), from where it was.
    expected_drop = DT * p * 2e-9 * (p - P_ATM)
    assert plant.effects == {'air_leak': {'conductance': 2e-9}}
    assert 0.0 < (sealed.gas - plant.gas) and plant.x_nut == sealed.x_nut
    drop = (gas - plant.gas) * _amount_per_p_ref(plant)  # p_ref is proportional to the amount
    assert drop == pytest.approx(expected_drop, rel=1e-6)
    run(plant, 2.0, x_s=0.0)
    assert plant.pressure < p - 0.3 * (p - P_ATM)            # the leak drains it
    # Off again (strength 0): the gas amount stays where the leak left it.
    plant.set_strengths({'air_leak': 0.0})
    plant.step(DT, 0.0, x_s_imposed=0.0)
    held = plant.gas
    run(plant, 0.5, x_s=0.0)
    assert plant.gas == held and plant.effects == {}


def _amount_per_p_ref(plant):
    """Gas amount N (Pa·m³) per Pa of p_ref at the plant's present volumes."""
    return gas_amount(plant.params, 2.0) - gas_amount(plant.params, 1.0)


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


def test_heat_exchange_overshoots_on_fast_compression_then_relaxes():
    tau = 0.5
    plant = ActuatorPlant(PARAMS, PLANT, {'heat_exchange': {'time_constant': tau}}, seed=2)
    samples = run(plant, 0.5 + 0.05 + 8 * tau, x_s=fast_spring_step)
    model = model_params(PARAMS)
    excess = np.array([s.p - evaluate(model, s.x_c, s.x_s)[0] for s in samples])
    t = np.array([s.t for s in samples])
    just_after = excess[(t > 0.55) & (t < 0.6)].mean()
    late = excess[t > 0.55 + 6 * tau].mean()
    assert just_after > 30 * SIGMA_P           # hotter gas: pressure above the isothermal value
    assert abs(late) < 0.05 * just_after       # relaxed back to the isothermal (ambient) value
    assert excess[(t > 0.55 + tau) & (t < 0.6 + tau)].mean() < 0.5 * just_after


def test_sensor_lag_delays_the_pressure_reading():
    tau = 0.05
    lagged = ActuatorPlant(PARAMS, PLANT, {'sensor_lag': {'time_constant': tau}}, noise=False)
    direct = ActuatorPlant(PARAMS, PLANT, noise=False)
    a = run(lagged, 1.0, x_s=lambda t: fast_spring_step(t, rise=0.002))
    b = run(direct, 1.0, x_s=lambda t: fast_spring_step(t, rise=0.002))
    t = np.array([s.t for s in a])
    pa, pb = np.array([s.p for s in a]), np.array([s.p for s in b])
    p0, p1 = pb[0], pb[-1]
    # Time to reach 63 % of the step, measured from the direct sensor's crossing.
    level = p0 + 0.632 * (p1 - p0)
    delay = t[np.argmax(pa > level)] - t[np.argmax(pb > level)]
    assert delay == pytest.approx(tau, rel=0.2)
    assert abs(pa[-1] - pb[-1]) < 1.0         # same value once settled


def test_backlash_leaves_a_dead_band_at_reversals():
    width = 0.001
    results = {}
    for name, effects in (('backlash', {'backlash': {'width': width}}), ('tight', None)):
        plant = ActuatorPlant(PARAMS, PLANT, effects, noise=False, x_c0=0.0)
        run(plant, 2.0, 1.0, x_s=0.0)                     # compress, stop, then reverse briefly
        run(plant, 0.3, 0.0, x_s=0.0)
        counts_before, p_before = plant.step(DT, 0.0, 0.0).encoder_counts, plant.pressure
        run(plant, 0.25, -1.0, x_s=0.0)
        sample = plant.step(DT, 0.0, 0.0)
        travel = (counts_before - sample.encoder_counts) * PLANT.drive.metres_per_count
        results[name] = (travel, plant.pressure - p_before)
    travel, dp = results['backlash']
    assert 0.2 * width < travel < 0.9 * width     # the nut did move back ...
    assert dp == 0.0                              # ... but the plate (and the pressure) did not
    travel_tight, dp_tight = results['tight']
    assert travel_tight == pytest.approx(travel, rel=0.05)
    assert dp_tight < -100.0                      # without backlash the pressure falls at once


def test_wall_bulging_adds_volume_under_pressure():
    bulging = ActuatorPlant(PARAMS, PLANT, ['wall_bulging'], noise=False, x_c0=0.045)
    rigid = ActuatorPlant(PARAMS, PLANT, noise=False, x_c0=0.045)
    assert bulging.pressure < rigid.pressure - 500.0
    # With the effect on, the plant is the YAML's augmented model.
    assert bulging.pressure == pytest.approx(evaluate(PARAMS, 0.045, 0.0)[0], rel=1e-9)


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


def test_buckling_effect_is_the_models_buckling_term():
    from bellows_ros.models.actuator import without_buckling
    forces = {}
    for effects in ((), ('buckling',), {'buckling': {'scale': 0.5}}):
        plant = ActuatorPlant(PARAMS, PLANT, effects, noise=False, x_c0=0.045)
        sample = plant.step(1e-3, 0.0, x_s_imposed=0.012)
        forces[str(effects)] = sample.f
        expected = evaluate(model_params(PARAMS, effect_parameters(PLANT, effects)), sample.x_c,
                            0.012)[1]
        assert sample.f == pytest.approx(expected, abs=1e-9)
    plain, full, half = forces.values()
    assert full < half < plain - 1.0          # the buckled spring pushes back less
    assert plain == pytest.approx(
        evaluate(without_buckling(model_params(PARAMS)), 0.045 - 0.0, 0.012)[1], rel=1e-3)
