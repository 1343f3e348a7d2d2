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
Geometry, augmented volume and equivalent area of one bellows of paper B (equations 2-6, 10).

A bellows is n identical segments, each two conical frusta of opposite orientation (Table II). The
per-segment compression is Δh = h0 - h; the bellows' total compression is x = n Δh (positive =
compressed, negative = extended), as in docs/equations.md.

Every function here accepts Python floats or NumPy arrays alike (only `+ - * / **` are used), so
the fast scalar path of `actuator.evaluate` and the vectorised `evaluate_array` share one set of
equations.

The volume error E_V (5) is the paper's full cubic in (Δh, P), written in the dimensionless
variables d = Δh / h0 and q = (P - P_atm) / P_atm  **[choice: an affine change of variables
leaves the family of full cubics unchanged; it only keeps the 10 coefficients (m³) well scaled]**.
Coefficient order is the paper's: a00, a10, a01, a20, a11, a02, a30, a21, a12, a03.
"""
from dataclasses import dataclass
import math

P_ATM = 101325.0  # Pa, paper B's atmospheric pressure (8)

# Exponents (i of d, j of q) of the E_V terms, in the order of equation (5).
E_V_TERMS = ((0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2), (3, 0), (2, 1), (1, 2), (0, 3))


@dataclass(frozen=True)
class Bellows:
    """
    One bellows: Table II geometry (m), travel limits (m) and E_V coefficients (m³).

    r_big: R0, large radius at rest; r_small: r, small radius (constant, (2)); wall: t;
    h0: segment height at rest; n: number of segments; x_min/x_max: admissible total compression
    (extension limit / compression limit); e_v: the 10 coefficients of (5).
    """

    r_big: float
    r_small: float
    wall: float
    h0: float
    n: int
    x_min: float
    x_max: float
    e_v: tuple = (0.0,) * 10

    def __post_init__(self):
        # Derived constants, computed once: the hot path only multiplies.
        object.__setattr__(self, 'n', int(self.n))
        object.__setattr__(self, 'e_v', tuple(float(a) for a in self.e_v))
        object.__setattr__(self, '_a2', (self.r_big - self.r_small) ** 2)
        object.__setattr__(self, '_k', math.pi / 3.0)
        object.__setattr__(self, 'bulging', any(a != 0.0 for a in self.e_v))


def frustum_state(b, x):
    """
    Large radius R (3), its derivative dR/dΔh, and f = R² + r² + R r at compression x (m).

    (3): R(Δh) = sqrt((R0 - r)² - (Δh² - 2 h0 Δh)/4) + r.
    """
    dh = x / b.n
    s = (b._a2 - (dh * dh - 2.0 * b.h0 * dh) * 0.25) ** 0.5
    radius = s + b.r_small
    d_radius = (b.h0 - dh) / (4.0 * s)
    r = b.r_small
    return radius, d_radius, radius * radius + r * r + radius * r


def volume_geo(b, x, state=None):
    """
    Geometric volume V_geo (4), m³, of 2n frusta at total compression x (m).

    `state`: `frustum_state(b, x)` if the caller already has it (the fast path computes it once).
    """
    _, _, f = state or frustum_state(b, x)
    return b._k * b.n * (b.h0 - x / b.n) * f


def volume_geo_slope(b, x, state=None):
    """
    dV_geo/dx (m²): the exact derivative of (4) with respect to the total compression x.

    Negative while compressing shrinks the volume; it changes sign near full extension, where the
    radius R collapses towards r. `state` as in `volume_geo`.
    """
    radius, d_radius, f = state or frustum_state(b, x)
    return b._k * (-f + (b.h0 - x / b.n) * (2.0 * radius + b.r_small) * d_radius)


def area(b, x, p, state=None, error=None):
    """
    Equivalent area A = dV/d(nh) (10), m², and its partial derivatives ∂A/∂x (m), ∂A/∂P (m²/Pa).

    A = π/3 (R² + r² + R r) + dE_V/d(nh); [choice] dE_V/d(nh) = -∂E_V/∂x, since
    x = nΔh = -(nh - nh0). `state` as in `volume_geo`; `error`: `e_v(b, x, p)` if the caller
    already has it. Floats or arrays.
    """
    radius, d_radius, f = state or frustum_state(b, x)
    value = b._k * f
    d_x = b._k * (2.0 * radius + b.r_small) * d_radius / b.n
    if not b.bulging:
        return value, d_x, 0.0
    _, e_x, _, e_xx, e_xp = error or e_v(b, x, p)
    return value - e_x, d_x - e_xx, -e_xp


def e_v(b, x, p):
    """
    E_V (5), m³, and its partial derivatives: (E, ∂E/∂x, ∂E/∂P, ∂²E/∂x², ∂²E/∂x∂P).

    Derivatives are in SI (per m of total compression, per Pa).
    """
    a00, a10, a01, a20, a11, a02, a30, a21, a12, a03 = b.e_v
    d = x / (b.n * b.h0)
    q = (p - P_ATM) / P_ATM
    value = (a00 + d * (a10 + d * (a20 + d * a30)) + q * (a01 + q * (a02 + q * a03))
             + d * q * (a11 + a21 * d + a12 * q))
    e_d = a10 + d * (2.0 * a20 + 3.0 * a30 * d) + q * (a11 + 2.0 * a21 * d + a12 * q)
    e_q = a01 + q * (2.0 * a02 + 3.0 * a03 * q) + d * (a11 + a21 * d + 2.0 * a12 * q)
    e_dd = 2.0 * a20 + 6.0 * a30 * d + 2.0 * a21 * q
    e_dq = a11 + 2.0 * a21 * d + 2.0 * a12 * q
    sx = 1.0 / (b.n * b.h0)
    sp = 1.0 / P_ATM
    return value, e_d * sx, e_q * sp, e_dd * sx * sx, e_dq * sx * sp


def e_v_in_q(b, x):
    """
    E_V (5) at fixed x as a cubic in q = (P - P_atm)/P_atm: coefficients (c0, c1, c2, c3), m³.

    The gas-law Newton iteration (17) varies only P, so it evaluates this cubic and not (5) in
    full.
    """
    a00, a10, a01, a20, a11, a02, a30, a21, a12, a03 = b.e_v
    d = x / (b.n * b.h0)
    return (a00 + d * (a10 + d * (a20 + d * a30)), a01 + d * (a11 + d * a21), a02 + d * a12, a03)


def e_v_regressors(b, x, p):
    """Return the 10 monomials d^i q^j of (5) at (x, P) in coefficient order: E_V = Σ a_k m_k."""
    d = x / (b.n * b.h0)
    q = (p - P_ATM) / P_ATM
    return [d ** i * q ** j for i, j in E_V_TERMS]


def volume(b, x, p):
    """Augmented volume V = V_geo + E_V (6), m³."""
    if not b.bulging:
        return volume_geo(b, x)
    return volume_geo(b, x) + e_v(b, x, p)[0]
