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
The doctor's report as data (doctor/report.py): report.json, details.json and report.md.

A segment diagnosis is made by hand, its held-out residuals alternating ±size so that every RMSE
is exact (baseline 2 N·m, extended 1 N·m: a gain of 50 %), with one cause of each kind: named,
scored but short of the rule, pinned at a bound, not identifiable. The actuator's two outputs come
from a real diagnosis of a short record.
"""
import json

import numpy as np
import pytest

from bellows_ros.config.actuator import load_actuator
from bellows_ros.doctor import checks, diagnosis, report, scoring, segment_causes
from bellows_ros.papers.actuator_experiments import actuator_record

N = 400
REPORT_KEYS = {'system', 'baseline', 'cause', 'extended', 'gain', 'causes', 'unexplained',
               'candidates'}
PLOTS = ['residuals.png', 'fit.png']
PINNED = {'parameter': 'c_psi0', 'side': 'upper', 'kind': 'range',
          'meaning': 'a bound of the fit, not of physics'}


def known_score(size, values=None):
    """Return a `Score` whose held-out RMSE is `size` and in-sample RMSE 0.9 `size`."""
    model = scoring.Model((), [], [], [], [], None, lambda theta, linear: values or {})
    return scoring.Score(model, scoring.Fit(np.empty(0), {}, None, (0.9 * size) ** 2),
                         size * (-1.0) ** np.arange(N))


def known_diagnosis(causes=('sensor_lag',), unexplained=False, failure=None, edges=()):
    """Return a segment `Diagnosis` with known RMSEs (N·m): baseline 2, extended 1."""
    t = np.arange(N) * 0.01
    record = checks.Record('segment', 'bench.csv', 0.01, {
        't': t, 'psi': 0.3 * np.sin(t), 'p1': 3e5 + 1e5 * np.sin(0.3 * t), 'p2': 2e5 + 0 * t},
        factor=10)
    baseline = known_score(2.0, {'baseline': {'restoring.k_s': -1.5}})
    values = {'baseline': {'restoring.k_s': -1.5}, 'sensor_lag': {'tau': 0.04}}
    named = known_score(1.0, values)
    # without a named cause the lag is scored short of the rule, and the others extend nothing
    lag = (named, 0.5) if causes else (known_score(1.9), 0.05)
    candidates = {
        'contact_hysteresis': diagnosis.Candidate(
            'contact_hysteresis', False, 'the angle reverses only 1 time(s)'),
        'pressure_friction': diagnosis.Candidate(
            'pressure_friction', True, score=known_score(0.95), extends=tuple(causes),
            gain=0.05),
        'natural_curvature': diagnosis.Candidate(
            'natural_curvature', True, score=known_score(0.9), extends=tuple(causes),
            gain=0.1, note='fitted c_psi0 at the upper bound of its range', edges=[PINNED]),
        'sensor_lag': diagnosis.Candidate('sensor_lag', True, score=lag[0], gain=lag[1],
                                          pays=bool(causes), edges=list(edges)),
    }
    final = named if causes else baseline
    if failure:
        for cause in ('pressure_friction', 'natural_curvature', 'sensor_lag'):
            candidates[cause] = diagnosis.Candidate(cause, True)
    evidence = diagnosis.residual_evidence(record, final.heldout, 0.5, 'segment')
    return diagnosis.Diagnosis(
        'segment', 'bench.csv', record, np.sin(t), 'N·m', segment_causes.BASELINE, baseline,
        final, list(causes), candidates, 0.5 * np.sqrt(10), evidence, unexplained,
        final.params(), {}, {'load': 0.1}, failure)


def test_the_summary_line_and_the_extended_files_header():
    d = known_diagnosis()
    assert report.summary_line(d, 'out/r') == ('segment: cause sensor_lag; held-out RMSE 2 -> 1 '
                                               'N·m (gain 50.0 %); report in out/r')
    assert 'unexplained structure left; report' in report.summary_line(
        known_diagnosis(unexplained=True), 'out/r')
    assert report.extended_header(d) == ('Extended segment model written by `bellows diagnose` '
                                         'from bench.csv\n'
                                         'causes: sensor_lag; held-out gain 50.0 %')


def test_report_json_has_the_interface_keys_and_strict_numbers():
    d = known_diagnosis()
    d.candidates['pressure_friction'].score.heldout[0] = np.nan    # a broken candidate score
    data = json.loads(json.dumps(report.report_dict(d), allow_nan=False))
    assert set(data) == REPORT_KEYS
    assert data['baseline'] == {'model': segment_causes.BASELINE, 'rmse': 2.0, 'unit': 'N·m'}
    assert data['extended'] == {'model': 'baseline + sensor_lag', 'rmse': 1.0}
    assert data['cause'] == 'sensor_lag' and data['causes'] == ['sensor_lag']
    assert data['gain'] == pytest.approx(0.5) and data['unexplained'] is False
    rows = {c['cause']: c for c in data['candidates']}
    assert list(rows) == list(d.candidates)
    assert rows['sensor_lag'] == {'cause': 'sensor_lag', 'heldout_rmse': 1.0,
                                  'params': {'tau': 0.04}, 'edges': []}
    assert rows['contact_hysteresis']['heldout_rmse'] is None       # not identifiable
    assert rows['pressure_friction']['heldout_rmse'] is None        # not a number
    assert rows['natural_curvature']['edges'] == [PINNED]


def test_details_hold_the_decision_and_the_closest_candidate():
    d = known_diagnosis()
    details = json.loads(json.dumps(report.details_dict(d), default=float))
    assert details['data'] == 'bench.csv' and details['samples_fitted'] == N
    assert details['fit_rate_hz'] == pytest.approx(100.0) and details['decimation'] == 10
    assert details['baseline']['heldout_rmse'] == pytest.approx(2.0)
    assert details['baseline']['insample_rmse'] == pytest.approx(1.8)
    assert details['baseline']['heldout_rmse_per_fold'] == pytest.approx([2.0] * scoring.FOLDS)
    assert details['rule']['min_gain'] == scoring.MIN_GAIN
    lag = details['candidates']['sensor_lag']
    assert lag['pays'] is True and lag['heldout_rmse'] == pytest.approx(1.0)
    assert details['candidates']['contact_hysteresis']['reason'].startswith('the angle')
    # the largest gain among the scored and not named, with its note and the data to decide it
    assert details['closest'] == {
        'cause': 'natural_curvature', 'gain': 0.1,
        'why_not': 'fitted c_psi0 at the upper bound of its range',
        'deciding_data': segment_causes.DECIDING_DATA['natural_curvature']}
    # Without a note, the rule it missed: the gain reached MIN_GAIN, so the BIC did not fall.
    d.candidates['natural_curvature'].note = None
    assert report.closest(d)['why_not'] == (
        'held-out gain 10.0 %, but its BIC did not fall (the gain does not pay for the '
        'parameters it adds)')
    d.candidates['natural_curvature'].gain = 0.06
    assert report.closest(d)['why_not'] == 'held-out gain 6.0 % < 10 %'


def test_a_broken_held_out_score_is_null_in_report_json():
    # scoring.heldout_failure: a baseline whose held-out RMSE is not a number.
    d = known_diagnosis(causes=(), failure='numerical failure of the held-out refits')
    d.baseline.heldout[0] = np.nan
    data = json.loads(json.dumps(report.report_dict(d), allow_nan=False))
    assert data['baseline']['rmse'] is None and data['extended']['rmse'] is None
    assert data['gain'] == 0.0  # scoring.gain of a broken score


def test_fold_rmse_is_the_rmse_of_each_folds_held_out_blocks():
    heldout = np.zeros(1000)
    _, test = scoring.block_masks(1000)[2]
    heldout[test] = 3.0
    assert report.fold_rmse(heldout) == [0.0, 0.0, 3.0, 0.0, 0.0]


def test_report_md_of_a_named_cause():
    text = report.markdown(known_diagnosis(), PLOTS)
    assert text.startswith('# Model doctor: segment\n\nData: `bench.csv` — 400 samples fitted at '
                           '100 Hz (block means of 10 raw samples).')
    assert ('**Cause: `sensor_lag`.** Extending the baseline with it cuts the held-out RMSE from '
            '2 to 1 N·m (gain 50.0 %).') in text
    assert '| `contact_hysteresis` | no: the angle reverses only 1 time(s) | | | | no |' in text
    assert '| `sensor_lag` | yes | baseline | 1 N·m | 50.0 % | yes |' in text
    assert ('| `natural_curvature` | yes | baseline + sensor_lag | 0.9 N·m | 10.0 % | no: fitted '
            'c_psi0 at the upper bound of its range |') in text
    assert '- sensor_lag: tau = 0.04' in text
    # the extended model back into the system: the lag is a plant effect switched by --effect
    assert '--params extended.yaml --effect sensor_lag' in text
    assert 'sensor_lag is a dynamic effect of the plant' in text
    assert 'driving torque is the `tau_prev` output' in text
    assert text.endswith('![residuals.png](residuals.png)\n![fit.png](fit.png)\n')
    assert 'Closest candidate' not in text      # no structure left to explain


def test_report_md_of_structure_left_and_of_a_broken_baseline():
    text = report.markdown(known_diagnosis(causes=(), unexplained=True), [])
    assert '**Cause: `none`.** No candidate cause improves the held-out RMSE (2 N·m)' in text
    assert '**Unexplained structure remains**' in text
    assert 'Closest candidate: `natural_curvature`, held-out gain 10.0 %, not named' in text
    broken = known_diagnosis(causes=(), failure='numerical failure of the held-out refits')
    text = report.markdown(broken, [])
    assert '**Cause: `none` — the baseline could not be scored.**' in text
    assert ("| `sensor_lag` | yes | | | | not tried: the baseline's held-out score is "
            'broken |') in text
    assert report.extended_name(broken) == 'baseline (no cause pays)'


def test_a_fit_at_a_physical_limit_is_stated_as_a_finding():
    limit = {'parameter': 'log10_tau', 'side': 'lower', 'kind': 'limit', 'meaning': 'no lag'}
    d = known_diagnosis(edges=[limit])
    assert report.limit_findings(d) == [
        '`sensor_lag` is fitted at a physical limit, a finding: log10_tau at its lower bound: '
        'no lag.']
    text = report.markdown(d, [])
    assert 'yes (at a physical limit: log10_tau at its lower bound, no lag) |' in text
    d.candidates['contact_hysteresis'] = diagnosis.Candidate(
        'contact_hysteresis', True, score=known_score(0.5), gain=0.5, pays=True)
    d.causes.append('contact_hysteresis')
    assert 'driving torque is the `tau_drive` output' in report.markdown(d, [])


@pytest.fixture(scope='module')
def actuator():
    config = load_actuator()
    record = actuator_record(config.model, config.plant, {'sensor_lag': {'time_constant': 0.05}},
                             seed=3, duration=10.0)
    return diagnosis.diagnose('actuator', record, config, causes=('sensor_lag',),
                              source='bench 2')


def test_both_outputs_of_the_actuator_are_reported(actuator):
    data = json.loads(json.dumps(report.report_dict(actuator), allow_nan=False))
    assert set(data) == REPORT_KEYS | {'outputs', 'output'}
    assert data['output'] == 'p' and data['baseline']['unit'] == 'Pa'
    assert set(data['outputs']) == {'p', 'f'}
    for name, unit in (('p', 'Pa'), ('f', 'N')):
        output = data['outputs'][name]
        assert output['unit'] == unit
        assert output['candidates_heldout_rmse']['sensor_lag'] == pytest.approx(
            output['extended_rmse'])
    assert data['extended']['rmse'] == pytest.approx(data['outputs']['p']['extended_rmse'])
    details = json.loads(json.dumps(report.details_dict(actuator), default=float))
    assert details['heldout_units'] == 'noise floors of each output (combined)'
    assert set(details['evidence_per_output']) == {'p', 'f'}
    text = report.markdown(actuator, [])
    assert '## Both measured outputs' in text and '| pressure `p` (Pa) |' in text
    assert '| force `f` (N) |' in text and "figures above are the pressure's" in text
    assert 'tau_prev' not in text               # the segment's torques are not the actuator's
