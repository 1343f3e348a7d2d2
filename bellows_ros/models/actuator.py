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
Paper B's dual-bellows tunable-stiffness actuator: gas, force and stiffness (equations 1-17).

Two bellows, the air chamber (c) and the spring (s), share one sealed gas through a tube. Given the
chamber compression x_c and the spring compression x_s (m, positive = compressed), the pressure P
is the root of the isothermal gas law (17) with volumes that depend on P through E_V (14, 15):

    P (V_c(x_c, P) + V_s(x_s, P) + V_tube) = N,

where N (Pa·m³) is the amount of gas. The amount is given as `p_ref`: the pressure the same gas
would have at the design point (x_c = x_c_ref = 20 mm, x_s = 0); nominally atmospheric, as in the
paper's design. A leak or a temperature change shows up as a different `p_ref` (see
`estimate_gas`).

The spring force is F = F_air + F_mat + F_buckle (7) with F_air = (P - P_atm) A (9, 10),
F_mat = F_MTS(x_s) + E_F(Δh_s, P) (11, 12) and F_buckle <= 0 the force the spring loses when it
buckles under pressure and compression (`buckling_force`; paper B names buckling as where (7)-(12)
fail, sections III-C and IV-D, but gives it no equation); the stiffness K = dF/dx_s (13) is the
exact total derivative (P moves with x_s), not a finite difference.

`evaluate` is the fast scalar path (floats, `math`); `evaluate_array` runs the same equations on
NumPy arrays (a vectorised Newton on P).
"""
import dataclasses
from dataclasses import dataclass
import math

import numpy as np

from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator_geometry import (area, Bellows, e_v, e_v_in_q, frustum_state,
                                                  P_ATM, volume, volume_geo, volume_geo_slope)

_NEWTON_TOL = 1e-6   # Pa
_NEWTON_MAX = 30


@dataclass(frozen=True)
class Buckling:
    """
    The spring's buckling under pressure and compression (`buckling_force`), SI units.

    stiffness_loss: k_b, N/m, stiffness lost once buckled; critical_pressure: p_cr, Pa gauge, the
    pressure at which the free spring would buckle; critical_compression: x_cr, m, the compression
    at which the unpressurised spring would buckle; onset_width: δ, the smoothness of the onset
    (fraction of the critical load); bounds: ((name, (low, high)), ...) the physical range of each.
    """

    stiffness_loss: float
    critical_pressure: float
    critical_compression: float
    onset_width: float
    bounds: tuple = ()

    NAMES = ('stiffness_loss', 'critical_pressure', 'critical_compression', 'onset_width')

    def __post_init__(self):
        bounds = dict(self.bounds)
        for name in self.NAMES:
            value = float(getattr(self, name))
            object.__setattr__(self, name, value)
            low, high = bounds.get(name, (-math.inf, math.inf))
            if not (math.isfinite(value) and low <= value <= high):
                raise ParameterError(f"parameter 'actuator.buckling.{name}': {value:g} is outside "
                                     f'its physical range [{low:g}, {high:g}]')
        if min(self.critical_pressure, self.critical_compression, self.onset_width) <= 0.0:
            raise ParameterError("parameter 'actuator.buckling.critical_pressure' (and "
                                 'critical_compression, onset_width) must be > 0')

    def bound(self, name):
        """(low, high) of parameter `name`."""
        return dict(self.bounds)[name]


NO_BUCKLING = None  # `ActuatorParams.buckling` of an actuator whose spring does not buckle


@dataclass(frozen=True)
class ActuatorParams:
    """
    The model's parameters of `config/actuator.yaml` (section `actuator.`), SI units.

    chamber, spring: `Bellows` (Table II, E_V); p_ref: gas amount as the design-point pressure, Pa;
    x_c_ref: design-point chamber compression, m; v_tube: tube volume, m³ (17);
    f_mts: F_MTS(x) = Σ f_mts[i] x^(i+1), N (unpressurised spring curve); e_f: C1..C4 of (11);
    x_s_low, x_s_high: spring range of the paper's average-slope stiffness (0-12 mm);
    buckling: `Buckling` of the spring (None, or stiffness_loss 0: the spring does not buckle).
    The simulated actuator's drive, sensors and effects are `actuator_plant.ActuatorPlantParams`;
    the config layer (`bellows_ros.config.actuator`) builds both from the one file.
    """

    chamber: Bellows
    spring: Bellows
    p_ref: float
    x_c_ref: float
    v_tube: float
    f_mts: tuple
    e_f: tuple
    x_s_low: float
    x_s_high: float
    buckling: Buckling = NO_BUCKLING

    def __post_init__(self):
        if len(self.e_f) != 4:
            raise ParameterError("parameter 'actuator.force.e_f': expected 4 coefficients "
                                 f'C1..C4, got {len(self.e_f)}')
        if not self.f_mts:
            raise ParameterError("parameter 'actuator.force.f_mts': expected at least one "
                                 'coefficient')
        for bellows, name in ((self.chamber, 'air_chamber'), (self.spring, 'spring')):
            if len(bellows.e_v) != 10:
                raise ParameterError(f"parameter 'actuator.{name}.e_v': expected 10 "
                                     f'coefficients, got {len(bellows.e_v)}')
        object.__setattr__(self, '_gas_nominal', gas_amount(self, self.p_ref))


def without_bulging(params):
    """Return the actuator with the purely geometric volume (E_V = 0): the doctor's baseline."""
    return scaled_bulging(params, 0.0)


def without_buckling(params):
    """Return the actuator with a spring that does not buckle: (7)-(12) only, as in the paper."""
    return scaled_buckling(params, 0.0)


def scaled_buckling(params, scale):
    """Return the same actuator with the buckling's stiffness loss multiplied by `scale`."""
    if params.buckling is NO_BUCKLING:
        return params
    return dataclasses.replace(params, buckling=dataclasses.replace(
        params.buckling, stiffness_loss=scale * params.buckling.stiffness_loss, bounds=()))


def scaled_bulging(params, scale):
    """Return the same actuator with both E_V polynomials multiplied by `scale`."""
    return dataclasses.replace(
        params,
        chamber=dataclasses.replace(params.chamber,
                                    e_v=tuple(scale * a for a in params.chamber.e_v)),
        spring=dataclasses.replace(params.spring, e_v=tuple(scale * a for a in params.spring.e_v)))


# --- gas (1, 16, 17) -----------------------------------------------------------------------------

def total_volume(params, x_c, x_s, p):
    """V_c(x_c, P) + V_s(x_s, P) + V_tube, m³ (17)."""
    return volume(params.chamber, x_c, p) + volume(params.spring, x_s, p) + params.v_tube


def gas_amount(params, p_ref):
    """N = P·V (Pa·m³) of the gas whose design-point pressure is `p_ref`."""
    return p_ref * total_volume(params, params.x_c_ref, 0.0, p_ref)


def _gas(params, gas):
    return params._gas_nominal if gas is None else gas_amount(params, gas)


def pressure(params, x_c, x_s, gas=None, v_geo=None):
    """
    System pressure P (Pa) at (x_c, x_s): the root of (17), floats or arrays.

    `v_geo`: the geometric total volume V_c + V_s + V_tube (m³), if the caller already has it.
    """
    return pressure_of_amount(params, x_c, x_s, _gas(params, gas), v_geo)


def pressure_of_amount(params, x_c, x_s, amount, v_geo=None):
    """
    System pressure P (Pa) of the gas amount N = `amount` (Pa·m³): the root of (17).

    For a caller that holds N itself (the doctor's leak and heating); `v_geo` as in `pressure`.
    """
    return _solve_pressure(params, x_c, x_s, amount, v_geo)[0]


def _solve_pressure(params, x_c, x_s, amount, v_geo=None):
    """
    Newton on g(P) = P·V(P) - N; returns P and g'(P) = V + P ∂V/∂P (needed for dP/dx).

    `v_geo` (the geometric total volume) may be passed when the caller already has it.
    """
    c, s = params.chamber, params.spring
    if v_geo is None:
        v_geo = volume_geo(c, x_c) + volume_geo(s, x_s) + params.v_tube
    p = amount / v_geo   # exact when E_V = 0, the starting point otherwise
    if not (c.bulging or s.bulging):
        return p, v_geo
    # Both E_V polynomials as one cubic in q: V(P) = v0 + b1 q + b2 q² + b3 q³.
    c0, c1, c2, c3 = e_v_in_q(c, x_c)
    s0, s1, s2, s3 = e_v_in_q(s, x_s)
    v0, b1, b2, b3 = v_geo + c0 + s0, c1 + s1, c2 + s2, c3 + s3
    scalar = isinstance(p, float)
    for _ in range(_NEWTON_MAX):
        q = (p - P_ATM) / P_ATM
        v = v0 + q * (b1 + q * (b2 + q * b3))
        slope = v + p * (b1 + q * (2.0 * b2 + 3.0 * b3 * q)) / P_ATM
        step = (p * v - amount) / slope
        p = p - step
        size = abs(step) if scalar else float(np.max(np.abs(step)))
        if size < _NEWTON_TOL:
            break
    else:
        raise ParameterError('actuator: the gas law (17) has no positive pressure root for these '
                             'parameters (check actuator.*.e_v and actuator.gas.v_tube)')
    # `slope` is g'(P) at the previous iterate; after convergence the difference is < 1e-12.
    return p, slope


def estimate_gas(params, p_measured, x_c, x_s):
    """
    Gas amount as `p_ref` (Pa) from a measured pressure at (x_c, x_s).

    The stiffness controller uses this to correct for a slow leak or a temperature change: the
    measured P with (17) gives N = P·V(x_c, x_s, P), and `p_ref` is the design-point pressure of N.
    """
    return p_ref_of_amount(params, p_measured * total_volume(params, x_c, x_s, p_measured))


def p_ref_of_amount(params, amount):
    """
    Return the design-point pressure p_ref (Pa) of the gas amount N (Pa·m³).

    (17) solved at the design point.
    """
    if isinstance(amount, np.ndarray):
        x_c = np.full(amount.shape, params.x_c_ref)
        return _solve_pressure(params, x_c, np.zeros(amount.shape), amount)[0]
    return _solve_pressure(params, params.x_c_ref, 0.0, float(amount))[0]


# --- force and stiffness (7-13)
# -------------------------------------------------------------------

def evaluate(params, x_c, x_s, gas=None):
    """
    Pressure P (Pa), spring force F (N) and stiffness K = dF/dx_s (N/m) at one (x_c, x_s).

    The fast scalar path: floats in, floats out. `gas` is the gas amount as `p_ref` (Pa), default
    `params.p_ref`.
    """
    return forward(params, float(x_c), float(x_s), _gas(params, gas), math.exp)


def evaluate_array(params, x_c, x_s, gas=None):
    """
    `evaluate` over arrays (broadcast); returns three float arrays (P, F, K).

    `gas` may be a scalar or an array of `p_ref` values (e.g. a leak over a record).
    """
    x_c = np.asarray(x_c, dtype=float)
    x_s = np.asarray(x_s, dtype=float)
    if gas is None:
        amount = params._gas_nominal
    else:
        amount = gas_amount(params, np.asarray(gas, dtype=float))
    x_c, x_s = np.broadcast_arrays(x_c, x_s)
    return forward(params, x_c, x_s, amount, np.exp)


def forward(params, x_c, x_s, amount, exp=math.exp):
    """
    (P, F, K) at gas amount N = `amount` (Pa·m³): the gas law (17), force (7)-(12), K (13).

    What `evaluate` and `evaluate_array` compute, for a caller that holds N itself (the plant,
    whose N changes with a leak and the gas temperature). Floats with `math.exp`, arrays with
    `np.exp`.
    """
    s = params.spring
    state = frustum_state(s, x_s)
    v_geo = volume_geo(params.chamber, x_c) + volume_geo(s, x_s, state) + params.v_tube
    p, g_slope = _solve_pressure(params, x_c, x_s, amount, v_geo)
    error = e_v(s, x_s, p) if s.bulging else None
    dv_dx = volume_geo_slope(s, x_s, state)             # exact dV_s/dx_s (4)-(6) for the gas law
    if error:
        dv_dx = dv_dx + error[1]
    dp_dx = -p * dv_dx / g_slope                        # implicit differentiation of (17)
    force, stiffness = spring_force(params, x_s, p, dp_dx, exp, area(s, x_s, p, state, error))
    return p, force, stiffness


def spring_force(params, x_s, p, dp_dx=0.0, exp=math.exp, spring_area=None):
    """
    Spring force F (7), N, at (x_s, P), and its total derivative dF/dx_s (N/m) at dP/dx_s = dp_dx.

    F = F_air (9) + F_MTS + E_F (12, 11) + F_buckle (`buckling_force`, when the parameters have
    it). `spring_area`: `actuator_geometry.area(params.spring, x_s, p)` if the caller has it.
    """
    air, stiffness = air_force(params, x_s, p, dp_dx, spring_area)
    f_mts, k_mts = material_force(params.f_mts, x_s)
    e_f, e_f_x, e_f_p = force_error(params.e_f, params.spring.n, x_s, p, exp)
    force = air + f_mts + e_f                           # (7), (12)
    stiffness = stiffness + k_mts + e_f_x + e_f_p * dp_dx
    if params.buckling is not NO_BUCKLING and params.buckling.stiffness_loss:
        f_b, f_b_x, f_b_p = buckling_force(params.buckling, x_s, p, exp)
        force = force + f_b
        stiffness = stiffness + f_b_x + f_b_p * dp_dx
    return force, stiffness


def air_force(params, x_s, p, dp_dx=0.0, spring_area=None):
    """
    F_air = (P - P_atm) A (9), N, and its total derivative along x_s (N/m) at dP/dx_s = dp_dx.

    A: the spring's equivalent area (10), `actuator_geometry.area`. Floats or arrays.
    """
    value, d_x, d_p = spring_area or area(params.spring, x_s, p)
    gauge = p - P_ATM
    return gauge * value, dp_dx * value + gauge * (d_x + d_p * dp_dx)


def material_force(f_mts, x_s):
    """
    F_MTS(x_s) = Σ_i f_i x_s^(i+1), N, and its slope (N/m): the unpressurised spring (12).

    [choice] A polynomial fitted to the unpressurised spring stands for paper B's FEA curve.
    `material_terms` gives its monomials for fitting.
    """
    power, value, slope = 1.0, 0.0, 0.0
    for i, coefficient in enumerate(f_mts):
        slope = slope + (i + 1) * coefficient * power
        power = power * x_s
        value = value + coefficient * power
    return value, slope


def material_terms(x_s, degree):
    """Return the monomials x_s^(i+1), i < degree, of F_MTS (`material_force`) as columns."""
    return [x_s ** (i + 1) for i in range(degree)]


def force_error(e_f, n, x_s, p, exp=math.exp):
    """
    E_F = C1 exp(C2 P + C3 Δh + C4) (11), N, with ∂E_F/∂x_s (N/m) and ∂E_F/∂P (N/Pa).

    `e_f`: (C1, C2, C3, C4); n: the spring's segment count (Δh = x_s/n). With
    (1, C2, C3, -C2 P_atm) it is the shape exp(C2 (P - P_atm) + C3 Δh) the fits scale by C1.
    """
    c1, c2, c3, c4 = e_f
    value = c1 * exp(c2 * p + c3 * x_s / n + c4)
    return value, value * c3 / n, value * c2


def buckling_force(b, x_s, p, exp=math.exp):
    """
    Force the buckled spring loses, F_b <= 0 (N), and ∂F_b/∂x_s (N/m), ∂F_b/∂P (N/Pa).

    [choice: paper B sees buckling "under high pressure and compression" but gives no model.]
    A pressurised bellows column buckles when its load index λ = x_s/x_cr + (P - P_atm)/p_cr
    reaches 1: compression and internal pressure both load the walls, so the onset compression
    x_cr (1 - (P - P_atm)/p_cr) falls as the pressure rises. Past the onset the spring loses the
    stiffness k_b; the onset is smoothed over a fraction δ of the critical load:

        F_b = -k_b x_cr δ softplus((λ - 1)/δ),   softplus(z) = ln(1 + e^z).

    Below the onset F_b vanishes (relative size e^(-1/δ)); far above it
    F_b = -k_b (x_s - x_onset(P)).
    Floats or arrays (`exp` is `math.exp` or `np.exp`).
    """
    k_b, p_cr = b.stiffness_loss, b.critical_pressure
    x_cr, width = b.critical_compression, b.onset_width
    z = ((x_s / x_cr + (p - P_ATM) / p_cr) - 1.0) / width
    if exp is math.exp:
        tail = math.exp(-abs(z))
        soft = max(z, 0.0) + math.log1p(tail)
        onset = (1.0 if z >= 0.0 else tail) / (1.0 + tail)
    else:
        tail = np.exp(-np.abs(z))
        soft = np.maximum(z, 0.0) + np.log1p(tail)
        onset = np.where(z >= 0.0, 1.0, tail) / (1.0 + tail)
    return -k_b * x_cr * width * soft, -k_b * onset, -k_b * x_cr / p_cr * onset


def stiffness(params, x_c, gas=None):
    """
    Compute paper B's stiffness figure (N/m).

    The average slope of F over spring 0-12 mm (section IV-D).
    """
    amount = _gas(params, gas)
    low, high = params.x_s_low, params.x_s_high
    f_low = forward(params, float(x_c), low, amount)[1]
    f_high = forward(params, float(x_c), high, amount)[1]
    return (f_high - f_low) / (high - low)


def stiffness_from_rest(params, x_c, gas=None):
    """
    Average slope of F from the spring's rest point (F = 0) to x_s_high, N/m (section IV-D).

    Paper B's extended range, "extending the curves out to the spring bellows' rest length": the
    window starts where the force curve at this chamber compression crosses zero (the spring
    contracted below atmospheric, extended above) instead of at x_s = 0.
    """
    amount = _gas(params, gas)
    rest = rest_compression(params, x_c, gas)
    f_high = forward(params, float(x_c), params.x_s_high, amount)[1]
    return f_high / (params.x_s_high - rest)


def rest_compression(params, x_c, gas=None, step=5e-4):
    """
    Spring compression (m) at which the spring force vanishes, chamber at x_c (sealed gas).

    The zero nearest to x_s = 0 along the force curve, searched in `step`s towards the spring's
    end stop (extended) or x_s_high (contracted): the polynomial F_MTS is only valid near its data.
    """
    from scipy.optimize import brentq
    amount = _gas(params, gas)

    def force(x):
        return forward(params, float(x_c), x, amount)[1]
    x, f = 0.0, force(0.0)
    direction = -1.0 if f > 0.0 else 1.0
    end = params.spring.x_min if f > 0.0 else params.x_s_high
    while (x - end) * direction < 0.0:
        x_next = max(x - step, end) if direction < 0 else min(x + step, end)
        f_next = force(x_next)
        if f_next * f <= 0.0:
            return brentq(force, min(x, x_next), max(x, x_next), xtol=1e-12)
        x, f = x_next, f_next
    raise ParameterError(f'actuator: the spring force has no zero between 0 and {end} m at '
                         f'x_c = {x_c} m')


def rest_length_change(params, p, x_low=-0.03, x_high=0.03):
    """
    Elongation (m, positive = longer) of the spring's rest length at pressure P (Fig. 10).

    The spring alone held at pressure P: the rest point is where F(x_s, P) = 0, so the elongation
    is -x_s there. Below atmospheric it contracts, above it extends.
    """
    from scipy.optimize import brentq

    def force(x):
        return spring_force(params, x, p)[0]
    try:
        return -brentq(force, x_low, x_high, xtol=1e-9)
    except ValueError:
        raise ParameterError(
            f'actuator: no rest length within [{x_low}, {x_high}] m at {p:.0f} Pa') from None
