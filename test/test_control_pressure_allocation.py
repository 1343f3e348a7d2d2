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

"""Pressure allocation: round trip through the models, saturation, and the contact memory."""
import copy
import math

import pytest

from bellows_ros.config.segment import load_segment_params
from bellows_ros.control.pressure_allocation import (allocate_paper_a, allocate_previous,
                                                     chain_pressures)
from bellows_ros.models.segment import SegmentModel

P = load_segment_params()
# One sample of the strain profile moves s~_a by (l0 π/2)/Nλ·λ1 (28); with λ1 < 2 that moves τ_a
# (29) by less than this at full pressure: the resolution of paper A's torque in the pressures.
SAMPLE_TORQUE = P.geometry_l0 * math.pi / 2 / P.geometry_n_lambda * 2.0 * abs(P.actuator_theta[1])


def state(model):
    return [(m.n, m.total, m.lam1, list(m.profile)) for m in (model.memory1, model.memory2)]


def pressurised(psi, p1, excursion=None, p2=None):
    """
    Step a model along a history and return it.

    Bend to `psi` vented, ramp chain 1 to `p1` (chain 2 to `p2`), then optionally an excursion to
    the angle `excursion` and back at that pressure.
    """
    p2 = P.p0 if p2 is None else p2
    model = SegmentModel(P)
    for k in range(1000):
        model.step(psi * k / 999, 0.0, P.p0, P.p0)
    for k in range(1000):
        model.step(psi, 0.0, P.p0 + (p1 - P.p0) * k / 999, P.p0 + (p2 - P.p0) * k / 999)
    if excursion is not None:
        for k in range(2000):
            model.step(psi + (excursion - psi) * k / 1999, 0.0, p1, p2)
        for k in range(2000):
            model.step(excursion + (psi - excursion) * k / 1999, 0.0, p1, p2)
    return model


@pytest.mark.parametrize('psi, p1, p2, base', [
    (0.8, 3.0e5, None, P.p0), (-0.9, 1.2e5, 3.5e5, P.p0), (0.0, 2.0e5, 2.0e5, 2.0e5),
    (1.3, 4.0e5, None, 1.5e5)])
def test_round_trip_paper_a(psi, p1, p2, base):
    model = pressurised(psi, p1, p2=p2)
    before = state(model)
    low = allocate_paper_a(model, psi, 0.3, -1e6, base).tau
    high = allocate_paper_a(model, psi, 0.3, 1e6, base).tau
    assert high - low > 40.0  # the reachable range is tens of N·m wide
    for fraction in (0.02, 0.25, 0.5, 0.75, 0.98):
        tau = low + fraction * (high - low)
        out = allocate_paper_a(model, psi, 0.3, tau, base)
        assert not out.saturated
        assert P.p0 <= out.p1 <= P.p_max and P.p0 <= out.p2 <= P.p_max
        assert state(model) == before  # candidates were peeked, the memory is as it was
        stepped = copy.deepcopy(model)
        reached = stepped.step(psi, 0.3, out.p1, out.p2)[5]
        assert reached == pytest.approx(out.tau, abs=1e-12)
        assert abs(reached - tau) <= SAMPLE_TORQUE, (tau, reached)


def test_round_trip_previous_model_and_co_contraction():
    model = pressurised(0.5, 2.5e5)
    base = 2.5e5
    for tau in (-20.0, -4.0, 0.0, 3.0, 15.0):
        out = allocate_previous(model, 0.5, -0.2, tau, base)
        assert not out.saturated
        reached = model.torques(0.5, -0.2, out.p1, out.p2, 0.0, 0.0)[4]
        assert reached == pytest.approx(tau, abs=1e-3)
        if min(out.p1, out.p2) > P.p0:  # on the unclipped part of the path both chains share u
            assert out.p1 + out.p2 == pytest.approx(2 * base, abs=1.0)
    # co-contraction raises both chains for the same torque
    out = allocate_previous(model, 0.5, 0.0, 1.0, base)
    assert out.p1 > base > out.p2 > P.p0


@pytest.mark.parametrize('allocate', [allocate_paper_a, allocate_previous])
def test_saturation_gives_the_nearest_end(allocate):
    model = pressurised(0.6, 3.0e5)
    top = allocate(model, 0.6, 0.0, 1e3, P.p0)
    bottom = allocate(model, 0.6, 0.0, -1e3, P.p0)
    assert top.saturated and bottom.saturated
    assert (top.p1, top.p2) == (P.p_max, P.p0)
    assert (bottom.p1, bottom.p2) == (P.p0, P.p_max)
    assert bottom.tau < 0.0 < top.tau < 1e3
    # just inside the range: not saturated, the pressures move off the end
    inside = allocate(model, 0.6, 0.0, top.tau - 0.5, P.p0)
    assert not inside.saturated and inside.p1 < P.p_max
    # a torque exactly at the end is reachable
    assert not allocate(model, 0.6, 0.0, top.tau, P.p0).saturated


def test_contact_memory_changes_the_pressures():
    """
    Same (Ψ, τ) after two histories: paper A's inverse asks for different pressures.

    The previous model asks for the same ones.
    """
    plain = pressurised(0.8, 3.0e5)
    moved = pressurised(0.8, 3.0e5, excursion=-0.6)
    assert moved.memory1.s_a > plain.memory1.s_a  # the excursion through Ψ < 0 grew the contact
    for tau in (0.0, 2.0, 5.0):
        a = allocate_paper_a(plain, 0.8, 0.0, tau, P.p0)
        b = allocate_paper_a(moved, 0.8, 0.0, tau, P.p0)
        # more material on the rib: more torque per pascal, so less pressure for the same torque
        assert a.p1 - b.p1 > 5e3, (tau, a, b)
        assert allocate_previous(plain, 0.8, 0.0, tau, P.p0) == \
            allocate_previous(moved, 0.8, 0.0, tau, P.p0)


def test_chain_pressures_path():
    span = P.p_max - P.p0
    assert chain_pressures(P, 0.0, 2e5) == (2e5, 2e5)
    assert chain_pressures(P, span, 2e5) == (P.p_max, P.p0)
    assert chain_pressures(P, -span, P.p0) == (P.p0, P.p_max)
    assert chain_pressures(P, 5e4, 2e5) == (2.5e5, 1.5e5)
