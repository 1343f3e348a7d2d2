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
The no-slip membrane contact of paper A (models/contact.py): A(13), A(20)-A(28), Algorithm 1.

One chain's strain memory stepped alone: the contact angle's sign and scale, the geometry of a
step against a hand computation of A(20), A(21), A(25), A(26), A(28), the clamps, the release, and
Appendix B's fixed point. Lengths m, angles rad, pressures Pa (relative to p0 where named p_rel).
"""
import math

import pytest

from bellows_ros.config.segment import load_segment_params
from bellows_ros.models.contact import ALPHA_PER_PSI, contact_angle, StrainMemory
from bellows_ros.models.ogden import stress
from bellows_ros.models.segment import strain_memory

MU, GAMMA = (4000.0, 400.0), (2.5, 6.0)  # N/m, 1: config/segment.yaml's membrane
L0, S0 = 0.05, 0.06                      # m


@pytest.fixture(scope='module')
def params():
    return load_segment_params()


def memory(sa_max=0.5, n_lambda=1000):
    """Return one chain's memory with the Newton solve of (22), no table: λ1 to ~1e-15."""
    return StrainMemory(L0, S0, sa_max, n_lambda, MU, GAMMA)


def test_the_contact_angle_is_an_eighth_of_psi_against_the_chains_sign():
    """A(13) [choice]: α_j = -½ σ_j ψ_4 with ψ_4 = Ψ/4."""
    assert ALPHA_PER_PSI == -0.125
    assert contact_angle(0.8, 1.0) == pytest.approx(-0.1, rel=1e-15)
    assert contact_angle(0.8, -1.0) == pytest.approx(0.1, rel=1e-15)
    assert contact_angle(-0.8, -1.0) == contact_angle(0.8, 1.0)


def test_steps_follow_the_equations_by_hand():
    """
    A(20), A(21), A(25), A(26), A(28) over steps from the empty profile: filling, then releasing.

    λ1 is checked against the stress of (22) rather than solved here (test_models_ogden.py pins
    the solver); R, β, a, n and s̃_a are computed from the equations.
    """
    chain = memory()
    s_a, stored, counts = 0.0, [], []    # the empty profile of Algorithm 1's start
    for p_rel, psi_deg in ((2e5, 60.0), (2e5, 60.0), (2.4e5, 70.0), (1.5e5, 60.0), (1.5e5, 45.0)):
        alpha = contact_angle(math.radians(psi_deg), 1.0)
        radius = L0 + (S0 + s_a) * math.tan(alpha)                 # (20)
        beta = math.pi / 2 + alpha                                 # (21)
        result = chain.step(p_rel, alpha)
        lam1 = chain.lam1
        assert stress(lam1, MU, GAMMA) == pytest.approx(p_rel * radius, rel=1e-12)  # (22)
        a = 1 - radius * beta / (lam1 * L0 * math.pi / 2)           # (25)
        assert 0 < a < 1
        n = math.ceil(a * 1000)
        # (26): samples beyond n released, new ones and the transition point n take λ1
        stored = (stored + [lam1] * n)[:n]
        stored[n - 1] = lam1
        s_a = L0 * math.pi / 2 / 1000 * sum(stored)                  # (28)
        assert chain.n == n
        assert chain.profile[:n] == pytest.approx(stored, rel=1e-15)
        assert not any(chain.profile[n:])
        assert result == chain.s_a == pytest.approx(s_a, rel=1e-12)
        counts.append(n)
    # the contact grew, then shrank: both branches of (26); the first stretch was kept (no slip)
    assert counts[2] > counts[0] and counts[-1] < counts[-2] < counts[2]
    assert chain.profile[0] != chain.profile[chain.n - 1]


def test_vented_and_straight_there_is_no_contact():
    """p_rel ≤ 0 leaves λ1 = 1 and, with α = 0, a = 1 - (l0 π/2)/(l0 π/2) = 0: nothing touches."""
    for p_rel in (0.0, -5e4):
        chain = memory()
        assert chain.step(p_rel, 0.0) == 0.0
        assert (chain.n, chain.lam1, chain.total) == (0, 1.0, 0.0)


def test_contact_grows_with_pressure_and_bending_towards_the_rib():
    def settled(p_rel, psi):
        chain = memory()
        for _ in range(200):
            s_a = chain.step(p_rel, contact_angle(psi, 1.0))
        return s_a
    pressures = [settled(p, 1.0) for p in (5e4, 1e5, 2e5, 4e5)]
    angles = [settled(2e5, psi) for psi in (-0.5, 0.0, 0.5, 1.0)]
    assert pressures == sorted(pressures) and len(set(pressures)) == 4
    assert angles == sorted(angles) and len(set(angles)) == 4


def test_the_contact_length_stays_on_the_rib():
    """s̃_a is clamped to [0, sa_max] (28), the profile beneath it is not."""
    chain = memory(sa_max=0.01)
    assert chain.step(4e5, contact_angle(1.3, 1.0)) == 0.01
    assert chain.sample_length * chain.total > 0.01


def test_venting_releases_the_whole_contact_exactly():
    chain = memory()
    profile = chain.profile  # the fused step of models.segment keeps this list
    for k in range(300):
        chain.step(3e5 * k / 299, contact_angle(1.2 * k / 299, 1.0))
    assert chain.n > 0
    assert chain.step(0.0, 0.0) == 0.0
    assert (chain.n, chain.total) == (0, 0.0) and not any(chain.profile)
    chain.step(3e5, contact_angle(1.0, 1.0))
    chain.reset()
    assert chain.profile is profile and not any(profile)
    assert (chain.n, chain.total, chain.lam1, chain.s_a) == (0, 0.0, 1.0, 0.0)


def test_the_running_sum_is_the_sum_of_the_profile(monkeypatch):
    monkeypatch.setattr(StrainMemory, 'RESUM_EVERY', 50)
    chain = memory()
    for k in range(2000):
        psi = 1.4 * math.sin(k / 40.0)
        chain.step(2.5e5 * (1 + math.sin(k / 23.0)) / 2, contact_angle(psi, 1.0))
        assert chain.total == pytest.approx(math.fsum(chain.profile), rel=1e-12, abs=1e-12)
        if k % 50 == 49:  # re-summed exactly
            assert chain.total == math.fsum(chain.profile[:chain.n])


@pytest.mark.parametrize('p_abs, psi_deg',
                         [(4.0e5, 74.5), (2.0e5, 30.0), (7.5e5, 100.0), (6.0e5, -20.0)])
def test_appendix_b_repeated_steps_converge_to_one_contact_length(params, p_abs, psi_deg):
    memory = strain_memory(params)
    alpha = contact_angle(math.radians(psi_deg), 1.0)
    history = [memory.step(p_abs - params.p0, alpha) for _ in range(400)]
    assert history[-1] > 0.0  # there is contact: the fixed point is not the trivial empty one
    assert max(history[-100:]) - min(history[-100:]) <= 1e-12 * history[-1]
    # and it converges from a different start (a memory filled along another path) to the same
    # fixed point when that path leaves no stored strain in the contact...
    other = strain_memory(params)
    for _ in range(50):
        other.step(0.0, contact_angle(0.0, 1.0))  # vented and straight: no contact
    again = [other.step(p_abs - params.p0, alpha) for _ in range(400)]
    assert again[-1] == pytest.approx(history[-1], rel=1e-9)
