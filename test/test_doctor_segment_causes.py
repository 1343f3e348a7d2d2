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
The segment's baseline and causes as models the doctor fits (doctor/segment_causes.py).

Short records with known parameters: the segment plant on the bench with a sensor lag of 40 ms
(10 s, the quick pressure schedule of test_doctor_segment.py), and a synthetic record whose
torque does not depend on the pressures at all. Each effect's own regression and file are held by
test_segment_effects.py; here, what this module builds around them: the target Y (30), the
regression (34) with its ridge, the partition of the fitted coefficients, and the YAML names.
"""
import numpy as np
import pytest

from bellows_ros.config.segment import load_segment
from bellows_ros.doctor import checks, scoring, segment_causes
from bellows_ros.models.segment import contact_lengths
from bellows_ros.papers.segment_experiments import quasi_static_record

CONFIG = load_segment()
# The segment the bench record is drawn from: k_s and c_f away from the YAML's.
TRUTH = CONFIG.model.replace(restoring_k_s=-1.7, friction_c_f=0.45)
TAU = 0.04          # s, the sensors' lag
FACTOR = 10         # 1 kHz -> the doctor's 100 Hz (FIT_RATE)


def prepared(columns, params=CONFIG.model):
    """Return (full-rate record with `add_columns`, its 100 Hz block means)."""
    full = checks.checked_record(checks.as_table(columns, 'segment', 'bench'), 'segment')
    segment_causes.add_columns(full, params, CONFIG.identify.input_cutoff)
    return full, full.decimated(FACTOR)


@pytest.fixture(scope='module')
def lagged():
    record = quasi_static_record(TRUTH, CONFIG.plant, {'sensor_lag': {'tau': TAU}}, seed=7,
                                 duration=10.0, pressure_hold=(0.5, 2.0))
    return prepared(record)


def fitted(full, record, causes, train=None):
    model = segment_causes.build_model(
        record, CONFIG.model, causes,
        contact=segment_causes.ContactLengths(CONFIG.model, full, FACTOR))
    train = np.ones(len(record), bool) if train is None else train
    result = scoring.fit(model, segment_causes.measured(record), train)
    return model, result


def test_the_target_is_taken_from_the_raw_record_and_the_inputs_are_low_passed():
    record = quasi_static_record(TRUTH, CONFIG.plant, None, seed=3, duration=6.0,
                                 pressure_hold=(0.5, 2.0))
    raw = {name: np.array(record[name]) for name in ('t', 'psi', 'p1', 'p2', 'tau_ext',
                                                     'tau_motion')}
    full, _ = prepared(raw)
    assert np.array_equal(full['y'], raw['tau_motion'] - raw['tau_ext'])    # Y (30), unfiltered
    # Ψ̇ differenced from the angle where the record has none: it follows the plant's own
    assert np.corrcoef(full['psi_dot'], record['psi_dot'])[0, 1] > 0.95
    # the pressure sensors' white noise is filtered out of the inputs, the signal kept
    assert np.std(np.diff(full['p1'])) < 0.2 * np.std(np.diff(raw['p1']))
    assert np.max(np.abs(full['p1'] - raw['p1'])) < 0.02 * np.ptp(raw['p1'])


def test_a_fit_with_the_lag_recovers_the_segments_parameters(lagged):
    full, record = lagged
    model, result = fitted(full, record, ('sensor_lag',))
    values = model.physical(result.theta, result.linear)
    assert values['sensor_lag']['tau'] == pytest.approx(TAU, rel=0.05)
    assert values['baseline']['restoring.k_s'] == pytest.approx(TRUTH.restoring_k_s, rel=0.05)
    assert values['baseline']['friction.c_f'] == pytest.approx(TRUTH.friction_c_f, rel=0.05)
    for k, true in enumerate(TRUTH.previous_theta):          # A(34)'s pressure polynomial
        assert values['baseline'][f'previous.theta[{k}]'] == pytest.approx(true, rel=0.05)
    # the baseline, blind to the lag, is left far above that
    _, baseline = fitted(full, record, ())
    assert baseline.cost > 100 * result.cost


def test_the_coefficients_are_split_between_the_baseline_and_the_causes_that_own_them(lagged):
    full, record = lagged
    causes = ('pressure_friction', 'natural_curvature')
    model = segment_causes.build_model(
        record, CONFIG.model, causes,
        contact=segment_causes.ContactLengths(CONFIG.model, full, FACTOR))
    assert model.names == ['natural_curvature.c_psi0', 'natural_curvature.c_psi0_p']
    assert model.n_linear == segment_causes.BASELINE_COLUMNS + 2      # c_f,p and k_s,p
    # the last cause's alternative starts, the others' variables at x0
    assert all(len(start) == len(model.names) for start in model.starts) and model.starts
    theta = np.asarray(model.x0, float)
    prediction, linear = model.predict(theta, np.ones(len(record), bool))
    assert prediction.shape == (len(record),) and len(linear) == model.n_linear
    values = model.physical(theta, linear)
    assert set(values['pressure_friction']) == {'friction.c_fp'}
    assert set(values['natural_curvature']) == {'restoring.k_sp', 'restoring.c_psi0',
                                                'restoring.c_psi0_p'}
    assert len(values['baseline']) == segment_causes.BASELINE_COLUMNS
    # warm: a start from an earlier model's solution, by variable name
    warm = segment_causes.build_model(record, CONFIG.model, causes,
                                      warm={'natural_curvature.c_psi0': 7.0}, contact=lambda: None)
    assert warm.x0[0] == 7.0


def test_pressures_only_held_out_rows_reach_do_not_blow_up_their_prediction():
    """
    A torque that does not depend on the pressures; the chains pressurised only in the last 0.5 s.

    Trained before that, the pressure columns are sensor noise around p0. The ridge, relative to
    each column's size over the whole record, keeps them from being fitted to that noise
    (docs/doctor.md: a held-out RMSE of 3981 N·m against 0.018 in-sample before).
    """
    rng = np.random.default_rng(0)
    params = CONFIG.model
    t = np.arange(10000) * 1e-3
    psi = 0.3 * np.sin(2 * np.pi * t / 4.0)
    psi_dot = 0.3 * 2 * np.pi / 4.0 * np.cos(2 * np.pi * t / 4.0)
    y = (2 * -1.5 * psi + 0.4 * np.tanh(params.friction_c_vel * psi_dot)
         + rng.normal(0.0, 0.01, t.size))
    columns = {'t': t, 'psi': psi, 'psi_dot': psi_dot, 'tau_ext': -y, 'tau_motion': 0 * t,
               'p1': np.where(t >= 9.5, 4e5, params.p0) + rng.normal(0.0, 500.0, t.size),
               'p2': params.p0 + rng.normal(0.0, 500.0, t.size)}
    full, record = prepared(columns)
    _, result = fitted(full, record, (), train=record['t'] < 9.4)
    assert result.linear['restoring.k_s'] == pytest.approx(-1.5, rel=0.01)
    assert result.linear['friction.c_f'] == pytest.approx(0.4, rel=0.01)
    held = record['t'] >= 9.5
    error = np.sqrt(np.mean((result.prediction - record['y'])[held] ** 2))
    assert error < np.std(record['y'])


def test_the_contact_state_runs_once_at_full_rate_and_is_block_averaged(lagged):
    full, record = lagged
    contact = segment_causes.ContactLengths(CONFIG.model, full, FACTOR)
    first = contact()
    assert contact() is first                            # Algorithm 1 runs once
    expected = contact_lengths(CONFIG.model, full['psi'], full['p1'], full['p2'])
    for sa, raw in zip(first, expected):
        assert len(sa) == len(record)
        np.testing.assert_allclose(sa, raw[:len(record) * FACTOR].reshape(-1, FACTOR).mean(1))


def test_the_extended_file_holds_what_was_fitted_and_switches_off_what_was_not():
    values = {'baseline': {'previous.theta[2]': 7.5, 'restoring.k_s': -1.2,
                           'friction.c_f': 0.3},
              'sensor_lag': {'tau': 0.04}}
    flat = segment_causes.extended_flat(CONFIG, ('sensor_lag',), values)
    theta = list(CONFIG.model.previous_theta)
    theta[2] = 7.5
    assert flat['segment.previous.theta'] == pytest.approx(theta)
    assert flat['segment.restoring.k_s'] == -1.2 and flat['segment.friction.c_f'] == 0.3
    assert flat['segment.plant.sensor_lag_tau'] == 0.04         # the plant's lag (its label)
    # physics no cause found is written switched off: c_f,p = 0, k_s,p = c_Ψ0,p = 0
    assert flat['segment.friction.c_fp'] == 0.0
    assert flat['segment.restoring.k_sp'] == 0.0 and flat['segment.restoring.c_psi0_p'] == 0.0
    # the rest is the diagnosed file's
    changed = {'segment.previous.theta', 'segment.restoring.k_s', 'segment.friction.c_f',
               'segment.plant.sensor_lag_tau', 'segment.friction.c_fp', 'segment.restoring.k_sp',
               'segment.restoring.c_psi0_p'}
    base = CONFIG.flat()
    assert set(flat) == set(base)
    assert {k: v for k, v in flat.items() if k not in changed} == \
        {k: v for k, v in base.items() if k not in changed}
