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
The stiffness controller on drawn actuators, with the map identified from the device's record.

Per device (drawn at random, `devices.draw_actuator`, seeded, with a leak, wall bulging and
buckling): the sealed gas amount, the tube volume, the geometry, material, the drive's friction,
the sensors and the effects' strengths and shapes differ from config/actuator.yaml. Then:
1. an excitation record on the device (`actuator_experiments.actuator_record`: the chamber moved
   by its PD loop through steps, ramps and holds, the spring cycled as by paper B's test machine),
   the device's sensors;
2. `bellows identify actuator` on it (`identify.actuator.fit_actuator`, as the CLI calls it, from
   config/actuator.yaml);
3. stiffness steps on the same device, gas as after the record: `StiffnessSetpoint` (the inverse
   map) on the identified parameters and the lead-screw PD of config/nodes_sim.yaml's
   stiffness_controller_node, at its rates (sample 1 kHz, control every 5, target every 4); and,
   as the reference, the same with config/actuator.yaml's map (no identification).

Per step: the step time, until the device's true stiffness (paper B's figure at the true plate
position and gas, `models.actuator.stiffness` of the plant's physics) stays within
STEP_BAND of the set-point; and the error at the end of the hold (mean over the last second),
relative to the set-point. Reported: median and worst over all steps of all devices.
"""
import math

import numpy as np

from bellows_ros.bench import devices, Result
from bellows_ros.config.actuator import load_actuator
from bellows_ros.control.pd import PDController, PDGains
from bellows_ros.control.stiffness import StiffnessSetpoint
from bellows_ros.errors import BellowsError, ParameterError
from bellows_ros.identify.actuator import fit_actuator
from bellows_ros.io import params as parameters
from bellows_ros.models.actuator import stiffness
from bellows_ros.models.actuator_plant import ActuatorPlant
from bellows_ros.models.stiffness_map import stiffness_range
from bellows_ros.papers.actuator_experiments import actuator_record

DEVICES, QUICK_DEVICES = 10, 2
SEED = 41
RECORD = 40.0  # s of excitation
STEPS = (0.2, 0.8, 0.4, 0.6)  # set-points as fractions of the device's reachable range
HOLD = 8.0  # s per set-point
STEP_BAND = 0.02  # relative band around the set-point for the step time
DT = 1e-3


EFFECTS = ('air_leak', 'wall_bulging', 'buckling')


def draw_actuator(seed):
    """Return a drawn actuator (`devices.draw_actuator`) with a leak, wall bulging and buckling."""
    return devices.draw_actuator(seed, EFFECTS, buckling=devices.CONTROL_BUCKLING)


def controller_settings():
    """(PDGains, gas_time_constant, control_every, target_every) of nodes_sim.yaml."""
    flat = parameters.read_file(parameters.default_file('nodes_sim'),
                                'stiffness_controller_node')
    gains = PDGains(flat['pd.kp'], flat['pd.kd'], flat['pd.velocity_cutoff'],
                    flat['pd.duty_max'], flat['pd.deadband'])
    return gains, flat['gas_time_constant'], int(flat['control_every']), int(flat['target_every'])


def identify(device):
    """
    `bellows identify actuator` on an excitation record of `device` -> (ActuatorParams, how).

    The sealed fit first; where it fails (no pressure root, V_tube <= 0, no rising branch of
    K(x_c)), the fit with a leak (`--leak`, which the doctor's `air_leak` would point to), kept
    if it does not fail. The params are None when both fail; `how` says which fit was kept (with
    its G, and the volume error's correlation over STRUCTURE_LAG against the bound beyond which
    `bellows identify actuator` refuses the record) or why both failed.
    """
    record = actuator_record(device.params, device.plant, device.effects, None, seed=device.seed,
                             duration=RECORD)
    start = load_actuator().model
    reasons = []
    for leak in (False, True):
        label = 'with a leak' if leak else 'sealed'
        try:
            fit = fit_actuator(start, record['x_c'], record['x_s'], record['p'], record['f'],
                               seed=0, rate=1.0 / DT, t=record['t'] if leak else None)
        except BellowsError as exc:
            reasons.append(f'{label}: {exc}')
            continue
        why = _unusable(fit)
        if why:
            reasons.append(f'{label}: {why}')
            continue
        correlation, bound = fit.structure
        return fit.params, (f'{label}{f", G = {fit.leak:.3g} m^3/(s Pa)" if leak else ""}, '
                            f'structure {correlation:.2f} (bound {bound:.3f})')
    return None, '; '.join(reasons)


def _unusable(fit):
    """Why the map of `fit` is of no use, or ''."""
    if not fit.params.v_tube > 0:
        return f'V_tube = {fit.params.v_tube:.3g} m^3'
    k_min, k_max = stiffness_range(fit.params)
    if not (k_min > 0.0 and k_max > 1.01 * k_min):
        return f'the map has no usable rising branch (range {k_min:.0f}-{k_max:.0f} N/m)'
    return ''


def steps_on(device, controller_params):
    """Run the set-point steps on `device` with the map of `controller_params` -> per step."""
    gains, gas_tau, control_every, target_every = controller_settings()
    plant = ActuatorPlant(device.params, device.plant, device.effects, seed=device.seed + 1)
    truth = plant.params
    setpoint = StiffnessSetpoint(controller_params, gas_tau)
    pd = PDController(gains)
    k_low, k_high = stiffness_range(truth, plant.gas)
    x, duty, target, count, out = plant.x_nut, 0.0, None, 0, []
    for fraction in STEPS:
        k_goal = k_low + fraction * (k_high - k_low)
        setpoint.set_stiffness(min(max(k_goal, setpoint.range()[0]), setpoint.range()[1]))
        target = setpoint.target()
        true_k = np.empty(int(HOLD / DT))
        for i in range(len(true_k)):
            sample = plant.step(DT, duty)
            x = plant.x_from_counts(sample.encoder_counts)
            count += 1
            if count % control_every == 0:
                dt = DT * control_every
                setpoint.update_measurement(x, sample.x_s, sample.p, dt)
                if (count // control_every) % target_every == 0:
                    target = setpoint.target()
                duty = pd.update(target, x, dt)
            true_k[i] = stiffness(truth, sample.x_c, plant.gas)
        relative = true_k / k_goal - 1.0
        outside = np.flatnonzero(np.abs(relative) > STEP_BAND)
        settle = (outside[-1] + 1) * DT if outside.size else 0.0
        out.append((settle if settle < HOLD else math.inf,
                    abs(float(np.mean(relative[-int(1.0 / DT):])))))
    return out


def run(quick=False):
    count = QUICK_DEVICES if quick else DEVICES
    figures = {'identified_map': [], 'default_map': []}
    default = load_actuator().model
    failed, kept = [], []
    for index in range(count):
        device = draw_actuator(SEED + index)
        fitted, how = identify(device)
        try:
            steps = [] if fitted is None else steps_on(device, fitted)
        except ParameterError as exc:   # the map has no usable branch at the device's gas
            fitted, how = None, f'{how}; in use: {exc}'
        if fitted is None:
            failed.append(f'{index}: {how}')
        else:
            kept.append(f'{index}: {how}')
            figures['identified_map'] += steps
        figures['default_map'] += steps_on(device, default)
    results = []
    for name, steps in figures.items():
        if not steps:
            continue
        times = np.array([s[0] for s in steps])
        errors = np.array([s[1] for s in steps])
        result = Result(f'stiffness_control.devices.{name}.step_time', float(np.median(times)),
                        's', len(steps))
        result.extra.update({'worst_step_time': float(times.max()),
                             'median_error': float(np.median(errors)),
                             'worst_error': float(errors.max()),
                             'per_step_error': ' '.join(f'{e:.3f}' for e in errors)})
        result.extra_units.update(median_error='', worst_error='')
        if name == 'identified_map':
            result.extra['identification_failed'] = f'{len(failed)} of {count}'
            result.extra['failures'] = '; '.join(failed) or 'none'
            result.extra['fits'] = '; '.join(kept) or 'none'
        results.append(result)
    return results
