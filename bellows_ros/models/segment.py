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
Driving torque of one arm segment (paper A): parameters, regressors, the stateful 1 kHz evaluator.

τ_drive = τ_a + τ_s + τ_f (2), with
- τ_a, actuator torque (29): Σ_j σ_j x_a,jᵀ θ_a, x_a,j = p_j [1, s_j, s_j², s_j p_j, s_j Ψ_j, s_j
  Ψ_j², p_j Ψ_j, Ψ_j²] ([choice] for the garbled regressor), s_j = s̃_a of chain j from the no-slip
  strain memory (`bellows_ros.models.contact`, Algorithm 1);
- τ_s, restoring torque (3, 4): Σ_j (Ψ - Ψ_j0)(k_s + k_s,p p_j), Ψ_j0 = σ_j c_Ψ0,p tanh(c_Ψ0 p_j);
- τ_f, friction torque (5): tanh(c_vel Ψ̇)(c_f + c_f,p Σ_j p_j);
- τ_prev, the previous model (34): τ_f + τ_s + Σ_j σ_j p_j [1, p_j, Ψ_j, p_j²] θ_prev ([choice]).
Here p_j is the scaled pressure p_scl,j = (p_j - p0)/(p_max - p0), Ψ_j = σ_j Ψ, σ = (+1, -1)
(mirrored chains, [choice]). τ_prev is, like τ_drive, a driving torque: on a quasi-static
bench both predict -τ_ext.

The NumPy regressors are the reference (one home per equation: identification, the doctor and the
tests use them). `SegmentModel.step` is the 1 kHz fast path, hand-expanded because NumPy's per-call
overhead is larger than the whole step; `test/test_models_segment.py` holds it equal to the
regressors over random states to 1e-12 relative.
"""
import dataclasses
from dataclasses import dataclass, fields
import math
from typing import NamedTuple

import numpy as np

from bellows_ros.errors import ParameterError
from bellows_ros.models.contact import ALPHA_PER_PSI, contact_angle, HALF_PI, StrainMemory
from bellows_ros.models.limits import AMBIENT_RANGE, MAX_LENGTH, MAX_PROFILE_SAMPLES
from bellows_ros.models.ogden import free_strain, StretchTable

SIGNS = (1.0, -1.0)  # σ_j of chains 1 and 2 ([choice], docs/equations.md)


class SegmentOutput(NamedTuple):
    """What `SegmentModel.step` returns: contact lengths s̃_a (m), torques (N·m) of one sample."""

    sa1: float
    sa2: float
    tau_a: float
    tau_s: float
    tau_f: float
    tau_drive: float
    tau_prev: float


OUTPUTS = SegmentOutput._fields


@dataclass(frozen=True)
class SegmentParams:
    """
    The driving-torque model's parameters of `config/segment.yaml`; field = dotted name with '_'.

    Everything under `segment.` except `segment.plant.*` (the simulated segment,
    `segment_plant.SegmentPlantParams`) and `segment.identify.*` (identification settings): the
    config layer (`bellows_ros.config.segment`) builds all three from the one file.
    Units: Pa, m, N/m (Ogden μ), N·m, N·m/rad, rad, s, kg·m². See the YAML for each meaning.
    """

    p0: float
    p_max: float
    geometry_l0: float
    geometry_s0: float
    geometry_sa_max: float
    geometry_n_lambda: int
    ogden_mu: tuple
    ogden_gamma: tuple
    restoring_k_s: float
    restoring_k_sp: float
    restoring_c_psi0: float
    restoring_c_psi0_p: float
    friction_c_f: float
    friction_c_fp: float
    friction_c_vel: float
    actuator_theta: tuple
    previous_theta: tuple
    dynamics_inertia: float
    dynamics_damping: float
    dynamics_gravity: float

    def replace(self, **changes):
        """Return a copy with some fields changed (tuples for vectors)."""
        return dataclasses.replace(self, **changes)

    def flat(self):
        """Return flat ROS 2 names (`segment.ogden.mu`, ...) -> values, for `params.write_file`."""
        return {'segment.' + DOTTED[f.name]: _plain(getattr(self, f.name)) for f in fields(self)}


def _plain(value):
    return [float(v) for v in value] if isinstance(value, tuple) else value


# Field name -> dotted YAML name below `segment.` (the YAML nests one level, see
# config/segment.yaml).
DOTTED = {name: name for name in ('p0', 'p_max')}
DOTTED.update({f.name: f.name.replace('_', '.', 1) for f in fields(SegmentParams)
               if f.name not in DOTTED})
UNDOTTED = {dotted: name for name, dotted in DOTTED.items()}


def check_params(p, source='parameters'):
    """Raise ParameterError for values the model cannot use (names the parameter)."""

    def fail(name, why):
        raise ParameterError(f"{source}: parameter 'segment.{DOTTED[name]}' {why}")
    if len(p.ogden_mu) != 2 or min(p.ogden_mu) <= 0:
        fail('ogden_mu', 'needs two values > 0 (N/m)')
    if len(p.ogden_gamma) != 2 or min(p.ogden_gamma) <= 2:
        fail('ogden_gamma', 'needs two values > 2 (Appendix B convergence condition)')
    if len(p.actuator_theta) != 8:
        fail('actuator_theta', 'needs 8 values (29)')
    if len(p.previous_theta) != 4:
        fail('previous_theta', 'needs 4 values (34)')
    if not AMBIENT_RANGE[0] <= p.p0 <= AMBIENT_RANGE[1]:
        fail('p0', f'must be an ambient pressure, {AMBIENT_RANGE[0]:g}..{AMBIENT_RANGE[1]:g} '
             f'Pa abs, got {p.p0:g} (in bar or kPa?)')
    if not p.p_max > p.p0:
        fail('p_max', 'must exceed p0')
    for name in ('geometry_l0', 'geometry_s0', 'geometry_sa_max'):
        if not 0 < getattr(p, name) <= MAX_LENGTH:
            fail(name, f'must lie in (0, {MAX_LENGTH:g}] m, got {getattr(p, name):g} (in mm?)')
    if int(p.geometry_n_lambda) != p.geometry_n_lambda or \
            not 1 <= p.geometry_n_lambda <= MAX_PROFILE_SAMPLES:
        fail('geometry_n_lambda', f'must be a whole number in 1..{MAX_PROFILE_SAMPLES}, got '
             f'{p.geometry_n_lambda:g}')
    for name in ('dynamics_inertia', 'dynamics_damping'):  # negative: energy from nowhere
        if getattr(p, name) < 0:
            fail(name, 'must be >= 0')


def stretch_table(p):
    """
    Return the `ogden.StretchTable` of λ1 (22) for the membrane of a segment with parameters `p`.

    It covers the loads p_rel·R (N/m) of pressures up to 2 p_max abs (the model node refuses
    more) at angles up to a half turn (|α| ≤ π/8 by (13)): R ≤ l0 + (s0 + sa_max) tan(π/8) (20).
    Larger loads still get λ1, from the Newton solve.
    """
    radius = p.geometry_l0 + (p.geometry_s0 + p.geometry_sa_max) * math.tan(math.pi / 8.0)
    return StretchTable(p.ogden_mu, p.ogden_gamma, (2.0 * p.p_max - p.p0) * radius)


def strain_memory(p, table=None):
    """
    Return a fresh Algorithm-1 state for one chain of a segment with parameters `p`.

    `table`: the `stretch_table(p)` to share between chains (built here when None), or False for
    the Newton solve of (22) at every step (the exact reference, ~1e-15).
    """
    if table is None:
        table = stretch_table(p)
    return StrainMemory(p.geometry_l0, p.geometry_s0, p.geometry_sa_max, p.geometry_n_lambda,
                        p.ogden_mu, p.ogden_gamma, table or None)


# --- regressors (NumPy, one row per sample)
# -------------------------------------------------------

def relative_pressure(p, pressure):
    """p_rel = p - p0, Pa (17): the pressure the membrane of Algorithm 1 carries."""
    return np.asarray(pressure, float) - p.p0


def scaled_pressure(p, pressure):
    """p_scl = (p - p0)/(p_max - p0), 1 ([choice] p_max)."""
    return relative_pressure(p, pressure) / (p.p_max - p.p0)


def actuator_regressor(psi, ps1, ps2, sa1, sa2):
    """
    Compute X_a (29a), shape (N, 8).

    Σ_j σ_j p_j [1, s_j, s_j², s_j p_j, s_j Ψ_j, s_j Ψ_j², p_j Ψ_j, Ψ_j²].
    """
    total = 0.0
    for sign, ps, sa in zip(SIGNS, (ps1, ps2), (sa1, sa2)):
        psi_j = sign * np.asarray(psi, float)
        total = total + sign * ps[:, None] * np.column_stack(
            [np.ones_like(sa), sa, sa * sa, sa * ps, sa * psi_j, sa * psi_j ** 2, ps * psi_j,
             psi_j ** 2])
    return total


def natural_curvature(ps, sign, c_psi0, c_psi0_p):
    """Ψ_j0(p) = σ_j c_Ψ0,p tanh(c_Ψ0 p_scl,j), rad (4; [choice], zero at ambient)."""
    return sign * c_psi0_p * np.tanh(c_psi0 * ps)


def restoring_regressor(psi, ps1, ps2, c_psi0, c_psi0_p):
    """X_s (3b), shape (N, 2): Σ_j [(Ψ - Ψ_j0), p_j (Ψ - Ψ_j0)]."""
    columns = 0.0
    for sign, ps in zip(SIGNS, (ps1, ps2)):
        bend = np.asarray(psi, float) - natural_curvature(ps, sign, c_psi0, c_psi0_p)
        columns = columns + np.column_stack([bend, ps * bend])
    return columns


def friction_regressor(psi_dot, ps1, ps2, c_vel):
    """X_f (5b), shape (N, 2): [tanh(c_vel Ψ̇), (p_1 + p_2) tanh(c_vel Ψ̇)]."""
    slip = np.tanh(c_vel * np.asarray(psi_dot, float))
    return np.column_stack([slip, (ps1 + ps2) * slip])


def previous_regressor(psi, ps1, ps2):
    """Pressure part of the previous model (34), shape (N, 4): Σ_j σ_j p_j [1, p_j, Ψ_j, p_j²]."""
    total = 0.0
    for sign, ps in zip(SIGNS, (ps1, ps2)):
        psi_j = sign * np.asarray(psi, float)
        total = total + sign * ps[:,
                                  None] * np.column_stack([np.ones_like(ps), ps, psi_j, ps * ps])
    return total


def contact_lengths(p, psi, pressure1, pressure2):
    """s̃_a of both chains over a record (Algorithm 1 carried along the rows), m; two arrays."""
    out = []
    table = stretch_table(p)
    for sign, pressure in zip(SIGNS, (pressure1, pressure2)):
        memory = strain_memory(p, table)
        step = memory.step
        p_rel = relative_pressure(p, pressure).tolist()
        alpha = [contact_angle(x, sign) for x in np.asarray(psi, float).tolist()]
        out.append(np.array([step(pr, al) for pr, al in zip(p_rel, alpha)]))
    return out[0], out[1]


def motion_torque(inertia, damping, gravity, psi, psi_dot, psi_ddot):
    """
    τ_motion = M Ψ̈ + C Ψ̇ + N(Ψ), N(Ψ) = gravity·sin Ψ: the left-hand side of (2), N·m.

    M (kg·m²), C (N·m·s/rad) and the gravity amplitude (N·m) are constants [ours]: the model's
    `segment.dynamics.*` or the plant's `segment.plant.*`. Works on scalars and arrays.
    """
    # math.sin for a plain float: the model node and the plant call this per sample, where
    # NumPy's scalar overhead is most of the cost.
    sin = math.sin if isinstance(psi, float) else np.sin
    return inertia * psi_ddot + damping * psi_dot + gravity * sin(psi)


def external_torque(p, psi, psi_dot, psi_ddot, tau_drive):
    """
    Compute τ_ext = M Ψ̈ + C Ψ̇ + N(Ψ) - τ_drive from (2), N·m.

    M, C, N of `segment.dynamics` (quasi-static by default: M = C = N = 0, so τ_ext = -τ_drive).
    Works on scalars and arrays.
    """
    return (motion_torque(p.dynamics_inertia, p.dynamics_damping, p.dynamics_gravity,
                          psi, psi_dot, psi_ddot) - tau_drive)


# --- the 1 kHz evaluator
# ---------------------------------------------------------------------------

# The parameters of the strain memories and of λ1's table (`strain_memory`, `stretch_table`).
MEMORY_FIELDS = ('p0', 'p_max', 'geometry_l0', 'geometry_s0', 'geometry_sa_max',
                 'geometry_n_lambda', 'ogden_mu', 'ogden_gamma')


class SegmentModel:
    """
    Stateful driving-torque model of one segment: one `step` per sample, both chains.

    `step(psi, psi_dot, p1, p2)` (rad, rad/s, Pa abs, Pa abs) returns a `SegmentOutput`
    (sa1, sa2, tau_a, tau_s, tau_f, tau_drive, tau_prev) in m and N·m. It validates nothing: the
    caller (the model node, `simulate`) checks finiteness and ranges first — a per-call check would
    cost a noticeable part of the 20 µs budget. Everything that depends only on the parameters is
    precomputed here, λ1 of (22) included (`stretch_table`, shared by both chains). `reset()`
    returns the strain memories to Algorithm 1's initial state.

    Each instance's `step` is the fused two-chain closure of `_fused_step` (the 1 kHz path); the
    class's `step`, `SegmentModel.step(model, ...)`, is the same update written per chain
    (`StrainMemory.step` + `torques`), equal to it bit for bit (tested). `exact=True` keeps the
    per-chain form with the Newton solve of (22) at every step: the implementation before the
    table, which the tests hold the table's results to.
    """

    def __init__(self, params, exact=False):
        p = self.params = params
        self.table = None if exact else stretch_table(p)
        self.memory1 = strain_memory(p, self.table or False)
        self.memory2 = strain_memory(p, self.table or False)
        self._pressure = (p.p0, 1.0 / (p.p_max - p.p0))
        self._theta_a = tuple(float(v) for v in p.actuator_theta)
        self._previous = previous_torques(p)
        if not exact:
            self.step = _fused_step(p, self.memory1, self.memory2, self.table)

    def reset(self):
        self.memory1.reset()
        self.memory2.reset()

    def carried_on(self, params):
        """
        Return a model of new torque parameters `params` stepping on from this one's memories.

        For a change while running (the simulated segment's live effects): the strain memories
        (Algorithm 1) and λ1's table are shared, not copied, so the new model takes over exactly
        where this one stands; only one of the two may be stepped from then on. The memories'
        own parameters (p0, p_max, geometry, Ogden) must not change (ParameterError naming one).
        """
        for name in MEMORY_FIELDS:
            if getattr(params, name) != getattr(self.params, name):
                raise ParameterError(f"segment model: parameter '{name}' cannot change while "
                                     'the strain memories carry on')
        model = object.__new__(SegmentModel)
        model.__setstate__(dict(self.__getstate__(), params=params))
        model._pressure = (params.p0, 1.0 / (params.p_max - params.p0))
        model._theta_a = tuple(float(v) for v in params.actuator_theta)
        return model

    def __getstate__(self):
        # copy.deepcopy (the pressure allocation's trial steps) and pickle: the closures are
        # rebuilt on the copy's own memories (a closure copied by reference would step the
        # original's)
        state = dict(self.__dict__)
        state.pop('step', None)
        state.pop('_previous', None)
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._previous = previous_torques(self.params)
        if self.table is not None:
            self.step = _fused_step(self.params, self.memory1, self.memory2, self.table)

    def step(self, psi, psi_dot, p1, p2):
        """
        One sample of both chains: the strain memories advance (Algorithm 1), then `torques`.

        Contact state of chain j from p_rel (17) and α_j = ALPHA_PER_PSI σ_j Ψ (13).
        `test_fast_step_equals_the_reference_functions` in test/test_models_segment.py holds the
        result equal to `relative_pressure`, `scaled_pressure`, `contact_angle` and the regressors.
        """
        p0 = self._pressure[0]
        alpha = ALPHA_PER_PSI * psi
        s1 = self.memory1.step(p1 - p0, alpha)
        s2 = self.memory2.step(p2 - p0, -alpha)
        return _output(_SegmentOutput, (s1, s2) + self.torques(psi, psi_dot, p1, p2, s1, s2))

    def peek(self, psi, psi_dot, p1, p2):
        """Return what `step` would, the strain memories left untouched (candidate pressures)."""
        p0 = self._pressure[0]
        alpha = ALPHA_PER_PSI * psi
        s1 = self.memory1.peek(p1 - p0, alpha)
        s2 = self.memory2.peek(p2 - p0, -alpha)
        return _output(_SegmentOutput, (s1, s2) + self.torques(psi, psi_dot, p1, p2, s1, s2))

    def torques(self, psi, psi_dot, p1, p2, s1, s2):
        """
        (τ_a, τ_s, τ_f, τ_drive, τ_prev), N·m, at given contact lengths s1, s2 (m); no state.

        The fast form of (3)-(5), (17), (29), (34), hand-expanded for speed (see `step`); τ_s, τ_f
        and τ_prev from `previous_torques`.
        """
        p0, inv_span = self._pressure
        q1 = (p1 - p0) * inv_span
        q2 = (p2 - p0) * inv_span
        # actuator torque (29): chain 2 sees Ψ_2 = -Ψ and acts with σ_2 = -1
        t0, t1, t2, t3, t4, t5, t6, t7 = self._theta_a
        # (the chains' common terms once: `_fused_step` repeats these lines)
        psi_sq = psi * psi
        even_s = t1 + t5 * psi_sq
        odd_s = t4 * psi
        even = t0 + t7 * psi_sq
        odd = t6 * psi
        tau_a = (q1 * (even + s1 * (even_s + odd_s + t2 * s1 + t3 * q1) + odd * q1)
                 - q2 * (even + s2 * (even_s - odd_s + t2 * s2 + t3 * q2) - odd * q2))
        tau_s, tau_f, tau_prev = self._previous(psi, psi_dot, q1, q2)
        return tau_a, tau_s, tau_f, tau_a + tau_s + tau_f, tau_prev


def previous_torques(p):
    """
    Return the fast scalar τ_s (3, 4), τ_f (5) and τ_prev (34) of a segment with parameters `p`.

    The returned function maps (Ψ rad, Ψ̇ rad/s, p_scl,1, p_scl,2) to (τ_s, τ_f, τ_prev) in N·m.
    Hand-expanded for the 1 kHz step (`SegmentModel.torques`), whose part it is, and the
    benchmark's reference (`bench.segment.previous_step`, the previous model alone);
    test/test_models_segment.py holds both equal to the regressors.
    """
    tanh = math.tanh
    k_s, k_sp = p.restoring_k_s, p.restoring_k_sp
    c_psi0, c_psi0_p = p.restoring_c_psi0, p.restoring_c_psi0_p
    c_f, c_fp, c_vel = p.friction_c_f, p.friction_c_fp, p.friction_c_vel
    u0, u1, u2, u3 = (float(v) for v in p.previous_theta)

    def terms(psi, psi_dot, q1, q2):
        # restoring torque (3, 4)
        bend1 = psi - c_psi0_p * tanh(c_psi0 * q1)
        bend2 = psi + c_psi0_p * tanh(c_psi0 * q2)
        tau_s = bend1 * (k_s + k_sp * q1) + bend2 * (k_s + k_sp * q2)
        # friction torque (5)
        tau_f = tanh(c_vel * psi_dot) * (c_f + c_fp * (q1 + q2))
        # previous model (34)
        tau_prev = (tau_f + tau_s + q1 * (u0 + q1 * (u1 + u3 * q1) + u2 * psi)
                    - q2 * (u0 + q2 * (u1 + u3 * q2) - u2 * psi))
        return tau_s, tau_f, tau_prev
    return terms


def _fused_step(p, memory1, memory2, table):
    """
    Return the 1 kHz `step(psi, psi_dot, p1, p2)` of a `SegmentModel`: both chains in one call.

    The same operations in the same order as `StrainMemory.step` (with `StretchTable.__call__`
    for λ1 of (22)) on `memory1` and `memory2`, then `SegmentModel.torques` ((3)-(5), (17), (29),
    (34)): written out in one closure because each Python call, attribute look-up and NumPy scalar
    costs about as much as a line of the arithmetic, and the step is ~100 lines of it. It leaves
    out only operations that cannot change a bit (terms of (29) with an exact-zero θ_a, a clamp
    that never acts), so it gives the same bits as the per-chain form;
    test/test_models_segment.py holds it to that. The
    parameters are closure constants; the state stays in the two `StrainMemory` objects (peek,
    reset and the tests read it there). tan(-α) = -tan(α) (an odd libm tan; the bit-for-bit test
    checks it) and π/2 + (-α) = π/2 - α exactly, so chain 2 reuses chain 1's tangent.
    """
    tan, tanh, log1p, ceil, floor, fsum = (math.tan, math.tanh, math.log1p, math.ceil,
                                           math.floor, math.fsum)
    l0, s0, sa_max = memory1.l0, memory1.s0, memory1.sa_max
    length0, sample_length = memory1.length0, memory1.sample_length
    # float: a float times an int takes CPython's slow path (the same product, exactly)
    n_lambda = float(memory1.n_lambda)
    half_pi, alpha_per_psi, output, output_type = HALF_PI, ALPHA_PER_PSI, _output, _SegmentOutput
    profile1, profile2 = memory1.profile, memory2.profile  # for good: reset() clears in place
    resum_every = memory1.RESUM_EVERY
    cells, inv_scale, inv_spacing = table.cells, table.inv_scale, table.inv_spacing
    count = float(table.count)  # compared with a float: the same answer, CPython's fast path
    material = table.material
    # plain floats: a NumPy scalar among them would make every operation several times dearer
    p0, inv_span = float(p.p0), 1.0 / float(p.p_max - p.p0)
    t0, t1, t2, t3, t4, t5, t6, t7 = (float(v) for v in p.actuator_theta)
    # θ_a with only the p·[1, s] columns (29) in use (the Fig. 10 calibration of config's default
    # frees only those): the other six terms are exact zeros, and dropping them leaves the same
    # value (x·0 = ±0 added to a non-zero sum changes nothing for finite inputs)
    linear_actuator = t2 == t3 == t4 == t5 == t6 == t7 == 0.0 and t1 != 0.0 and t0 != 0.0
    k_s, k_sp, c_psi0, c_psi0_p, c_f, c_fp, c_vel = (float(v) for v in (
        p.restoring_k_s, p.restoring_k_sp, p.restoring_c_psi0, p.restoring_c_psi0_p,
        p.friction_c_f, p.friction_c_fp, p.friction_c_vel))
    u0, u1, u2, u3 = (float(v) for v in p.previous_theta)

    def step(psi, psi_dot, p1, p2):
        alpha = alpha_per_psi * psi
        tan_a = tan(alpha)
        r1 = p1 - p0
        r2 = p2 - p0
        # --- chain 1: Algorithm 1 steps 1-4 (20)-(25) ...
        radius = l0 + (s0 + memory1.s_a) * tan_a
        load = r1 * radius
        if load > 0.0:  # λ1 of (22), `StretchTable.__call__`
            x = log1p(load * inv_scale) * inv_spacing
            if x < count:
                x0, c0, c1, c2, c3, c4, c5 = cells[floor(x)]
                t = x - x0
                lam1 = c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * c5))))
            else:
                lam1 = free_strain(load, *material)
        else:
            lam1 = 1.0 if load == load else load
        a = 1.0 - radius * (half_pi + alpha) / (lam1 * length0)
        a = 0.0 if a < 0.0 else (a if a < 1.0 else 1.0 - 1e-12)
        n = ceil(a * n_lambda)
        # ... step 5 (26) and s̃_a (28)
        old = memory1.n
        total = memory1.total
        if n < old:
            total = 0.0 if n == 0 else total - fsum(profile1[n:old])
            profile1[n:old] = [0.0] * (old - n)
        elif n > old:
            profile1[old:n] = [lam1] * (n - old)
            total += (n - old) * lam1
        if n > 0:
            total += lam1 - profile1[n - 1]
            profile1[n - 1] = lam1
        memory1.n = n
        memory1.lam1 = lam1
        # --- chain 2 (σ_2 = -1: α_2 = -α), the same lines
        radius = l0 - (s0 + memory2.s_a) * tan_a
        load = r2 * radius
        if load > 0.0:
            x = log1p(load * inv_scale) * inv_spacing
            if x < count:
                x0, c0, c1, c2, c3, c4, c5 = cells[floor(x)]
                t = x - x0
                lam2 = c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * c5))))
            else:
                lam2 = free_strain(load, *material)
        else:
            lam2 = 1.0 if load == load else load
        a = 1.0 - radius * (half_pi - alpha) / (lam2 * length0)
        a = 0.0 if a < 0.0 else (a if a < 1.0 else 1.0 - 1e-12)
        n = ceil(a * n_lambda)
        old = memory2.n
        total2 = memory2.total
        if n < old:
            total2 = 0.0 if n == 0 else total2 - fsum(profile2[n:old])
            profile2[n:old] = [0.0] * (old - n)
        elif n > old:
            profile2[old:n] = [lam2] * (n - old)
            total2 += (n - old) * lam2
        if n > 0:
            total2 += lam2 - profile2[n - 1]
            profile2[n - 1] = lam2
        memory2.n = n
        memory2.lam1 = lam2
        # the running sums re-summed exactly every RESUM_EVERY steps (`StrainMemory.step`); the
        # chains step together, so memory1's count serves both (memory2's is not kept here)
        steps = memory1._steps + 1
        if steps >= resum_every:
            steps = 0
            total = fsum(profile1[:memory1.n])
            total2 = fsum(profile2[:n])
        memory1._steps = steps
        memory1.total = total
        memory2.total = total2
        # s̃_a (28) clamped to sa_max; StrainMemory.step also clamps at 0, which never acts: the
        # total is 0.0 exactly for an empty contact and a sum of n stretches ≥ 1 otherwise
        s1 = sample_length * total
        if s1 > sa_max:
            s1 = sa_max
        s2 = sample_length * total2
        if s2 > sa_max:
            s2 = sa_max
        memory1.s_a = s1
        memory2.s_a = s2
        # --- torques: `SegmentModel.torques` and `previous_torques`, the same expressions
        q1 = r1 * inv_span
        q2 = r2 * inv_span
        if linear_actuator:
            tau_a = q1 * (t0 + s1 * t1) - q2 * (t0 + s2 * t1)
        else:
            psi_sq = psi * psi
            even_s = t1 + t5 * psi_sq
            odd_s = t4 * psi
            even = t0 + t7 * psi_sq
            odd = t6 * psi
            tau_a = (q1 * (even + s1 * (even_s + odd_s + t2 * s1 + t3 * q1) + odd * q1)
                     - q2 * (even + s2 * (even_s - odd_s + t2 * s2 + t3 * q2) - odd * q2))
        bend1 = psi - c_psi0_p * tanh(c_psi0 * q1)
        bend2 = psi + c_psi0_p * tanh(c_psi0 * q2)
        tau_s = bend1 * (k_s + k_sp * q1) + bend2 * (k_s + k_sp * q2)
        tau_f = tanh(c_vel * psi_dot) * (c_f + c_fp * (q1 + q2))
        tau_prev = (tau_f + tau_s + q1 * (u0 + q1 * (u1 + u3 * q1) + u2 * psi)
                    - q2 * (u0 + q2 * (u1 + u3 * q2) - u2 * psi))
        return output(output_type, (s1, s2, tau_a, tau_s, tau_f, tau_a + tau_s + tau_f, tau_prev))
    return step


# tuple.__new__ on the tuple of values: a NamedTuple without the keyword-argument call of its
# generated __new__ (several times dearer; the fast step pays for one call only).
_output, _SegmentOutput = tuple.__new__, SegmentOutput


def simulate_model(params, psi, p1, p2, psi_dot, model=None):
    """
    Run `SegmentModel` over a record (state carried from row to row, starting from reset).

    Arrays in SI (rad, Pa abs, Pa abs, rad/s); returns {name: array} for the 7 `OUTPUTS`. Given
    a `model`, it goes on from that model's state (a record read in chunks).
    """
    model = SegmentModel(params) if model is None else model
    step = model.step
    rows = [step(a, b, c, d) for a, b, c, d in zip(
        np.asarray(psi, float).tolist(), np.asarray(psi_dot, float).tolist(),
        np.asarray(p1, float).tolist(), np.asarray(p2, float).tolist())]
    table = np.array(rows, float).reshape(-1, len(OUTPUTS))
    return {name: table[:, k] for k, name in enumerate(OUTPUTS)}
