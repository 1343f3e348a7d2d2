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
Two-dimensional no-slip membrane contact between a bellows and its rib.

Paper A, eqs. 13, 20-28, Algorithm 1 of Appendix A.

The material lying on the rib keeps the stretch it had when it touched down (no slip); only the
free arc follows the current pressure and joint angle. That memory is why the same (p, Ψ) reached
along two paths gives two contact lengths s̃_a and two actuator torques (the hysteresis of paper A,
Fig. 10/11).

Geometry of one chain (docs/equations.md, A(20)-A(28)), lengths in m, angles in rad:
    α = -½ σ_j ψ_4 with ψ_4 = Ψ/4 (13; [choice] sign and equal joints)
    R = l0 + (s0 + s̃_a) tan α (20),   β = π/2 + α (21)
    a = 1 - R β / (λ1 l0 π/2) (23-25), clamped to [0, 1)
"""
import math

from bellows_ros.models.ogden import free_strain

HALF_PI = 0.5 * math.pi
# dα_1/dΨ of (13): α_j = -½ σ_j ψ_4 with ψ_4 = Ψ/4 ([choice]: equal joints, sign from Fig. 10).
# A constant so that the 1 kHz `SegmentModel.step` can use it without a call.
ALPHA_PER_PSI = -0.125


def contact_angle(psi, sign):
    """α_j = -½ σ_j ψ_4 with ψ_4 = Ψ/4 (13; [choice]: equal joints, sign from Fig. 10), rad."""
    return ALPHA_PER_PSI * sign * psi


class StrainMemory:
    """
    State of Algorithm 1 for one bellows chain: the sampled strain profile λ_s on the rib.

    Parameters: l0, s0 (m), sa_max (m, rib size: s̃_a is clamped to [0, sa_max]), n_lambda (samples
    of the profile over ā ∈ [0, 1]), Ogden mu (N/m) and gamma (two terms each, γ_k > 2), and the
    material's `ogden.StretchTable` for λ1 of (22) (None: the Newton solve `free_strain`).

    The contact always covers a prefix of the profile (samples beyond n are released), so the state
    is the prefix length `n`, the stored values, and their running sum `total` (kept instead of
    re-summing the profile every step; re-summed exactly whenever the contact empties or every
    65536 steps so rounding cannot drift).
    """

    RESUM_EVERY = 65536

    def __init__(self, l0, s0, sa_max, n_lambda, mu, gamma, table=None):
        self.l0, self.s0, self.sa_max = float(l0), float(s0), float(sa_max)
        self.n_lambda = int(n_lambda)
        self.length0 = l0 * HALF_PI  # undeformed length of the bellows section, l0 π/2 (23)
        self.sample_length = self.length0 / self.n_lambda  # (l0 π/2)/Nλ of (28)
        (self.mu1, self.mu2), (self.gamma1, self.gamma2) = mu, gamma
        # λ1 of (22): the material's `StretchTable` (to its tested bound, no solve), or None for
        # the Newton solve `free_strain` warm-started from the last λ1 (to ~1e-15).
        self.table = table
        self.profile = [0.0] * self.n_lambda
        self.reset()

    def reset(self):
        """Reset to the initial state of Algorithm 1: empty profile (a = 0, n = 0), λ1 = 1."""
        # in place: `models.segment._fused_step` keeps a reference to this list
        self.profile[:] = [0.0] * self.n_lambda
        self.n = 0
        self.total = 0.0
        self.lam1 = 1.0
        self.s_a = 0.0  # always the clamped sample_length·total (28): step 1 reads it
        self._steps = 0

    def _stretch(self, load):
        if self.table is not None:
            return self.table(load)
        return free_strain(load, self.mu1, self.mu2, self.gamma1, self.gamma2, self.lam1)

    def _touchdown(self, p_rel, alpha):
        """Run steps 1-4 of Algorithm 1 from the stored state: (λ1, a, n), nothing changed."""
        # The fused two-chain step of `bellows_ros.models.segment` repeats these lines (and those
        # of `step`) with the same operations in the same order, so both give the same bits.
        radius = self.l0 + (self.s0 + self.s_a) * math.tan(alpha)
        lam1 = self._stretch(p_rel * radius)
        a = 1.0 - radius * (HALF_PI + alpha) / (lam1 * self.length0)
        a = 0.0 if a < 0.0 else (a if a < 1.0 else 1.0 - 1e-12)
        return lam1, a, math.ceil(a * self.n_lambda)

    def step(self, p_rel, alpha):
        """
        Run one iteration of Algorithm 1 at relative pressure `p_rel` (Pa), contact angle `alpha`.

        `alpha` in rad; returns the contact length s̃_a (m) after the update.

        1. s̃_a from the stored profile (28), clamped to [0, sa_max]; 2. R, β (20, 21);
        3. λ1 of the free membrane (22); 4. a (25) and n = ceil(a Nλ) ([choice], 0-based);
        5. release samples beyond n, give λ1 to empty samples ≤ n and to sample n (continuity, 26);
        then s̃_a again from the updated profile (28). One iteration per time step (Appendix A/B).
        """
        lam1, a, n = self._touchdown(p_rel, alpha)
        profile, old = self.profile, self.n
        if n < old:
            if n == 0:
                self.total = 0.0
            else:
                self.total -= math.fsum(profile[n:old])
            profile[n:old] = [0.0] * (old - n)
        elif n > old:
            profile[old:n] = [lam1] * (n - old)
            self.total += (n - old) * lam1
        if n > 0:  # the transition point carries the free strain (26)
            self.total += lam1 - profile[n - 1]
            profile[n - 1] = lam1
        self.n, self.lam1 = n, lam1
        self._steps += 1
        if self._steps >= self.RESUM_EVERY:
            self._steps = 0
            self.total = math.fsum(profile[:n])
        s_a = self.sample_length * self.total
        s_a = 0.0 if s_a < 0.0 else (self.sa_max if s_a > self.sa_max else s_a)
        self.s_a = s_a
        return s_a

    def peek(self, p_rel, alpha):
        """
        Return the s̃_a (m) that `step(p_rel, alpha)` would return, leaving the state untouched.

        For evaluating candidate pressures (the pressure allocation): the same update as `step`,
        summed instead of stored, O(samples released) like `step`.
        """
        lam1, _, n = self._touchdown(p_rel, alpha)
        profile, old = self.profile, self.n
        if n < old:
            total = 0.0 if n == 0 else self.total - math.fsum(profile[n:old])
        else:
            total = self.total + (n - old) * lam1
        if 0 < n <= old:  # the transition point carries the free strain (26)
            total += lam1 - profile[n - 1]
        s_a = self.sample_length * total
        return 0.0 if s_a < 0.0 else (self.sa_max if s_a > self.sa_max else s_a)
