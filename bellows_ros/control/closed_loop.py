"""The arm controller closed around the simulated segment, in process (bench, scenario, tests).

Per 1 kHz sample, as on the graph: the plant (`SegmentPlant`, effects and noise as given) is
measured; Ψ̇ is the backward difference of the measured angles (what the driver publishes, the arm
has no velocity sensor); the tracker's model steps with the sample; every `control_every`-th
sample the tracker commands new pressures, which the plant's valves follow until the next command
(the driver holds set-points). Deterministic for a given seed.
"""
from collections import namedtuple

import numpy as np

from bellows_ros.control import angle_trajectory
from bellows_ros.control.angle_tracking import AngleTracker
from bellows_ros.models.segment_plant import SegmentPlant

TrackingRun = namedtuple('TrackingRun', 't psi_d psi p1_cmd p2_cmd saturated')
TrackingRun.__doc__ = ('Arrays per sample: time s, set-point and true angle rad, commanded '
                       'pressures Pa abs, whether the allocation saturated.')

DT = 1e-3


def simulate(params, gains, feedforward, trajectory, effects, seed=0, control_every=5,
             duration=None, noise=None):
    """Track `trajectory` on `SegmentPlant(params, effects, noise, seed)` -> TrackingRun."""
    total = angle_trajectory.duration(trajectory) if duration is None else duration
    steps = int(round(total / DT))
    plant = SegmentPlant(params, effects=effects, noise=noise, seed=seed, psi0=trajectory.start)
    tracker = AngleTracker(params, gains, feedforward)
    out = np.zeros((steps, 6))
    sample = plant.step(DT, params.p0, params.p0)
    last_psi, command = sample.psi, None
    for k in range(steps):
        t = k * DT
        psi_dot = (sample.psi - last_psi) / DT
        last_psi = sample.psi
        tracker.observe(sample.psi, psi_dot, sample.p1, sample.p2, DT)
        psi_d, psi_dot_d, psi_ddot_d = angle_trajectory.setpoint(trajectory, t)
        if k % control_every == 0:
            command = tracker.command(psi_d, psi_dot_d, psi_ddot_d, sample.psi,
                                      DT * control_every)
        out[k] = (t, psi_d, plant.psi, command.p1, command.p2, command.saturated)
        sample = plant.step(DT, command.p1, command.p2)
    return TrackingRun(*(out[:, i] for i in range(5)), out[:, 5].astype(bool))


def rms(values):
    """Root mean square, NaN for an empty selection."""
    values = np.asarray(values, float)
    return float(np.sqrt(np.mean(values * values))) if values.size else float('nan')
