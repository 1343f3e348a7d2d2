"""Paper A segment model: Algorithm 1 (Appendix A/B), path dependence, regressors vs the 1 kHz step,
the Fig. 10 calibration of config/segment.yaml, parameter checks."""
import math

import numpy as np
import pytest

from bellows_ros.errors import ParameterError
from bellows_ros.identify.segment import calibrate_fig10, fig10_torques
from bellows_ros.models.contact import contact_angle
from bellows_ros.models.segment import (OUTPUTS, SegmentModel, actuator_regressor, friction_regressor,
                                        load_segment_params, previous_regressor, restoring_regressor,
                                        scaled_pressure, simulate_model, strain_memory)


@pytest.fixture(scope='module')
def params():
    return load_segment_params()


@pytest.mark.parametrize('p_abs, psi_deg', [(4.0e5, 74.5), (2.0e5, 30.0), (7.5e5, 100.0), (6.0e5, -20.0)])
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


def test_gamma_of_two_or_less_is_rejected(tmp_path, params):
    bad = tmp_path / 'bad.yaml'
    bad.write_text('/**:\n  ros__parameters:\n    segment:\n      ogden:\n        gamma: [2.0, 6.0]\n')
    with pytest.raises(ParameterError, match='segment.ogden.gamma'):
        load_segment_params(bad)


def test_unknown_parameter_is_rejected(tmp_path):
    bad = tmp_path / 'bad.yaml'
    bad.write_text('/**:\n  ros__parameters:\n    segment:\n      ogden:\n        nu: 0.5\n')
    with pytest.raises(ParameterError, match='segment.ogden.nu'):
        load_segment_params(bad)


def _run(params, psi_path, p1):
    model = SegmentModel(params)
    out = None
    for k, psi in enumerate(psi_path):
        out = model.step(psi, 0.0, p1[k], params.p0)
    return out


def test_same_pressure_and_angle_by_two_paths_gives_two_torques(params):
    """Path dependence (the hysteresis of Fig. 10): Ψ = 74.5° at 4 bar reached directly, or after an
    excursion to -30° and back. s̃_a and τ_a differ; the previous model (34) cannot tell them apart."""
    p0, psi_end = params.p0, math.radians(74.5)
    ramp = np.concatenate([np.linspace(p0, 4e5, 1000), np.full(3000, 4e5)])
    direct = _run(params, np.full(ramp.size, psi_end), ramp)
    excursion = np.concatenate([np.full(1000, psi_end),
                                psi_end + (math.radians(-30) - psi_end) * np.sin(np.linspace(0, np.pi, 3000))])
    excursion[-1] = psi_end  # exactly the same final (p, Ψ)
    via = _run(params, excursion, ramp)
    s_direct, s_via = direct[OUTPUTS.index('sa1')], via[OUTPUTS.index('sa1')]
    tau_direct, tau_via = direct[OUTPUTS.index('tau_a')], via[OUTPUTS.index('tau_a')]
    assert s_via > 1.1 * s_direct  # the stretched material snuggles the rib: more contact
    assert tau_via > tau_direct + 1.0
    assert via[OUTPUTS.index('tau_prev')] == direct[OUTPUTS.index('tau_prev')]
    assert via[OUTPUTS.index('tau_s')] == direct[OUTPUTS.index('tau_s')]


def test_scalar_step_agrees_with_the_regressors(params):
    rng = np.random.default_rng(5)
    n = 3000
    t = np.arange(n) * 1e-3
    psi = 1.2 * np.sin(2 * np.pi * 0.3 * t) + 0.01 * rng.standard_normal(n)
    psi_dot = np.gradient(psi, t)
    p1 = params.p0 + 3e5 * (0.5 + 0.5 * np.sin(2 * np.pi * 0.7 * t))
    p2 = params.p0 + 2e5 * (0.5 + 0.5 * np.cos(2 * np.pi * 0.45 * t))
    out = simulate_model(params, psi, p1, p2, psi_dot)
    q1, q2 = scaled_pressure(params, p1), scaled_pressure(params, p2)
    tau_a = actuator_regressor(psi, q1, q2, out['sa1'], out['sa2']) @ np.array(params.actuator_theta)
    tau_s = restoring_regressor(psi, q1, q2, params.restoring_c_psi0, params.restoring_c_psi0_p) @ np.array(
        [params.restoring_k_s, params.restoring_k_sp])
    tau_f = friction_regressor(psi_dot, q1, q2, params.friction_c_vel) @ np.array(
        [params.friction_c_f, params.friction_c_fp])
    prev = previous_regressor(psi, q1, q2) @ np.array(params.previous_theta) + tau_s + tau_f
    np.testing.assert_allclose(out['tau_a'], tau_a, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(out['tau_s'], tau_s, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(out['tau_f'], tau_f, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(out['tau_prev'], prev, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(out['tau_drive'], tau_a + tau_s + tau_f, rtol=1e-10, atol=1e-10)
    assert np.ptp(out['sa1']) > 0.01 and np.ptp(out['sa2']) > 0.01  # the memories really moved


def test_reset_restores_the_initial_state(params):
    model = SegmentModel(params)
    first = [model.step(0.5, 0.0, 4e5, 2e5) for _ in range(200)]
    model.reset()
    again = [model.step(0.5, 0.0, 4e5, 2e5) for _ in range(200)]
    assert first == again


@pytest.mark.slow
def test_fig10_calibration_of_the_default_parameters(params):
    """Fig. 10 scenario (chain 1 at 4 bar abs, chain 2 vented, Ψ = 74.5°, excursion to -30° and
    back): paper A measured 6.7 N·m before and 9.1 N·m after; the previous model gives one value."""
    before, after, prev_before, prev_after = fig10_torques(params)
    assert before == pytest.approx(6.7, abs=0.01)
    assert after == pytest.approx(9.1, abs=0.01)
    assert after >= 1.1 * before and 5.0 <= before <= 12.0 and 5.0 <= after <= 12.0
    assert prev_before == prev_after and 5.0 <= prev_before <= 12.0
    # the YAML values are what the documented calibration produces (a trace, not magic numbers)
    calibrated = calibrate_fig10(params)
    np.testing.assert_allclose(calibrated.actuator_theta, params.actuator_theta, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(calibrated.previous_theta, params.previous_theta, rtol=1e-5, atol=1e-5)


def test_peek_is_the_next_step_without_the_update(params):
    """`peek` returns what `step` will, through contact growth, release and emptying, and changes
    nothing (the pressure allocation evaluates its candidates with it)."""
    model = SegmentModel(params)
    rng = np.random.default_rng(3)
    t = np.arange(6000) * 1e-3
    psi = 1.2 * np.sin(2 * np.pi * 0.4 * t) + 0.02 * rng.standard_normal(t.size)
    p1 = params.p0 + 3e5 * (0.5 + 0.5 * np.sin(2 * np.pi * 0.3 * t)) ** 2
    p2 = params.p0 + 2e5 * (0.5 - 0.5 * np.cos(2 * np.pi * 0.7 * t))
    released = grown = 0
    for row in zip(psi.tolist(), (0.1 * np.cos(t)).tolist(), p1.tolist(), p2.tolist()):
        n_before = model.memory1.n
        first, second = model.peek(*row), model.peek(*row)
        assert first == second
        assert model.step(*row) == first
        released += model.memory1.n < n_before
        grown += model.memory1.n > n_before
    assert released > 100 and grown > 100
