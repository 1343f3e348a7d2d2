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
The arm controller closed around the simulated segment, in process (bench, scenario, tests).

Per 1 kHz sample, as on the graph: the plant (`SegmentPlant`, effects and noise as given) is
measured; Ψ̇ is the backward difference of the measured angles (what the driver publishes, the arm
has no velocity sensor); the tracker's model steps with the sample; every `control_every`-th
sample the tracker commands new pressures; the plant's valves get the newest command every
`setpoint_every` samples (the arm bus sends its set-point frames at a fixed cycle, config/arm.dbc)
and hold it in between. Deterministic for a given seed.
"""
from collections import namedtuple
import dataclasses

import numpy as np

from bellows_ros.config.segment import load_segment
from bellows_ros.control import angle_trajectory
from bellows_ros.control.angle_tracking import AngleTracker, TrackingGains
from bellows_ros.hardware import can_protocol
from bellows_ros.io import params as parameters
from bellows_ros.models.segment_plant import FULL_MODEL, SegmentPlant

TrackingRun = namedtuple('TrackingRun',
                         't psi_d psi psi_dot p1 p2 tau_drive p1_cmd p2_cmd saturated')
TrackingRun.__doc__ = ('Arrays per sample: time s, set-point and true angle rad, true velocity '
                       'rad/s, true chamber pressures Pa abs, true driving torque N·m, pressures '
                       'at the valves Pa abs, whether the allocation saturated.')

DT = 1e-3


def simulate(params, plant_params, gains, feedforward, trajectory, effects, seed=0,
             control_every=5, setpoint_every=1, duration=None, noise=None, physics=None,
             model=None):
    """
    Track `trajectory` on `SegmentPlant(physics, plant_params, effects, noise, seed)` -> a run.

    params: the tracker's model (SegmentParams); plant_params: the simulated segment's
    SegmentPlantParams; physics: the plant's SegmentParams (default: the tracker's); model: a
    stand-in for the tracker's `SegmentModel` (step, peek, torques, params), for ablations.
    """
    total = angle_trajectory.duration(trajectory) if duration is None else duration
    steps = int(round(total / DT))
    plant = SegmentPlant(physics or params, plant_params, effects=effects, noise=noise, seed=seed,
                         psi0=trajectory.start)
    tracker = AngleTracker(params, gains, feedforward)
    if model is not None:
        tracker.model = model
    out = np.zeros((steps, 10))
    sample = plant.step(DT, params.p0, params.p0)
    last_psi, command, valves = sample.psi, None, (params.p0, params.p0)
    for k in range(steps):
        t = k * DT
        psi_dot = (sample.psi - last_psi) / DT
        last_psi = sample.psi
        tracker.observe(sample.psi, psi_dot, sample.p1, sample.p2, DT)
        psi_d, psi_dot_d, psi_ddot_d = angle_trajectory.setpoint(trajectory, t)
        if k % control_every == 0:
            ahead = angle_trajectory.setpoint(trajectory, t + gains.lead)
            command = tracker.command(psi_d, psi_dot_d, psi_ddot_d, sample.psi,
                                      DT * control_every, ahead)
        if k % setpoint_every == setpoint_every - 1:
            valves = command.p1, command.p2
        out[k] = (t, psi_d, plant.psi, plant.psi_dot, plant.p1, plant.p2, plant.tau_drive,
                  valves[0], valves[1], command.saturated)
        sample = plant.step(DT, *valves)
    return TrackingRun(*(out[:, i] for i in range(9)), out[:, 9].astype(bool))


def rms(values):
    """Root mean square, NaN for an empty selection."""
    values = np.asarray(values, float)
    return float(np.sqrt(np.mean(values * values))) if values.size else float('nan')


def controller_settings(segment):
    """(TrackingGains, control_every) of config/nodes_sim.yaml's arm_controller_node."""
    flat = parameters.read_file(parameters.default_file('nodes_sim'), 'arm_controller_node')
    gains = TrackingGains(flat['pid.kp'], flat['pid.ki'], flat['pid.kd'],
                          flat['pid.velocity_cutoff'], flat['pid.integral_limit'],
                          segment.p0 + flat['co_contraction'], flat['feedforward_lead'])
    return gains, int(flat['control_every'])


def setpoint_every():
    """Count the samples between the arm bus's set-point frames (config/arm.dbc cycle times)."""
    db = can_protocol.load_dbc()
    return round(db.get_message_by_name('ARM_HOST_HEARTBEAT').cycle_time
                 / db.get_message_by_name('ARM_SEG1_SAMPLE').cycle_time)


def with_rigid_body(segment, plant):
    """Return the model's (2) with the simulated segment's M, C, N (as segment.dynamics)."""
    return segment.replace(dynamics_inertia=plant.inertia, dynamics_damping=plant.damping,
                           dynamics_gravity=plant.gravity)


def track(mode, trajectory, rigid_body=True, lead=True, seed=0, duration=None,
          model_factory=None):
    """
    Run controller `mode` ('none', 'previous', 'paper_a') in closed loop -> TrackingRun.

    On the default simulated segment with its full physics (`FULL_MODEL`), the gains of
    config/nodes_sim.yaml's arm_controller_node. Optionally without the rigid-body terms of (2) or
    the valve-lag lead; `model_factory(params)` replaces the tracker's own SegmentModel.
    """
    segment, plant, _ = load_segment()
    gains, control_every = controller_settings(segment)
    if not lead:
        gains = dataclasses.replace(gains, lead=0.0)
    model = with_rigid_body(segment, plant) if rigid_body and mode != 'none' else segment
    return simulate(model, plant, gains, mode, trajectory, FULL_MODEL, seed=seed,
                    control_every=control_every, setpoint_every=setpoint_every(),
                    duration=duration, physics=segment,
                    model=None if model_factory is None else model_factory(model))
