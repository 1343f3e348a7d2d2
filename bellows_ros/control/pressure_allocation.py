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
Pressure allocation: the chain pressures that give a segment a desired driving torque.

The inverse of paper A's driving-torque model τ_drive = τ_a + τ_s + τ_f (2, 29, 3, 5), and of the
previous model (34) for comparison, at the segment's present state: angle Ψ, velocity Ψ̇ (for the
friction term) and, for paper A's model, the chains' contact memory (Algorithm 1). The memory is
only peeked (`SegmentModel.peek`): evaluating a candidate leaves the model as it was, so the caller
keeps stepping it with the measured samples.

Two pressures, one torque: the pair is taken on the antagonistic path through a co-contraction
(base) pressure p_b the caller chooses,

    p_1(u) = clip(p_b + u, p0, p_max),   p_2(u) = clip(p_b - u, p0, p_max),
    u ∈ [-(p_max - p0), p_max - p0],

which runs from (p0, p_max) (chain 2 alone, most negative torque) through (p_b, p_b) to
(p_max, p0) (chain 1 alone, most positive torque). Along it the torque grows with u (chain 1 has
σ_1 = +1), so a bracketing search (regula falsi, Illinois variant) finds the u whose torque is
the desired one. A
desired torque outside [τ(u_min), τ(u_max)] gives the nearest end of the path, flagged saturated.

Paper A's model is continuous in the pressures except for the sampling of the strain profile
(28): s̃_a moves in steps of one sample, (l0 π/2)/Nλ·λ1, so the torque reached is the desired one
to within one such step of τ_a (≈ 0.05 N·m at full pressure with config/segment.yaml).
"""
from collections import namedtuple

Allocation = namedtuple('Allocation', 'p1 p2 tau saturated')
Allocation.__doc__ = ('Chain pressures (Pa abs), the model torque they give (N·m) and whether the '
                      'desired torque was outside the reachable range (then the nearest end).')

# The search stops when the bracket is narrower than U_TOL (Pa) or the torque is within TAU_TOL
# (N·m) of the desired one: 10 Pa moves the torque by about 2e-4 N·m at full pressure, below the
# model's own step in s_a (about 0.05 N·m, above). MAX_STEPS bounds the torque evaluations, each a
# `peek` of the strain memories; on this nearly linear path the Illinois steps need 3-6.
U_TOL = 10.0
TAU_TOL = 1e-3
MAX_STEPS = 30


def chain_pressures(params, u, p_base):
    """(p_1, p_2) on the antagonistic path at `u` (Pa) through base pressure `p_base` (Pa abs)."""
    p0, p_max = params.p0, params.p_max
    return (min(max(p_base + u, p0), p_max), min(max(p_base - u, p0), p_max))


def invert(torque, params, tau, p_base):
    """Allocation for `tau` (N·m) of `torque(p1, p2) -> N·m`, increasing along the path."""
    span = params.p_max - params.p0
    lo, hi = -span, span
    p_lo, p_hi = chain_pressures(params, lo, p_base), chain_pressures(params, hi, p_base)
    t_lo, t_hi = torque(*p_lo), torque(*p_hi)
    if tau <= t_lo:
        return Allocation(p_lo[0], p_lo[1], t_lo, tau < t_lo)
    if tau >= t_hi:
        return Allocation(p_hi[0], p_hi[1], t_hi, tau > t_hi)
    true_lo, true_hi = t_lo, t_hi  # t_lo, t_hi below are the Illinois rule's scaled values
    side = 0  # which end the last step moved: moving it again halves the other end's weight
    for _ in range(MAX_STEPS):
        if hi - lo < U_TOL:
            break
        mid = hi - (t_hi - tau) * (hi - lo) / (t_hi - t_lo) if t_hi > t_lo else 0.5 * (lo + hi)
        mid = min(max(mid, lo + 0.01 * (hi - lo)), hi - 0.01 * (hi - lo))
        p_mid = chain_pressures(params, mid, p_base)
        t_mid = torque(*p_mid)
        if abs(t_mid - tau) <= TAU_TOL:
            return Allocation(p_mid[0], p_mid[1], t_mid, False)
        if t_mid < tau:
            lo, p_lo, t_lo, true_lo = mid, p_mid, t_mid, t_mid
            if side == -1:
                t_hi = tau + 0.5 * (t_hi - tau)
            side = -1
        else:
            hi, p_hi, t_hi, true_hi = mid, p_mid, t_mid, t_mid
            if side == 1:
                t_lo = tau - 0.5 * (tau - t_lo)
            side = 1
    if tau - true_lo <= true_hi - tau:
        return Allocation(p_lo[0], p_lo[1], true_lo, False)
    return Allocation(p_hi[0], p_hi[1], true_hi, False)


def allocate_paper_a(model, psi, psi_dot, tau, p_base):
    """
    Pressures for driving torque `tau` with paper A's model (29, 3, 5; Algorithm 1 peeked).

    model: a `SegmentModel` stepped with the measured samples so far (not changed here);
    psi (rad), psi_dot (rad/s, friction (5)), tau (N·m), p_base (co-contraction, Pa abs).
    """
    def torque(p1, p2):
        return model.peek(psi, psi_dot, p1, p2).tau_drive
    return invert(torque, model.params, tau, p_base)


def allocate_previous(model, psi, psi_dot, tau, p_base):
    """Pressures for driving torque `tau` with the previous model (34): no contact memory."""
    def torque(p1, p2):
        return model.torques(psi, psi_dot, p1, p2, 0.0, 0.0)[4]
    return invert(torque, model.params, tau, p_base)
