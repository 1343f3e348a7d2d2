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
Angle tracking of one arm segment.

PID feedback plus model-based feedforward through the pressure allocation.

Paper A's equation of motion (2) for the free segment (τ_ext = 0) asks the bellows for the driving
torque τ_drive = M Ψ̈ + C Ψ̇ + N(Ψ). The controller asks for

    τ* = M Ψ̈_d + C Ψ̇_d + N(Ψ) + k_p e + k_i ∫e dt + k_d (Ψ̇_d − Ψ̇_f),   e = Ψ_d − Ψ,

(M, C, N: the model's `segment.dynamics`, quasi-static by default, so τ* is the PID term) and turns
τ* into the two chain pressures by inverting a torque model at the measured state
(`control.pressure_allocation`):

- `paper_a`: paper A's τ_drive (29, 3, 5) with the contact memory of Algorithm 1, from the
  tracker's own `SegmentModel`, stepped with every measured sample exactly as the model node does;
- `previous`: the previous model (34) (same restoring and friction terms, no contact memory);
- `none`: no model — feedback only: τ* / g0 is the pressure offset u of the antagonistic path,
  g0 the actuator's torque per pascal of u at the straight, vented segment (a constant).

The inversion at the measured Ψ cancels what the model knows of the torque's dependence on the
state (restoring torque, the actuator's growth with Ψ, the contact memory), so the feedback only
sees what the model gets wrong. The friction term (5) is evaluated at the desired velocity Ψ̇_d:
the measured Ψ̇ is a noisy difference of encoder angles, and tanh(c_vel Ψ̇) would chatter at holds.
Ψ̇_f is the measured velocity through a first-order low-pass (`velocity_cutoff`). The integrator is
clamped to ±`integral_limit` and holds while the allocation saturates (anti-windup).

The valves follow their set-points with a lag (first order, time constant ≈ `lead`), so a
feedforward pressure commanded now arrives late. The model-based modes therefore add to the
allocated pair the change of the pure feedforward pair (τ = M Ψ̈_d + C Ψ̇_d, at the desired angle,
same contact memory) between now and `lead` seconds ahead on the set-point, when the caller gives
the set-point there (`ahead`); 0 = no lead.
"""
from dataclasses import dataclass
import math

from bellows_ros.control.pressure_allocation import (allocate_paper_a, allocate_previous,
                                                     Allocation, chain_pressures)
from bellows_ros.errors import ParameterError
from bellows_ros.models.segment import SegmentModel

FEEDFORWARDS = ('paper_a', 'previous', 'none')


@dataclass(frozen=True)
class TrackingGains:
    """
    Gains and settings of the tracker.

    kp N·m/rad, ki N·m/(rad·s), kd N·m·s/rad, velocity_cutoff Hz, integral_limit N·m,
    base_pressure Pa abs (co-contraction of the antagonistic path), lead s (valve lag the
    feedforward anticipates).
    """

    kp: float
    ki: float
    kd: float
    velocity_cutoff: float
    integral_limit: float
    base_pressure: float
    lead: float = 0.0


def check_gains(gains, params, source='arm controller'):
    """Raise ParameterError naming the first inadmissible gain."""
    for name in ('kp', 'ki', 'kd', 'velocity_cutoff', 'integral_limit', 'lead'):
        value = getattr(gains, name)
        if not (math.isfinite(value) and value >= 0):
            raise ParameterError(f"{source}: parameter '{name}' must be finite and >= 0, "
                                 f'got {value}')
    if not params.p0 <= gains.base_pressure <= params.p_max:
        raise ParameterError(f"{source}: parameter 'base_pressure' must lie in [p0, p_max] = "
                             f'[{params.p0:.0f}, {params.p_max:.0f}] Pa, '
                             f'got {gains.base_pressure}')


def check_feedforward(name, source='arm controller'):
    if name not in FEEDFORWARDS:
        raise ParameterError(f"{source}: parameter 'feedforward' must be one of "
                             f"{', '.join(FEEDFORWARDS)}, got '{name}'")


def pressure_gain(model, p_base):
    """
    Return g0, N·m per Pa of u: the slope of the previous model's torque (34) at Ψ = 0, at rest.

    Taken from the base pressure over a tenth of the path each way (the feedback-only
    controller's only number).
    """
    p = model.params
    du = 0.1 * (p.p_max - p.p0)
    up = model.torques(0.0, 0.0, *chain_pressures(p, du, p_base), 0.0, 0.0)[4]
    down = model.torques(0.0, 0.0, *chain_pressures(p, -du, p_base), 0.0, 0.0)[4]
    return (up - down) / (2.0 * du)


class AngleTracker:
    """
    One segment's tracker. `observe` every measured sample; `command` at the control rate.

    params: SegmentParams (the model's); gains: TrackingGains; feedforward: one of FEEDFORWARDS.
    """

    def __init__(self, params, gains, feedforward):
        check_feedforward(feedforward)
        check_gains(gains, params)
        self.params, self.gains, self.feedforward = params, gains, feedforward
        self.model = SegmentModel(params)
        self.g0 = pressure_gain(self.model, gains.base_pressure)
        self.reset()

    def reset(self):
        self.model.reset()
        self.restart()

    def retune(self, gains, feedforward):
        """
        Take new gains and feedforward from the next command on (a live parameter change).

        The feedback state (integral, rate filter) and the model's contact memory are kept, so
        the command does not jump beyond what the new gains themselves change.
        """
        check_feedforward(feedforward)
        check_gains(gains, self.params)
        if gains.base_pressure != self.gains.base_pressure:
            self.g0 = pressure_gain(self.model, gains.base_pressure)  # torques(): no state
        self.gains, self.feedforward = gains, feedforward

    def restart(self):
        """
        Forget the feedback state (integral, velocity), keep the model's contact memory.

        After an interruption (the driver vented the arm) the integral no longer fits the segment.
        """
        self.integral = 0.0
        self.velocity = 0.0
        self.saturated = False

    def observe(self, psi, psi_dot, p1, p2, dt):
        """
        Take one measured sample (rad, rad/s, Pa abs, Pa abs; dt s since the previous one).

        The contact memory advances (Algorithm 1) and the velocity filter takes Ψ̇.
        """
        self.model.step(psi, psi_dot, p1, p2)
        if dt > 0.0:
            blend = 1.0 - math.exp(-2.0 * math.pi * self.gains.velocity_cutoff * dt)
            self.velocity += blend * (psi_dot - self.velocity)

    def command(self, psi_d, psi_dot_d, psi_ddot_d, psi, dt, ahead=None):
        """
        Return the pressure command for set-point (Ψ_d, Ψ̇_d, Ψ̈_d) at measured Ψ.

        dt s since the last command; `ahead`: the set-point `lead` s later, or None. Returns an
        `Allocation` (p1, p2 Pa abs, the torque asked for N·m, saturated).
        """
        g, p = self.gains, self.params
        error = psi_d - psi
        if not self.saturated:
            self.integral += g.ki * error * dt
            self.integral = max(-g.integral_limit, min(g.integral_limit, self.integral))
        feedback = g.kp * error + self.integral + g.kd * (psi_dot_d - self.velocity)
        if self.feedforward == 'none':
            span = p.p_max - p.p0
            u = feedback / self.g0
            p1, p2 = chain_pressures(p, max(-span, min(span, u)), g.base_pressure)
            self.saturated = abs(u) > span
            return Allocation(p1, p2, feedback, self.saturated)
        tau = (p.dynamics_inertia * psi_ddot_d + p.dynamics_damping * psi_dot_d
               + p.dynamics_gravity * math.sin(psi) + feedback)
        allocate = allocate_paper_a if self.feedforward == 'paper_a' else allocate_previous
        out = allocate(self.model, psi, psi_dot_d, tau, g.base_pressure)
        self.saturated = out.saturated
        if ahead is not None and g.lead > 0.0:
            now = self._feedforward(allocate, psi_d, psi_dot_d, psi_ddot_d)
            later = self._feedforward(allocate, *ahead)
            out = out._replace(p1=min(p.p_max, max(p.p0, out.p1 + later.p1 - now.p1)),
                               p2=min(p.p_max, max(p.p0, out.p2 + later.p2 - now.p2)))
        return out._replace(tau=tau)

    def _feedforward(self, allocate, psi_d, psi_dot_d, psi_ddot_d):
        """Return the set-point's own pair: (2)'s rigid-body torque at the desired state."""
        p = self.params
        tau = (p.dynamics_inertia * psi_ddot_d + p.dynamics_damping * psi_dot_d
               + p.dynamics_gravity * math.sin(psi_d))
        return allocate(self.model, psi_d, psi_dot_d, tau, self.gains.base_pressure)
