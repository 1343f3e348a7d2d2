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
Ogden material of the bellows membrane (paper A, eqs. 11, 14, 15).

And the free-membrane strain (22).

The membrane is incompressible (λ1 λ2 λ3 = 1) with no transverse strain (λ2 = 1), so everything is
a function of the longitudinal stretch λ1 alone. Paper A uses N = 2 Ogden terms with μ_k > 0 and
γ_k > 2 (the convergence condition of Appendix B); the functions here take the two terms as scalars
because the solver sits in the 1 kHz loop (docs/equations.md, A(11)-A(15)).

Units: μ_k in N/m (membrane stress resultant per unit width), T in N/m, p_rel in Pa, R in m.
"""
import math


def energy(lam, mu, gamma):
    """
    Strain-energy density W(λ1) = Σ_k (μ_k/γ_k)(λ1^γk + λ1^-γk - 2), N/m (14).

    The paper writes the constant as -3 for the general case; with λ2 = 1 it is -2 so that
    W(1) = 0.
    """
    return sum(m / g * (lam ** g + lam ** -g - 2.0) for m, g in zip(mu, gamma))


def stress(lam, mu, gamma):
    """Membrane stress resultant T(λ1) = dW/dλ1 = Σ_k μ_k (λ1^(γk-1) - λ1^(-γk-1)), N/m (15b)."""
    return sum(m * (lam ** (g - 1.0) - lam ** (-g - 1.0)) for m, g in zip(mu, gamma))


def stress_slope(lam, mu, gamma):
    """dT/dλ1 = Σ_k μ_k ((γk-1) λ1^(γk-2) + (γk+1) λ1^(-γk-2)), N/m; used in (B2)."""
    return sum(m * ((g - 1.0) * lam ** (g - 2.0) + (g + 1.0) * lam ** (-g - 2.0))
               for m, g in zip(mu, gamma))


def free_strain(load, mu1, mu2, gamma1, gamma2, guess=1.0):
    """
    Stretch λ1 ≥ 1 of the free membrane: solve p_rel·R = T(λ1) (22); `load` = p_rel·R in N/m.

    T is strictly increasing on λ1 ≥ 1 for γ_k > 1 and T(1) = 0, so the root is unique; a load ≤ 0
    (vented or sucked chain) leaves the membrane unstretched, λ1 = 1 (see A(22)). NaN gives NaN.

    Solved for u = ln λ1 with expm1 so that λ1 - 1 keeps full relative precision for tiny loads:
    safeguarded Newton inside the bracket [0, u_hi] (a bisection step whenever Newton leaves it).
    u_hi comes from T(λ) ≥ μ_k(λ^(γk-1) - 1) for each k, which also keeps every exponential finite
    for any finite load. λ1 (and λ1 - 1) come out to ~1e-15 relative (tested against a 50-digit
    reference). `guess` (a previous λ1) only speeds it up.
    """
    if not load > 0.0:
        return math.nan if load != load else 1.0
    a1, b1, a2, b2 = gamma1 - 1.0, -gamma1 - 1.0, gamma2 - 1.0, -gamma2 - 1.0
    lo = 0.0
    hi = min(math.log1p(load / mu1) / a1, math.log1p(load / mu2) / a2)
    if guess > 1.0:
        u = math.log(guess)
    else:  # linearisation at λ = 1: T ≈ 2 Σ μ_k γ_k (λ - 1)
        u = load / (2.0 * (mu1 * gamma1 + mu2 * gamma2))
    if not lo < u < hi:
        u = 0.5 * hi
    expm1 = math.expm1
    for _ in range(200):
        e1, f1, e2, f2 = expm1(a1 * u), expm1(b1 * u), expm1(a2 * u), expm1(b2 * u)
        residual = mu1 * (e1 - f1) + mu2 * (e2 - f2) - load
        if residual > 0.0:
            hi = u
        else:
            lo = u
        slope = (mu1 * (a1 * (e1 + 1.0) - b1 * (f1 + 1.0))
                 + mu2 * (a2 * (e2 + 1.0) - b2 * (f2 + 1.0)))
        new = u - residual / slope
        if not lo <= new <= hi:
            new = 0.5 * (lo + hi)
        # Newton converges quadratically here (|error after the step| ≲ 3 γ Δu²), so a step below
        # 1e-8·u leaves an error far below 1e-15·u; the bracket test ends bisection runs.
        if abs(new - u) <= 1e-8 * new or hi - lo <= 1e-15 * hi:
            return math.exp(new)
        u = new
    return math.exp(u)
