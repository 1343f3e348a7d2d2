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
Devices drawn at random: paper A segments and paper B actuators that are not config's defaults.

One generator for every bench that must hold on devices the package was not built from (issue 21):
the doctor on drawn devices (`doctor_devices`), arm control (`arm_control_devices`) and stiffness
control (`stiffness_devices`). Every draw comes from a `numpy.random.Generator` seeded by the
caller, so a device is its seed.

Paper B actuator (`draw_actuator`). Factors multiply config/actuator.yaml's value; logU is uniform
in the logarithm; the last column says why (notes below the table).

| drawn | range | why |
|---|---|---|
| sealed gas p_ref | ×U(0.9, 1.1) | 1 |
| tube volume V_tube | ×U(0.5, 2.0) | 2 |
| bellows R0 (chamber, spring) | ×U(0.95, 1.05) each | 3 |
| spring material F_MTS | ×U(0.7, 1.4) | 4 |
| E_F amplitude C1 | ×logU(0.5, 2) | 5 |
| drive viscous friction | ×logU(0.5, 3) | 6 |
| pressure noise, quantum | logU(5, 60) Pa; one of 1, 2, 5, 10 Pa | 7 |
| force noise, quantum | logU(0.01, 0.1) N; one of 0.005, 0.01, 0.02 N | 8 |
| sample rate | one of 100, 200, 250, 500, 1000 Hz | 9 |
| record length | U(30, 60) s | 10 |
| chamber targets | within [U(-20, 0), U(15, 40)] mm | 11 |
| spring peaks | U(4, 10) .. U(10, 20) mm | 12 |
| each effect | its own `devices` ranges (docs/effects.md, with why) | 13 |
| buckling, onset at ambient | p_cr logU(0.1, 2) kPa, x_cr logU(0.5, 50) mm | 14 |
| buckling, onset at end of travel | x_cr ×U(0.85, 1) top peak, p_cr logU(300, 1100) kPa | 15 |

1. Sealed at ambient (weather, altitude to ~900 m); paper B's volume test filled 0.92-1.08 × with
   a syringe.
2. Tube length and fittings differ by rig (the doctor refits it).
3. Moulding tolerance. Geometry is measured, so the doctor is given the device's.
4. Silicone hardness between batches (Shore A ± 5).
5. Paper B's force error is an empirical fit of one device.
6. Lead-screw lubrication and wear.
7. 0.02-0.2 % of a 30 kPa gauge sensor; 12-16 bit converters.
8. Load cells of 20-100 N at 0.05-0.1 %.
9. The drivers' range: serial boards to the 1 kHz CAN rig.
10. A short excitation run (the doctor needs 5 s; 30 s is what its tests take).
11. The part of the chamber's travel a user's test covers.
12. Paper B's test machine cycles the spring to 8-20 mm.
13. Each effect module of `models.actuator_effects` says what it is drawn from. Buckling's k_b
    is then lowered where the spring would lose more force than it carries (`within_carried`):
    past its onset `buckling_force` falls at k_b in the compression and k_b x_cr / p_cr in the
    pressure without end, kilonewtons at a small p_cr and a large x_cr.
14. The onset at ambient pressure (`onset='ambient'`): the free spring buckles within 2 kPa of
    ambient, and compressed (x_cr from 0.5 mm to beyond the record's 20 mm) at or below it;
    paper B's spring buckles "under high pressure and compression", a softer or more slender
    one at ambient.
15. The onset at the end of the travel (`onset='travel_end'`): only the record's deepest
    compressions buckle the spring, the pressure hardly moves the onset.

Paper A segment (`draw_segment`; ranges as docs/arm_control.md gives them, where they were first
drawn): geometry l0, s0 ×U(0.85, 1.15); Ogden μ ×logU(0.5, 2), γ1 U(2.2, 3.5), γ2 U(4, 8); actuator
torque scale θ_a[1] ×logU(0.7, 1.4); restoring k_s U(-2.5, -0.8), k_s,p U(-2, -0.3), c_Ψ0
U(1.5, 5), c_Ψ0,p U(0.2, 0.8) rad; friction c_f U(-0.8, -0.1), c_f,p U(-1.5, -0.2) N·m; valve
lag U(30, 80) ms; M logU(0.01, 0.04) kg·m², C logU(0.5, 2) N·m·s/rad; noise p logU(0.5, 3) kPa,
Ψ logU(0.5, 2) mrad, τ logU(0.02, 0.1) N·m; a pressure-sensor lag U(10, 40) ms on 30 % of them.
"""
from collections import namedtuple
import dataclasses

import numpy as np

from bellows_ros.bench import log_uniform
from bellows_ros.models.actuator_effects import BY_NAME, EFFECTS

RATES = (100.0, 200.0, 250.0, 500.0, 1000.0)   # Hz
SIM_DT = 1e-3   # s: the actuator plant runs at 1 kHz; a slower sensor reads every k-th step

# Per effect: {parameter: (kind, low, high)}, kind 'u' uniform, 'log' log-uniform (SI units),
# each effect's own `devices` (`models.actuator_effects`, note 13).
EFFECT_RANGES = {effect.name: dict(effect.devices) for effect in EFFECTS}
# Onsets at the edges of the physical range (notes 14, 15): {onset: {parameter: (kind, low,
# high)}}, replacing those of the effect that has the parameters (buckling); 'travel_end' x_cr is
# a fraction of the record's top spring peak (the drawn spring_range's high end).
ONSETS = {
    'ambient': {'critical_pressure': ('log', 1e2, 2e3),
                'critical_compression': ('log', 5e-4, 0.05)},
    'travel_end': {'critical_compression': ('u', 0.85, 1.0),
                   'critical_pressure': ('log', 3e5, 1.1e6)},
}
# The buckling the stiffness-control bench draws as a nuisance (`stiffness_devices`), as issue 21
# drew it for every bench: its devices and its log stay comparable. Not the doctor's ranges.
CONTROL_BUCKLING = {'stiffness_loss': ('log', 500.0, 8000.0),
                    'critical_compression': ('u', 0.005, 0.030),
                    'critical_pressure': ('log', 1e4, 3e5)}


Actuator = namedtuple('Actuator',
                      'params plant effects rate duration x_c_range spring_range seed drawn')
Actuator.__doc__ = ('A drawn actuator: true physics (ActuatorParams; p_ref the sealed gas), '
                    'ActuatorPlantParams (drive, sensors), effects {name: parameters} as '
                    '`ActuatorPlant` takes them, sample rate Hz, record length s, the record '
                    "programme's chamber targets and spring peaks (m), seed, and what was drawn "
                    'of each effect {name: parameters} (buckling: its onset, which the plant '
                    'keeps in params).')
Segment = namedtuple('Segment', 'physics plant effects seed')
Segment.__doc__ = ('A drawn segment: true physics (SegmentParams), SegmentPlantParams, effects '
                   '(name -> parameters), seed of its records and noise.')


def _draw(rng, kind, low, high):
    return log_uniform(rng, low, high) if kind == 'log' else float(rng.uniform(low, high))


# Gauge pressures (Pa) a drawn record's sealed gas spans at most (the chamber's targets within
# -20..40 mm from the design point; the records seen reach -10..+16 kPa).
RECORD_GAUGE = (-15e3, 20e3)


def within_carried(params, shape, peak):
    """
    Return the drawn k_b (N/m), lowered where the spring would lose more force than it carries.

    Past its onset `buckling_force` loses k_b (x_s - x_cr) + k_b x_cr (P - P_atm)/p_cr, linear
    without end: at a small p_cr and a large x_cr that is kilonewtons on a spring that carries
    tens of newtons. A buckled bellows cannot lose more force than it carries, at most its
    material force at the record's top compression `peak` (m) plus the pressure's force on it
    (equivalent area times the record's highest gauge, `RECORD_GAUGE`). k_b is scaled down until
    the largest loss over the record's range (x_s 0..peak, gauge over `RECORD_GAUGE`) is that.
    """
    from bellows_ros.models.actuator import Buckling, buckling_force, material_terms
    from bellows_ros.models.actuator_geometry import area, P_ATM
    x_s, gauge = np.meshgrid(np.linspace(0.0, peak, 41), np.linspace(*RECORD_GAUGE, 71))
    onset = Buckling(1.0, shape['critical_pressure'], shape['critical_compression'],
                     params.buckling.onset_width)
    loss = float(np.max(-buckling_force(onset, x_s, P_ATM + gauge, np.exp)[0]))
    carried = (float(np.dot(params.f_mts, material_terms(np.array(peak), len(params.f_mts))))
               + float(area(params.spring, 0.0, P_ATM)[0]) * RECORD_GAUGE[1])
    if loss <= 0.0:
        return shape['stiffness_loss']
    return float(min(shape['stiffness_loss'], carried / loss))


def draw_effect(rng, name, ranges=None):
    """Parameters of effect `name` drawn from `ranges` (default `EFFECT_RANGES[name]`, SI)."""
    return {key: _draw(rng, *spec) for key, spec in (ranges or EFFECT_RANGES[name]).items()}


def draw_actuator(seed, effects=(), onset=None, buckling=None):
    """
    Return an `Actuator` drawn from the ranges of the module docstring, seeded.

    `effects`: names of the effects it has (their strength and shape drawn too). The device's
    physics is drawn before its effects, so the same seed gives the same device with or without
    an effect. `onset` ('ambient', 'travel_end'; `ONSETS`) draws a buckling onset at that edge of
    its physical range; `buckling` replaces the buckling's ranges ({parameter: (kind, low,
    high)}, `CONTROL_BUCKLING`).
    """
    from bellows_ros.config.actuator import load_actuator
    rng = np.random.default_rng(seed)
    config = load_actuator()
    params, plant = config.model, config.plant
    chamber = dataclasses.replace(params.chamber,
                                  r_big=params.chamber.r_big * rng.uniform(0.95, 1.05))
    spring = dataclasses.replace(params.spring,
                                 r_big=params.spring.r_big * rng.uniform(0.95, 1.05))
    e_f = list(params.e_f)
    e_f[0] *= log_uniform(rng, 0.5, 2.0)
    params = dataclasses.replace(
        params, chamber=chamber, spring=spring, p_ref=params.p_ref * rng.uniform(0.9, 1.1),
        v_tube=params.v_tube * rng.uniform(0.5, 2.0),
        f_mts=tuple(float(c) for c in np.asarray(params.f_mts) * rng.uniform(0.7, 1.4)),
        e_f=tuple(e_f))
    drive = dataclasses.replace(plant.drive, viscous_friction=plant.drive.viscous_friction
                                * log_uniform(rng, 0.5, 3.0))
    sensors = dataclasses.replace(
        plant.sensors, pressure_noise=log_uniform(rng, 5.0, 60.0),
        pressure_quantum=float(rng.choice((1.0, 2.0, 5.0, 10.0))),
        force_noise=log_uniform(rng, 0.01, 0.1),
        force_quantum=float(rng.choice((0.005, 0.01, 0.02))))
    plant = dataclasses.replace(plant, drive=drive, sensors=sensors)
    rate = float(rng.choice(RATES))
    duration = float(rng.uniform(30.0, 60.0))
    x_c_range = (rng.uniform(-0.020, 0.0), rng.uniform(0.015, 0.040))
    spring_range = (rng.uniform(0.004, 0.010), rng.uniform(0.010, 0.020))
    # Effects last, each from its own stream: adding one leaves the device and the others as
    # they are.
    # An onset or buckling ranges replace those of the effect that has their parameters.
    replaced = {**(buckling or {}), **(ONSETS[onset] if onset else {})}
    drawn, plant_effects = {}, {}
    for name in effects:
        ranges = dict(EFFECT_RANGES[name])
        ranges.update({key: spec for key, spec in replaced.items() if key in ranges})
        # each effect from a stream of its own, by its rank, which never changes
        values = draw_effect(np.random.default_rng([seed, BY_NAME[name].rank]), name, ranges)
        if 'critical_compression' in values:
            if onset == 'travel_end':
                values['critical_compression'] *= spring_range[1]
            if not buckling:
                values['stiffness_loss'] = within_carried(params, values, spring_range[1])
        drawn[name] = values
        params, plant_effects[name] = BY_NAME[name].device(params, values)
    return Actuator(params, plant, plant_effects, rate, duration, x_c_range, spring_range, seed,
                    drawn)


def actuator_device_record(device, effects=None, noise=None):
    """
    Simulate `device`'s excitation record: {column: array} at the device's sample rate.

    `effects` (default the device's) and `noise` (None: the device's sensors; False: none) as
    `actuator_experiments.actuator_record`. The plant runs at 1 kHz; a slower sensor reads every
    k-th step (no averaging: what a slower board samples).
    """
    from bellows_ros.papers.actuator_experiments import actuator_record
    record = actuator_record(device.params, device.plant,
                             device.effects if effects is None else effects, noise,
                             seed=device.seed, duration=device.duration, dt=SIM_DT,
                             x_c_range=device.x_c_range, spring_range=device.spring_range)
    every = int(round(1.0 / (device.rate * SIM_DT)))
    return {name: column[::every] for name, column in record.items()}


def draw_segment(seed):
    """Return a `Segment` drawn from the ranges of the module docstring, seeded."""
    from bellows_ros.config.segment import load_segment
    from bellows_ros.models.segment_plant import FULL_MODEL
    rng = np.random.default_rng(seed)
    config = load_segment()
    base, plant = config.model, config.plant

    def scale(low, high):
        return log_uniform(rng, low, high)
    theta = list(base.actuator_theta)
    theta[1] *= scale(0.7, 1.4)
    physics = base.replace(
        geometry_l0=base.geometry_l0 * rng.uniform(0.85, 1.15),
        geometry_s0=base.geometry_s0 * rng.uniform(0.85, 1.15),
        ogden_mu=(base.ogden_mu[0] * scale(0.5, 2.0), base.ogden_mu[1] * scale(0.5, 2.0)),
        ogden_gamma=(rng.uniform(2.2, 3.5), rng.uniform(4.0, 8.0)),
        actuator_theta=tuple(theta),
        restoring_k_s=rng.uniform(-2.5, -0.8), restoring_k_sp=rng.uniform(-2.0, -0.3),
        restoring_c_psi0=rng.uniform(1.5, 5.0), restoring_c_psi0_p=rng.uniform(0.2, 0.8),
        friction_c_f=rng.uniform(-0.8, -0.1), friction_c_fp=rng.uniform(-1.5, -0.2))
    plant = plant.replace(
        valve_tau=rng.uniform(0.03, 0.08), inertia=scale(0.01, 0.04), damping=scale(0.5, 2.0),
        noise_p=scale(500.0, 3000.0), noise_psi=scale(5e-4, 2e-3),
        noise_tau=scale(0.02, 0.1))
    effects = {name: {} for name in FULL_MODEL}
    if rng.random() < 0.3:
        effects['sensor_lag'] = {'tau': rng.uniform(0.01, 0.04)}
    return Segment(physics, plant, effects, seed)
