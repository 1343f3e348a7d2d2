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


# Grid step of `StretchTable` in x = ln(1 + load/(μ1 + μ2)). The quintic Hermite error falls as
# h⁶. Over materials drawn across config/ranges.py, 0.005 gave at most ~5e-15 relative error in λ1
# (0.01 gave up to ~3e-13, where a stiff small-μ term with γ ≈ 17 takes over sharply), so
# `STRETCH_TABLE_ERROR` holds with margin. At most ~2900 cells (x ≤ 14.5 for the largest load and
# the smallest μ).
STRETCH_TABLE_SPACING = 0.005
# Bound on |λ_table - λ1| / λ1 over the documented ranges, held by
# test/test_models_ogden.py::test_stretch_table_error_bound_over_the_parameter_ranges.
STRETCH_TABLE_ERROR = 1e-13


class StretchTable:
    """
    λ1(load) of the free membrane (22) tabulated for one material: `free_strain` without a solve.

    For the 1 kHz strain memory (Algorithm 1), where the Newton solve of `free_strain` was most of
    the cost. λ1 is a smooth function of x = ln(1 + load/S), S = μ1 + μ2 (N/m): linear in x for
    small loads (λ1 - 1 ≈ load / 2Σμ_kγ_k) and again for large ones (λ1^(γ-1) ≈ load/μ). It is
    stored on a uniform grid in x from 0 to x(`load_max`) as quintic Hermite cells (value, first
    and second derivative at both ends, exact: the node values come from `free_strain` and the
    derivatives from T' and T'' of (15b), B2), so one lookup is a log1p, an index and a degree-5
    polynomial. Relative error of λ1 ≤ `STRETCH_TABLE_ERROR` over the ranges of config/ranges.py
    (tested). Loads above `load_max` (N/m) or NaN go to `free_strain`; loads ≤ 0 give λ1 = 1 like
    it. The cells are plain floats (NumPy scalars would make the lookup several times dearer).
    """

    def __init__(self, mu, gamma, load_max, spacing=STRETCH_TABLE_SPACING):
        import numpy as np  # only to build the table; the lookup is plain Python
        (mu1, mu2), (gamma1, gamma2) = mu, gamma
        self.material = (float(mu1), float(mu2), float(gamma1), float(gamma2))
        scale = mu1 + mu2
        self.load_max = float(load_max)
        self.inv_scale, self.inv_spacing = 1.0 / scale, 1.0 / spacing
        self.count = int(math.ceil(math.log1p(max(load_max, 0.0) / scale) / spacing)) + 1
        x = np.arange(self.count + 1) * spacing
        load = scale * np.expm1(x)
        lam = np.array([1.0] + [free_strain(v, *self.material) for v in load[1:].tolist()])
        # u = ln λ1 solves T(u) = load(x) = S (e^x - 1): u' = (load + S)/T_u, u'' = (load + S -
        # T_uu u'²)/T_u, with T_u, T_uu the u-derivatives of (15b); then λ' = λ u',
        # λ'' = λ (u'' + u'²). In units of the cell (t = 0..1): times h and h².
        u = np.log(lam)
        t_u = t_uu = 0.0
        for m, g in ((mu1, gamma1), (mu2, gamma2)):
            a, b = g - 1.0, -g - 1.0
            t_u = t_u + m * (a * np.exp(a * u) - b * np.exp(b * u))
            t_uu = t_uu + m * (a * a * np.exp(a * u) - b * b * np.exp(b * u))
        du = (load + scale) / t_u
        ddu = (load + scale - t_uu * du * du) / t_u
        d = lam * du * spacing
        s = lam * (ddu + du * du) * spacing * spacing
        y0, y1, d0, d1, s0, s1 = lam[:-1], lam[1:], d[:-1], d[1:], s[:-1], s[1:]
        dy = y1 - y0
        # quintic Hermite on t ∈ [0, 1]: p = y0 + d0 t + s0/2 t² + c3 t³ + c4 t⁴ + c5 t⁵
        c3 = 10.0 * dy - 6.0 * d0 - 4.0 * d1 - 1.5 * s0 + 0.5 * s1
        c4 = -15.0 * dy + 8.0 * d0 + 7.0 * d1 + 1.5 * s0 - s1
        c5 = 6.0 * dy - 3.0 * d0 - 3.0 * d1 - 0.5 * s0 + 0.5 * s1
        # each cell starts with its own x/h as a float: x - x0 is a float subtraction (a float
        # minus the int index is dearer in CPython), and floor() is a cheaper int than int()
        self.cells = [tuple(row) for row in np.column_stack(
            [np.arange(self.count, dtype=float), y0, d0, 0.5 * s0, c3, c4, c5]).tolist()]

    def __call__(self, load):
        """Return λ1 ≥ 1 for `load` = p_rel·R (N/m); as `free_strain`, to STRETCH_TABLE_ERROR."""
        # `bellows_ros.models.segment` inlines these lines in the fused step: keep them alike.
        if load > 0.0:
            x = math.log1p(load * self.inv_scale) * self.inv_spacing
            if x < self.count:  # (before floor(): x may be inf)
                x0, c0, c1, c2, c3, c4, c5 = self.cells[math.floor(x)]
                t = x - x0
                return c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * c5))))
            return free_strain(load, *self.material)
        return 1.0 if load == load else load
