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
The doctor's decision procedure (doctor/diagnosis.py), in process, on short records.

`diagnose` on 10 s of a plant with a sensor lag (actuator and segment, a couple of causes each so
that a run takes about a second), on the baseline alone and on arrays it must refuse; the pieces of
the decision on hand-made scores: a fit pinned at a bound, an output made worse, the residual
evidence and what counts as unexplained structure. The end-to-end runs on the whole vocabulary are
test_doctor_actuator.py and test_doctor_segment.py.
"""
import numpy as np
import pytest

from bellows_ros.config.actuator import load_actuator, load_actuator_params
from bellows_ros.config.segment import load_segment
from bellows_ros.doctor import actuator_causes, checks, diagnosis, scoring
from bellows_ros.errors import DataError
from bellows_ros.papers.actuator_experiments import actuator_record
from bellows_ros.papers.segment_experiments import quasi_static_record

ACTUATOR = load_actuator()
SEGMENT = load_segment()


@pytest.fixture(scope='module')
def lagged_actuator():
    """Return 10 s of the actuator's plant, its pressure sensor lagging by 50 ms (1 kHz)."""
    record = actuator_record(ACTUATOR.model, ACTUATOR.plant,
                             {'sensor_lag': {'time_constant': 0.05}}, seed=3, duration=10.0)
    return {name: np.array(record[name]) for name in ('t', 'x_c', 'x_s', 'p', 'f')}


def test_a_hidden_lag_is_named_and_the_next_round_extends_it(lagged_actuator):
    found = diagnosis.diagnose('actuator', lagged_actuator, ACTUATOR,
                               causes=('sensor_lag', 'air_leak'), source='bench 1')
    assert found.causes == ['sensor_lag'] and found.cause == 'sensor_lag'
    assert found.source == 'bench 1' and found.record.factor == 5   # 1 kHz -> FIT_RATE 200 Hz
    lag, leak = found.candidates['sensor_lag'], found.candidates['air_leak']
    assert lag.pays and lag.extends == () and lag.gain >= scoring.MIN_GAIN
    # the second round tries the leak on top of the lag, and it does not pay
    assert leak.extends == ('sensor_lag',) and not leak.pays
    assert found.final is lag.score
    assert found.values['sensor_lag']['time_constant'] == pytest.approx(0.05, rel=0.05)
    assert found.extended_flat['actuator.effects.sensor_lag.time_constant'] == pytest.approx(
        found.values['sensor_lag']['time_constant'])
    # two outputs, each in its unit; the headline is the pressure's, where the lag pays
    assert [(o.name, o.unit) for o in found.outputs] == [('p', 'Pa'), ('f', 'N')]
    assert found.primary == 0 and found.unit == 'Pa'
    assert found.baseline_rmse == pytest.approx(found.outputs[0].baseline_rmse)
    assert found.candidate_rmse('sensor_lag') == pytest.approx(found.final_rmse)
    assert found.gain == pytest.approx(1.0 - found.final_rmse / found.baseline_rmse)
    assert found.final_rmse < 1.5 * found.outputs[0].scale      # down to the averaged floor
    assert not found.unexplained and found.failure is None


def test_no_cause_fits_and_scores_the_baseline_alone(lagged_actuator):
    found = diagnosis.diagnose('actuator', lagged_actuator, ACTUATOR, causes=(),
                               raw_noise={'p': 100.0, 'f': 1.0})
    assert found.causes == [] and found.cause == 'none' and found.final is found.baseline
    assert found.gain == 0.0
    assert all(c.score is None for c in found.candidates.values())
    assert found.candidate_rmse('sensor_lag') is None
    # the raw rows' floors given: the fitted copy's are those over √5
    pressure, force = found.outputs
    assert pressure.noise == 100.0 and pressure.scale == pytest.approx(100.0 / np.sqrt(5))
    assert force.noise == 1.0 and found.noise == 100.0


def test_a_hidden_segment_lag_is_named():
    record = quasi_static_record(SEGMENT.model, SEGMENT.plant, {'sensor_lag': {'tau': 0.04}},
                                 seed=7, duration=10.0, pressure_hold=(0.5, 2.0))
    found = diagnosis.diagnose('segment', record, SEGMENT, causes=('sensor_lag',))
    assert found.causes == ['sensor_lag'] and found.unit == 'N·m' and found.outputs == []
    assert found.values['sensor_lag']['tau'] == pytest.approx(0.04, rel=0.05)
    assert found.extended_flat['segment.plant.sensor_lag_tau'] == pytest.approx(
        found.values['sensor_lag']['tau'])
    assert found.record.factor == 10 and found.gain >= 0.5


def test_standing_physics_is_the_actuators_only():
    with pytest.raises(ValueError, match="standing physics .* is the actuator's, not the segment"):
        diagnosis.diagnose('segment', {}, SEGMENT, standing=('buckling',))


def test_the_fitted_copy_is_at_most_the_fit_rate_and_fit_samples():
    def record(rows, dt):
        return checks.Record('segment', 'x', dt, {'t': np.arange(rows) * dt})
    assert diagnosis.decimation_factor(record(10000, 1e-3), 200.0) == 5
    assert diagnosis.decimation_factor(record(10000, 1e-3), 100.0) == 10
    assert diagnosis.decimation_factor(record(10000, 1e-2), 200.0) == 1      # already slower
    rows = 10 * diagnosis.FIT_SAMPLES + 1                    # long: FIT_SAMPLES binds
    assert diagnosis.decimation_factor(record(rows, 1e-3), 200.0) == 11


def test_an_output_made_worse_bars_a_cause():
    outputs = actuator_causes.OUTPUTS

    def scored(pressure, force):
        heldout = np.vstack([pressure * (-1.0) ** np.arange(100),
                             force * (-1.0) ** np.arange(100)])
        return scoring.Score(None, None, heldout)
    current = scored(2.0, 1.0)
    assert diagnosis._worsens(scored(1.0, 1.05), current, outputs) is None
    assert diagnosis._worsens(scored(1.0, 1.2), current, outputs) == \
        'makes the force (f) held-out RMSE 20 % worse'
    assert diagnosis._worsens(scored(1.0, 1.2), current, None) is None   # one output


def test_structure_left_is_correlated_and_above_the_floor():
    rng = np.random.default_rng(0)
    t = np.arange(2000) * 0.01
    record = checks.Record('segment', 'x', 0.01, {
        't': t, 'psi': 0.3 * np.sin(t), 'p1': 3e5 + 1e5 * np.sin(0.3 * t), 'p2': 2e5 + 0 * t})
    white = rng.normal(0.0, 1.0, t.size)
    evidence = diagnosis.residual_evidence(record, white, 1.0, 'segment')
    assert evidence['rmse_over_noise'] == pytest.approx(1.0, rel=0.05)
    assert evidence['ljung_box_lags'] == diagnosis.LB_LAGS and evidence['ljung_box_p'] > 1e-3
    assert not diagnosis._structured(evidence)
    # a residual that follows the pressure difference: 3 floors, correlated in time
    follows = 3.0 * np.sqrt(2) * np.sin(0.3 * t) + 0.1 * white
    evidence = diagnosis.residual_evidence(record, follows, 1.0, 'segment')
    assert evidence['correlation_with_pressure'] > 0.99
    assert abs(evidence['correlation_with_position']) < 0.2
    assert evidence['ljung_box_p'] < diagnosis.LB_P and diagnosis._structured(evidence)
    # correlated but within twice the floor: not what the doctor calls unexplained
    halved = diagnosis.residual_evidence(record, follows / 2.0, 1.0, 'segment')
    assert halved['ljung_box_p'] < diagnosis.LB_P and not diagnosis._structured(halved)
    assert diagnosis.residual_evidence(record, white, 0.0, 'segment')['rmse_over_noise'] == \
        float('inf')


def _pinned(names, theta, lower, upper):
    model = scoring.Model(('x',), names, list(theta), lower, upper, None, None)
    fit = scoring.Fit(np.asarray(theta, float), {}, None, 0.0)
    return scoring.Score(model, fit, np.zeros(1))


def test_a_bound_of_physics_and_a_bound_of_the_fit_read_differently():
    """
    The verdict on a pinned fit: a limit names, a bound of the fit says the range is wrong.

    Buckling at the lower bound of p_cr is the onset at ambient (kind 'limit': no doubt); heat
    exchange at the lower bound of its time constant (set against a second sensor lag, not by
    the walls) is 'range'; a sensor lag at 0.3 ms is 'absent'.
    """
    specs = actuator_causes.fit_variables('buckling', load_actuator_params())
    names = [f'buckling.{n}' for n, *_ in specs]
    lower, upper = [s[2] for s in specs], [s[3] for s in specs]
    at_ambient = _pinned(names, [0.5, lower[1], 1.1], lower, upper)
    edges = diagnosis.edge_report(at_ambient, 'buckling', actuator_causes)
    assert [(e['parameter'], e['side'], e['kind']) for e in edges] == [
        ('log10_critical_pressure_kpa', 'lower', 'limit')]
    assert diagnosis._doubt(edges, at_ambient, 1.0) is None
    heat = _pinned(['heat_exchange.log10_time_constant', 'heat_exchange.gamma'], [-1.0, 1.4],
                   [-1.0, 1.0], [2.5, 1.67])
    edges = diagnosis.edge_report(heat, 'heat_exchange', actuator_causes)
    assert [e['kind'] for e in edges] == ['range']
    assert 'the range is wrong' in diagnosis._doubt(edges, heat, 1.0)
    lag = _pinned(['sensor_lag.log10_time_constant'], [-3.5], [-3.5], [0.5])
    edges = diagnosis.edge_report(lag, 'sensor_lag', actuator_causes)
    assert [e['kind'] for e in edges] == ['absent'] and diagnosis._doubt(edges, lag, 1.0)


@pytest.mark.parametrize('change, message', [
    (lambda d: d.pop('f'), "column 'f': missing"),
    (lambda d: d.update(p=d['p'][:-1]), 'one length'),
    (lambda d: d.update(t=d['t'][:150], x_c=d['x_c'][:150], x_s=d['x_s'][:150],
                        p=d['p'][:150], f=d['f'][:150]), 'only 150 samples'),
])
def test_bad_arrays_are_named_by_their_source(change, message):
    t = np.arange(10000) * 1e-3
    data = {'t': t, 'x_c': 0.01 * np.sin(t), 'x_s': 0 * t, 'p': 1e5 + 0 * t, 'f': 0 * t}
    change(data)
    with pytest.raises(DataError, match=message) as error:
        diagnosis.diagnose('actuator', data, load_actuator(), source='rig 2')
    assert str(error.value).startswith('rig 2')
