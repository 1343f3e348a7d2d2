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
Ogden material (14, 15) and the free-membrane strain solve (22) against a 60-digit reference.

Reference: bisection on e = λ1 - 1 in Python's `decimal` at 60 significant digits (mpmath is not
installed in .venv), 240 halvings of a bracket [0, load/Σμ] that is valid because T(λ) ≥
Σμ(λ - 1/λ) ... ≥ Σμ (λ - 1) for γ ≥ 2 — so the reference is exact to far below 1e-15 relative.
"""
from decimal import Decimal, localcontext
import math

from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np
import pytest

from bellows_ros.config.ranges import RANGES
from bellows_ros.models.ogden import (energy, free_strain, stress, stress_slope,
                                      STRETCH_TABLE_ERROR, STRETCH_TABLE_SPACING, StretchTable)


def reference_strain(load, mu, gamma):
    with localcontext() as ctx:
        ctx.prec = 60
        load = Decimal(load)
        mu = [Decimal(m) for m in mu]
        gamma = [Decimal(g) for g in gamma]

        def residual(e):
            log_lam = (1 + e).ln()
            return sum(m * (((g - 1) * log_lam).exp() - ((-g - 1) * log_lam).exp())
                       for m, g in zip(mu, gamma)) - load
        lo, hi = Decimal(0), load / sum(mu)
        assert residual(hi) >= 0
        for _ in range(240):
            mid = (lo + hi) / 2
            if residual(mid) > 0:
                hi = mid
            else:
                lo = mid
        return (lo + hi) / 2  # λ1 - 1


MATERIALS = [((4000.0, 400.0), (2.5, 6.0)), ((2.0e4, 10.0), (2.000001, 11.5)),
             ((1.0, 1.0e5), (3.0, 2.0000001))]
LOADS = [1e-12, 1e-6, 1.0, 350.0, 2.6e4, 1e7, 1e12, 6.5e5 * 1e3]  # N/m: tiny to huge radii


@pytest.mark.parametrize('mu, gamma', MATERIALS)
@pytest.mark.parametrize('load', LOADS)
def test_free_strain_matches_high_precision_reference(load, mu, gamma):
    exact = reference_strain(load, mu, gamma)
    lam = free_strain(load, mu[0], mu[1], gamma[0], gamma[1])
    assert lam == pytest.approx(1.0 + float(exact), rel=1e-10)
    # the answer satisfies (22) (checked where T's own cancellation near λ = 1 allows it)
    if lam > 1.01:
        assert stress(lam, mu, gamma) == pytest.approx(load, rel=1e-9)


@pytest.mark.parametrize('guess', [1.0, 1.0000001, 1.3, 50.0, 1e9])
def test_free_strain_independent_of_warm_start(guess):
    mu, gamma = (4000.0, 400.0), (2.5, 6.0)
    cold = free_strain(2.6e4, *mu, *gamma)
    assert free_strain(2.6e4, *mu, *gamma, guess=guess) == pytest.approx(cold, rel=1e-13)


@pytest.mark.parametrize('mu, gamma', MATERIALS)
@pytest.mark.parametrize('load', [1e-12, 1e-6, 1.0, 350.0])
def test_stretch_minus_one_is_accurate_too(load, mu, gamma):
    # the solver works in ln λ1 with expm1, so λ1 - 1 keeps its relative precision for tiny loads;
    # λ1 - 1 is recovered from the returned λ1 only to ~1e-16/(λ1 - 1), hence the tolerance
    exact = float(reference_strain(load, mu, gamma))
    lam = free_strain(load, mu[0], mu[1], gamma[0], gamma[1])
    assert lam - 1.0 == pytest.approx(exact, rel=max(1e-10, 4e-16 / exact))


def test_tiny_loads_keep_relative_precision_of_the_stretch():
    mu, gamma = (4000.0, 400.0), (2.5, 6.0)
    load = 1e-9
    slope_at_one = 2.0 * sum(m * g for m, g in zip(mu, gamma))  # T'(1)
    assert free_strain(load, *mu, *gamma) - 1.0 == pytest.approx(load / slope_at_one, rel=1e-6)
    assert float(reference_strain(load, mu, gamma)) == pytest.approx(load / slope_at_one, rel=1e-6)


@pytest.mark.parametrize('load', [0.0, -1.0, -6.5e5 * 0.05, -1e300])
def test_vented_or_sucked_membrane_is_unstretched(load):
    assert free_strain(load, 4000.0, 400.0, 2.5, 6.0) == 1.0


def test_nan_load_gives_nan_not_a_number():
    assert math.isnan(free_strain(float('nan'), 4000.0, 400.0, 2.5, 6.0))


def test_stress_is_the_derivative_of_the_energy_and_slope_its_derivative():
    mu, gamma = (4000.0, 400.0), (2.5, 6.0)
    for lam in (1.0, 1.05, 1.4, 2.5):
        h = 1e-6
        assert stress(lam, mu, gamma) == pytest.approx(
            (energy(lam + h, mu, gamma) - energy(lam - h, mu, gamma)) / (2 * h),
            rel=1e-6, abs=1e-6)
        assert stress_slope(lam, mu, gamma) == pytest.approx(
            (stress(lam + h, mu, gamma) - stress(lam - h, mu, gamma)) / (2 * h), rel=1e-6)
    assert energy(1.0, mu, gamma) == 0.0 and stress(1.0, mu, gamma) == 0.0


@settings(max_examples=30, deadline=None)
@given(log_load=st.floats(-12.0, 12.0), log_mu1=st.floats(0.0, 5.0), log_mu2=st.floats(0.0, 5.0),
       gamma1=st.floats(2.0, 12.0, exclude_min=True),
       gamma2=st.floats(2.0, 12.0, exclude_min=True))
def test_any_admissible_input_is_solved_to_1e10(log_load, log_mu1, log_mu2, gamma1, gamma2):
    load, mu = 10.0 ** log_load, (10.0 ** log_mu1, 10.0 ** log_mu2)
    lam = free_strain(load, mu[0], mu[1], gamma1, gamma2)
    assert math.isfinite(lam) and lam >= 1.0
    assert lam == pytest.approx(1.0 + float(reference_strain(load, mu, (gamma1, gamma2))),
                                rel=1e-10)


def test_free_strain_solves_the_reference_stress():
    """
    A(15) has one home, `stress`; `free_strain` writes T in ln λ1 and is held equal to it.

    (ln λ1 for precision and speed in the 1 kHz loop.) Over random materials and loads (seeded),
    T(free_strain(load)) = load to 1e-12, where λ1 - 1 ≥ 1e-3 (closer to 1, `stress` itself
    cancels digits).
    """
    import numpy as np

    rng = np.random.default_rng(31)
    checked = 0
    for _ in range(2000):
        mu = tuple(10.0 ** rng.uniform(1.0, 5.0, 2))
        gamma = tuple(rng.uniform(2.05, 12.0, 2))
        load = 10.0 ** rng.uniform(0.0, 7.0)
        lam = free_strain(load, mu[0], mu[1], gamma[0], gamma[1])
        if lam - 1.0 < 1e-3:
            continue
        assert stress(lam, mu, gamma) == pytest.approx(load, rel=1e-12)
        checked += 1
    assert checked > 1000


# --- the tabulated λ1 (`StretchTable`) against the solver ----------------------------------------

def _table_materials(rng, count):
    """Return the corners of config/ranges.py's Ogden box (γ just above 2), then drawn ones."""
    mu_range, gamma_range = RANGES['segment.ogden.mu'], RANGES['segment.ogden.gamma']
    low_gamma = gamma_range.low + 1e-7  # γ > 2 (Appendix B): the range's low end is excluded
    corners = [((m1, m2), (g1, g2)) for m1 in (mu_range.low, mu_range.high)
               for m2 in (mu_range.low, mu_range.high)
               for g1 in (low_gamma, gamma_range.high) for g2 in (low_gamma, gamma_range.high)]
    drawn = [(tuple(np.exp(rng.uniform(np.log(mu_range.low), np.log(mu_range.high), 2))),
              tuple(rng.uniform(low_gamma, gamma_range.high, 2))) for _ in range(count)]
    return corners + drawn


def test_stretch_table_error_bound_over_the_parameter_ranges():
    """
    `StretchTable` gives `free_strain`'s λ1 to STRETCH_TABLE_ERROR (relative) on the whole box.

    Materials: the 16 corners of config/ranges.py's μ (1..1e7 N/m) and γ (2..30) ranges and 40
    drawn inside (log-uniform μ, uniform γ, seeded); loads log-uniform from 1e-9 N/m to the
    largest load a segment of the ranges meets (2 × 1.1 MPa times R ≤ 1 + 2 tan(π/8) m), plus the
    grid nodes, cell midpoints (where a Hermite error peaks) and loads past the table (the solver
    then answers). `free_strain` itself is good to ~1e-15 (the tests above). Largest error found
    when written: ~5e-15 at spacing 0.005 (~3e-13 at 0.01).
    """
    rng = np.random.default_rng(2211)
    load_max = 2.0 * RANGES['segment.p_max'].high * (1.0 + 2.0 * math.tan(math.pi / 8.0))
    worst = 0.0
    for mu, gamma in _table_materials(rng, 40):
        table = StretchTable(mu, gamma, load_max)
        scale = mu[0] + mu[1]
        cells = rng.integers(0, table.count, 200)
        loads = np.concatenate([
            np.exp(rng.uniform(np.log(1e-9), np.log(load_max), 800)),
            scale * np.expm1(cells * STRETCH_TABLE_SPACING),  # nodes
            scale * np.expm1((cells + 0.5) * STRETCH_TABLE_SPACING),  # midpoints
            load_max * np.array([1.0, 1.5, 1e3])])
        for load in loads.tolist():
            exact = free_strain(load, mu[0], mu[1], gamma[0], gamma[1])
            worst = max(worst, abs(table(load) - exact) / exact)
    assert worst <= STRETCH_TABLE_ERROR


def test_stretch_table_has_the_solvers_edge_cases():
    """λ1 = 1 for loads ≤ 0 (vented or sucked chain), NaN for NaN, the solver beyond the grid."""
    mu, gamma = (4000.0, 400.0), (2.5, 6.0)
    table = StretchTable(mu, gamma, 1e5)
    for load in (0.0, -1.0, -1e300, -math.inf):
        assert table(load) == 1.0 == free_strain(load, *mu, *gamma)
    assert math.isnan(table(math.nan))
    for load in (1e5 * 1.01, 1e9):  # past the table: the Newton solve itself
        assert table(load) == free_strain(load, *mu, *gamma)
    assert isinstance(table(2.6e4), float)  # plain floats, not NumPy scalars (speed)


def test_a_coarser_table_would_miss_the_bound():
    """The test above can fail: at 8× the spacing (error ∝ h⁶) the default material misses it."""
    mu, gamma = (4000.0, 400.0), (2.5, 6.0)
    coarse = StretchTable(mu, gamma, 2e5, spacing=8.0 * STRETCH_TABLE_SPACING)
    loads = 4400.0 * np.expm1((np.arange(coarse.count) + 0.5) * 8.0 * STRETCH_TABLE_SPACING)
    worst = max(abs(coarse(v) - free_strain(v, *mu, *gamma)) / free_strain(v, *mu, *gamma)
                for v in loads.tolist())
    assert worst > STRETCH_TABLE_ERROR
