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
Drawn devices (bench/devices.py): the ranges of its docstring, its streams, its bench-only rules.

Every draw is seeded, so each check below runs on fixed devices and cannot flake. What
test_bench_doctor_devices.py holds (a seed repeats, an effect leaves the physics, the buckling's
span and the 'ambient' p_cr, the 'travel_end' x_cr) is not repeated here.
"""
import numpy as np
import pytest

from bellows_ros.bench import devices
from bellows_ros.config.actuator import load_actuator
from bellows_ros.config.segment import load_segment
from bellows_ros.models.actuator import Buckling, buckling_force, material_terms
from bellows_ros.models.actuator_effects import EFFECTS
from bellows_ros.models.actuator_geometry import area, P_ATM
from bellows_ros.models.segment_plant import FULL_MODEL
from bellows_ros.papers.actuator_experiments import actuator_record

SEEDS = range(40)
NAMES = tuple(effect.name for effect in EFFECTS)


def within(value, low, high):
    return low <= value <= high


@pytest.fixture(scope='module')
def actuators():
    return [devices.draw_actuator(seed) for seed in SEEDS]


def test_an_actuator_is_drawn_within_the_ranges_of_the_docstring(actuators):
    config = load_actuator()
    model, plant = config.model, config.plant
    for device in actuators:
        p, sensors = device.params, device.plant.sensors
        assert within(p.p_ref / model.p_ref, 0.9, 1.1)
        assert within(p.v_tube / model.v_tube, 0.5, 2.0)
        assert within(p.chamber.r_big / model.chamber.r_big, 0.95, 1.05)
        assert within(p.spring.r_big / model.spring.r_big, 0.95, 1.05)
        # one material factor for the whole F_MTS polynomial (Shore A of one batch)
        factors = np.asarray(p.f_mts) / np.asarray(model.f_mts)
        assert within(factors[0], 0.7, 1.4) and np.allclose(factors, factors[0], rtol=1e-12)
        assert within(p.e_f[0] / model.e_f[0], 0.5, 2.0) and p.e_f[1:] == model.e_f[1:]
        assert within(device.plant.drive.viscous_friction
                      / plant.drive.viscous_friction, 0.5, 3.0)
        assert within(sensors.pressure_noise, 5.0, 60.0)                 # Pa
        assert sensors.pressure_quantum in (1.0, 2.0, 5.0, 10.0)
        assert within(sensors.force_noise, 0.01, 0.1)                    # N
        assert sensors.force_quantum in (0.005, 0.01, 0.02)
        assert device.rate in devices.RATES and within(device.duration, 30.0, 60.0)
        assert within(device.x_c_range[0], -0.020, 0.0)
        assert within(device.x_c_range[1], 0.015, 0.040)
        assert within(device.spring_range[0], 0.004, 0.010)
        assert within(device.spring_range[1], 0.010, 0.020)
        assert device.effects == {} and device.drawn == {}
    # drawn, not fixed: the draws spread over their ranges and every sample rate occurs
    tubes = [d.params.v_tube / model.v_tube for d in actuators]
    assert min(tubes) < 0.7 and max(tubes) > 1.5
    assert {d.rate for d in actuators} == set(devices.RATES)


def test_each_effect_is_drawn_within_its_ranges_from_a_stream_of_its_own():
    for seed in range(10):
        every = devices.draw_actuator(seed, NAMES)
        backwards = devices.draw_actuator(seed, NAMES[::-1])
        for name in NAMES:
            drawn = every.drawn[name]
            for key, (_, low, high) in devices.EFFECT_RANGES[name].items():
                # buckling's k_b may be lowered below its range (`within_carried`), never raised
                assert (0.0 < drawn[key] <= high if key == 'stiffness_loss'
                        else within(drawn[key], low, high)), (seed, name, key)
            # adding the other effects, or listing them in another order, changes none of it
            assert devices.draw_actuator(seed, (name,)).drawn[name] == drawn
            assert backwards.drawn[name] == drawn
        assert every.params == backwards.params


def test_draw_effect_draws_each_kind_of_range_as_it_says():
    ranges = {'a': ('u', 1.0, 1e4), 'b': ('log', 1.0, 1e4)}
    rng = np.random.default_rng(3)
    draws = [devices.draw_effect(rng, 'any', ranges) for _ in range(2000)]
    uniform, logs = (np.array([d[key] for d in draws]) for key in 'ab')
    assert uniform.min() >= 1.0 and uniform.max() <= 1e4 and logs.min() >= 1.0
    # uniform: median near the middle; log-uniform: near the geometric mean (100)
    assert 4000.0 < np.median(uniform) < 6000.0 and 50.0 < np.median(logs) < 200.0
    again = devices.draw_effect(np.random.default_rng(3), 'any', ranges)
    assert again == draws[0]
    # without ranges, the effect's own (EFFECT_RANGES)
    leak = devices.draw_effect(np.random.default_rng(3), 'air_leak')
    assert set(leak) == {'conductance'}
    assert within(leak['conductance'], *devices.EFFECT_RANGES['air_leak']['conductance'][1:])


def test_an_onset_at_an_edge_replaces_the_buckling_ranges_and_keeps_the_cap():
    for seed in range(10):
        ambient = devices.draw_actuator(seed, ('buckling',), 'ambient')
        shape = ambient.drawn['buckling']
        assert within(shape['critical_compression'], 5e-4, 0.05)        # note 14
        end = devices.draw_actuator(seed, ('buckling',), 'travel_end')
        shape = end.drawn['buckling']
        assert within(shape['critical_pressure'], 3e5, 1.1e6)           # note 15
        # what `drawn` says is what the plant has: x_cr in metres, not the fraction
        assert shape['critical_compression'] == end.params.buckling.critical_compression
        for device in (ambient, end):
            loss = device.drawn['buckling']['stiffness_loss']
            assert loss == pytest.approx(devices.within_carried(
                device.params, device.drawn['buckling'], device.spring_range[1]))


def test_control_buckling_ranges_are_drawn_and_never_capped():
    lowered = 0
    for seed in range(20):
        device = devices.draw_actuator(seed, ('buckling',), buckling=devices.CONTROL_BUCKLING)
        shape = device.drawn['buckling']
        for key, (_, low, high) in devices.CONTROL_BUCKLING.items():
            assert within(shape[key], low, high), (seed, key)
        assert device.params.buckling.stiffness_loss == shape['stiffness_loss']
        lowered += devices.within_carried(device.params, shape,
                                          device.spring_range[1]) < shape['stiffness_loss']
    assert lowered > 0      # the cap would have lowered some: it was not applied
    # an onset given with them wins where both draw a parameter
    both = devices.draw_actuator(0, ('buckling',), 'ambient', devices.CONTROL_BUCKLING)
    assert within(both.drawn['buckling']['critical_pressure'], 1e2, 2e3)
    assert within(both.drawn['buckling']['stiffness_loss'], 500.0, 8000.0)


def test_within_carried_lowers_k_b_to_the_force_the_spring_carries():
    params = load_actuator().model
    peak = 0.020
    carried = (float(np.dot(params.f_mts, material_terms(np.array(peak), len(params.f_mts))))
               + float(area(params.spring, 0.0, P_ATM)[0]) * devices.RECORD_GAUGE[1])

    def largest_loss(shape, k_b):
        # the loss grows with compression and pressure: largest at the record's corner
        onset = Buckling(k_b, shape['critical_pressure'], shape['critical_compression'],
                         params.buckling.onset_width)
        return -buckling_force(onset, peak, P_ATM + devices.RECORD_GAUGE[1])[0]

    # a small p_cr and a large x_cr: kilonewtons of loss at the drawn k_b
    wild = {'stiffness_loss': 1e5, 'critical_pressure': 1e3, 'critical_compression': 0.05}
    capped = devices.within_carried(params, wild, peak)
    assert largest_loss(wild, 1e5) > 100.0 * carried and capped < 1e5
    assert largest_loss(wild, capped) == pytest.approx(carried, rel=1e-9)
    # the cap does not depend on the k_b it lowers
    assert devices.within_carried(params, {**wild, 'stiffness_loss': 1e7}, peak) == \
        pytest.approx(capped, rel=1e-12)
    # an onset beyond the record loses little: k_b stays as drawn
    mild = {'stiffness_loss': 300.0, 'critical_pressure': 1.1e6, 'critical_compression': 1.0}
    assert devices.within_carried(params, mild, peak) == 300.0


def test_a_device_record_is_every_kth_sample_of_the_1_khz_plant():
    device = devices.draw_actuator(7, ('air_leak',))._replace(duration=3.0, rate=200.0)
    record = devices.actuator_device_record(device, noise=False)
    full = actuator_record(device.params, device.plant, device.effects, False, seed=device.seed,
                           duration=3.0, dt=devices.SIM_DT, x_c_range=device.x_c_range,
                           spring_range=device.spring_range)
    assert set(record) == {'t', 'x_c', 'x_s', 'p', 'f'} and len(record['t']) == 600
    for name, column in record.items():
        np.testing.assert_array_equal(column, full[name][::5], err_msg=name)   # no averaging
    sealed = devices.actuator_device_record(device, effects={}, noise=False)
    assert not np.array_equal(sealed['p'], record['p'])        # the leak was the device's


def test_a_segment_is_drawn_within_the_ranges_of_the_docstring():
    config = load_segment()
    base, plant = config.model, config.plant
    segments = [devices.draw_segment(seed) for seed in range(200)]
    for segment in segments:
        s, q = segment.physics, segment.plant
        assert within(s.geometry_l0 / base.geometry_l0, 0.85, 1.15)
        assert within(s.geometry_s0 / base.geometry_s0, 0.85, 1.15)
        assert all(within(m / m0, 0.5, 2.0) for m, m0 in zip(s.ogden_mu, base.ogden_mu))
        assert within(s.ogden_gamma[0], 2.2, 3.5) and within(s.ogden_gamma[1], 4.0, 8.0)
        assert within(s.actuator_theta[1] / base.actuator_theta[1], 0.7, 1.4)
        assert s.actuator_theta[0] == base.actuator_theta[0]
        assert s.actuator_theta[2:] == base.actuator_theta[2:]
        assert within(s.restoring_k_s, -2.5, -0.8) and within(s.restoring_k_sp, -2.0, -0.3)
        assert within(s.restoring_c_psi0, 1.5, 5.0)
        assert within(s.restoring_c_psi0_p, 0.2, 0.8)
        assert within(s.friction_c_f, -0.8, -0.1) and within(s.friction_c_fp, -1.5, -0.2)
        assert (s.p0, s.p_max, s.geometry_sa_max) == (base.p0, base.p_max, base.geometry_sa_max)
        assert within(q.valve_tau, 0.03, 0.08) and within(q.inertia, 0.01, 0.04)   # s, kg m²
        assert within(q.damping, 0.5, 2.0)
        assert within(q.noise_p, 500.0, 3000.0) and within(q.noise_psi, 5e-4, 2e-3)  # Pa, rad
        assert within(q.noise_tau, 0.02, 0.1)                                        # N m
        assert q.psi_limit == plant.psi_limit
        assert set(FULL_MODEL) <= set(segment.effects) <= set(FULL_MODEL) | {'sensor_lag'}
        if 'sensor_lag' in segment.effects:
            assert within(segment.effects['sensor_lag']['tau'], 0.01, 0.04)
    lagging = sum('sensor_lag' in segment.effects for segment in segments)
    assert 40 <= lagging <= 80                   # 30 % of them (60 of 200; fixed seeds)
