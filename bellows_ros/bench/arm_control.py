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
The gain of model-based arm control, measured.

RMS angle error tracking one trajectory on the simulated segment with feedback only, with the
previous model (34) and with paper A's model.

In process and deterministic (`control.closed_loop`, seed 0): the segment plant with its default
effects (contact hysteresis, pressure friction, natural curvature; valve lag and sensor noise are
always on), Ψ̇ by backward differences of the measured angle as the driver makes it, commands at
the controller's rate held by the valves for the arm bus's set-point cycle (config/arm.dbc).
Trajectory: `angle_trajectory.REVERSALS` (reversals, holds, peak speeds 0.4-2.6 rad/s within
|Ψ| <= 0.9 rad). The same PID gains for all three (config/nodes_sim.yaml `arm_controller_node`,
tuned once for feedback only, docs/arm_control.md). The model-based controllers get the rigid-body
terms of (2), M and C, of the simulated segment (`segment.plant.inertia/damping`): what an arm's
`segment.dynamics` would hold; the quasi-static figure (M = C = 0, config/segment.yaml as shipped)
is reported beside it.

Figures (rad): `arm_control.rms.feedback_only`, `.previous_model`, `.paper_a_model` (ratio to
feedback only; target paper_a_model <= 0.5 x feedback_only and below previous_model), each with
the RMS over the trajectory's holds, its moves that continue the previous direction, and its
reversals (moves against the previous one: where the stored strain of the contact memory is
released and rebuilt).

Where the difference comes from (extras): the ablations `rms_no_lead` (no valve-lag lead),
`rms_quasi_static` (also M = C = 0) and, for paper A, `rms_no_contact_memory` (paper A's model
with a frictionless contact instead of the no-slip memory, `FrictionlessContact`); along the paper
A run, the previous model's torque error against paper A's (`torque_error_*`, on the previous
model's entry) and what the contact memory adds to paper A's torque (`memory_torque_*`).
"""
import numpy as np

from bellows_ros.bench import Result
from bellows_ros.config.segment import load_segment_params
from bellows_ros.control import angle_trajectory, closed_loop, effort
from bellows_ros.models.contact import contact_angle
from bellows_ros.models.segment import SegmentModel, SegmentOutput, simulate_model, strain_memory

MODES = (('feedback_only', 'none'), ('previous_model', 'previous'), ('paper_a_model', 'paper_a'))
TARGET_RATIO = 0.5
SEED = 0
EFFORT_UNITS = {'command_variation': 'Pa/s', 'air_used': 'NL/L', 'hold_chatter': 'Pa',
                'hold_chatter_worst': 'Pa'}


def effort_figures(run, holding):
    """
    Control effort of a run (`control.effort`): command variation Pa/s, air used NL per L of chain.

    Also the median and worst hold chatter, Pa. `holding`: bool per sample, set-point holding.
    """
    chatter, worst = effort.hold_chatter(run.t, holding, (run.p1_cmd, run.p2_cmd))
    return {'command_variation': effort.command_variation(run.t, run.p1_cmd, run.p2_cmd),
            'air_used': effort.air_used(run.p1, run.p2),
            'hold_chatter': chatter, 'hold_chatter_worst': worst}


def windows(run, trajectory, error=None):
    """
    Return the RMS of `error` (default: the angle error, rad) by motion kind.

    Over holds, same-direction moves and reversals.
    """
    error = run.psi_d - run.psi if error is None else error
    kinds = [angle_trajectory.phases(trajectory, t) for t in run.t.tolist()]
    pick = {'holds': [k == ('hold', None) for k in kinds],
            'moves': [k == ('move', False) for k in kinds],
            'reversals': [k == ('move', True) for k in kinds]}
    return {name: closed_loop.rms(error[mask]) for name, mask in pick.items()}


class FrictionlessContact:
    """
    Paper A's model without the contact memory: the stand-in for `SegmentModel` in the ablation.

    Paper A: for a frictionless contact the strain on the rib equals the free strain, λ_a = λ1
    (26 without the no-slip history). That is Algorithm 1's fixed point at constant (p, α) from
    an empty profile (Appendix B: it converges), so s̃_a is computed by iterating a fresh
    `StrainMemory` to convergence at every evaluation: the same equations, no history.
    """

    def __init__(self, params):
        self.params = params
        self._model = SegmentModel(params)
        self._scratch = strain_memory(params)

    def _contact(self, p_rel, alpha):
        memory = self._scratch
        memory.reset()
        s_a = memory.step(p_rel, alpha)
        for _ in range(200):
            previous, s_a = s_a, memory.step(p_rel, alpha)
            if abs(s_a - previous) < 1e-7:
                break
        return s_a

    def peek(self, psi, psi_dot, p1, p2):
        p0 = self.params.p0
        s1 = self._contact(p1 - p0, contact_angle(psi, 1.0))
        s2 = self._contact(p2 - p0, contact_angle(psi, -1.0))
        return SegmentOutput(s1, s2, *self._model.torques(psi, psi_dot, p1, p2, s1, s2))

    step = peek  # nothing to remember

    def torques(self, *args):
        return self._model.torques(*args)

    def reset(self):
        pass


def track(mode, trajectory, rigid_body=True, lead=True, memory=True, duration=None):
    """
    Run `closed_loop.track`, for paper A without its contact memory on request.

    The ablation puts `FrictionlessContact` in place of the no-slip memory.
    """
    return closed_loop.track(mode, trajectory, rigid_body=rigid_body, lead=lead, seed=SEED,
                             duration=duration,
                             model_factory=None if memory else FrictionlessContact)


def memory_torque(run, trajectory, every=10):
    """
    Return the RMS (N·m) over the windows of what the contact memory adds to paper A's torque.

    Along a run: τ_drive with the memory minus with the frictionless contact, every `every`-th
    sample of the true states.
    """
    segment = load_segment_params()
    model = SegmentModel(segment)
    frictionless = FrictionlessContact(segment)
    picked = range(0, len(run.t), every)
    rows = list(zip(run.psi.tolist(), run.psi_dot.tolist(), run.p1.tolist(), run.p2.tolist()))
    added = np.zeros(len(run.t))
    for k, row in enumerate(rows):
        with_memory = model.step(*row).tau_drive
        if k % every == 0:
            added[k] = with_memory - frictionless.peek(*row).tau_drive
    index = np.asarray(picked)
    sub = closed_loop.TrackingRun(*(np.asarray(a)[index] for a in run))
    return windows(sub, trajectory, added[index])


def short_trajectory():
    """Return the first moves of REVERSALS (out, reversal through Ψ = 0, back): the quick run."""
    return angle_trajectory.Trajectory(angle_trajectory.REVERSALS.start,
                                       angle_trajectory.REVERSALS.waypoints[:3])


def run(quick=False):
    trajectory = short_trajectory() if quick else angle_trajectory.REVERSALS
    results, reference = [], None
    for name, mode in MODES:
        tracked = track(mode, trajectory)
        result = Result(f'arm_control.rms.{name}', closed_loop.rms(tracked.psi_d - tracked.psi),
                        'rad', len(tracked.t))
        result.extra.update({f'rms_{k}': v for k, v in windows(tracked, trajectory).items()})
        result.extra['max_error'] = float(abs(tracked.psi_d - tracked.psi).max())
        result.extra['saturated_fraction'] = float(tracked.saturated.mean())
        result.extra_units['saturated_fraction'] = ''
        holding = [angle_trajectory.phases(trajectory, t) == ('hold', None)
                   for t in tracked.t.tolist()]
        result.extra.update(effort_figures(tracked, holding))
        result.extra_units.update(EFFORT_UNITS)
        if mode != 'none' and not quick:
            ablations = [('no_lead', {'lead': False}),
                         ('quasi_static', {'lead': False, 'rigid_body': False})]
            if mode == 'paper_a':
                ablations.append(('no_contact_memory', {'memory': False}))
            for label, options in ablations:
                other = track(mode, trajectory, **options)
                result.extra[f'rms_{label}'] = closed_loop.rms(other.psi_d - other.psi)
                if label == 'no_contact_memory':
                    for window, value in windows(other, trajectory).items():
                        result.extra[f'rms_{window}_no_contact_memory'] = value
        if reference is None:
            reference = result
        else:
            result.reference, result.ratio = reference.name, result.value / reference.value
        if mode == 'paper_a':
            result.target = TARGET_RATIO * reference.value
            # Where the previous model's inverse goes wrong: its torque against paper A's on the
            # true states of this run (the plant's physics is paper A's model, default effects).
            model = simulate_model(load_segment_params(), tracked.psi, tracked.p1, tracked.p2,
                                   tracked.psi_dot)
            miss = windows(tracked, trajectory, model['tau_prev'] - model['tau_drive'])
            previous = results[-1]
            for window, value in miss.items():
                previous.extra[f'torque_error_{window}'] = value
                previous.extra_units[f'torque_error_{window}'] = 'N·m'
            if not quick:
                for window, value in memory_torque(tracked, trajectory).items():
                    result.extra[f'memory_torque_{window}'] = value
                    result.extra_units[f'memory_torque_{window}'] = 'N·m'
        results.append(result)
    return results
