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
The checks of the data the doctor is given (doctor/checks.py), on arrays in memory.

Each refusal is a `DataError` naming the data by its source, in one line that says what is wrong;
a record that passes comes back evenly sampled (resampled when its stamps jitter), and block
means keep its columns aligned. Per cause, a segment record whose high pressures lie in the blocks
one fold holds out gets the same reason for every cause: its held-out score would extrapolate.
"""
import numpy as np
import pytest

from bellows_ros.doctor import checks
from bellows_ros.errors import DataError
from bellows_ros.io.table import Table
from bellows_ros.models.actuator_geometry import P_ATM
from bellows_ros.models.segment_effects import NAMES as SEGMENT_CAUSES

DT = 1e-3


def actuator_columns(seconds=10.0):
    """Return a chamber cycled by 10 mm, the spring still, the gas near ambient (SI units)."""
    t = np.arange(int(round(seconds / DT))) * DT
    return {'t': t, 'x_c': 0.01 * np.sin(t), 'x_s': 0 * t, 'p': P_ATM + 1e3 * np.sin(t),
            'f': 0 * t}


def segment_columns(seconds=10.0, pressurised=None):
    """
    Return a segment swinging ±0.3 rad, chain 1 at 1-5 bar gauge (SI units).

    `pressurised` (s, s): chain 1 is above ambient only in that span of time.
    """
    t = np.arange(int(round(seconds / DT))) * DT
    p1 = P_ATM + 2e5 * (1.0 + np.sin(2 * np.pi * t / 3.0))
    if pressurised is not None:
        p1 = np.where((t >= pressurised[0]) & (t < pressurised[1]), p1 + 1e5, P_ATM)
    return {'t': t, 'psi': 0.3 * np.sin(2 * np.pi * t / 4.0), 'p1': p1, 'p2': P_ATM + 0 * t,
            'tau_ext': 0.1 * np.sin(t)}


def checked(columns, system, source='rig 2'):
    return checks.checked_record(checks.as_table(columns, system, source), system)


@pytest.mark.parametrize('change, message', [
    (lambda d: d.pop('f'), "rig 2: column 'f': missing"),
    (lambda d: d.update(p=d['p'][:-1]), 'rig 2: the columns must be 1-D arrays of one length'),
    (lambda d: d.update(p=np.column_stack([d['p'], d['p']])), 'rig 2: the columns must be 1-D'),
    (lambda d: d['x_s'].__setitem__(7, np.inf), "rig 2: column 'x_s': inf is not a finite number"),
    (lambda d: d['t'].__setitem__(5, d['t'][4]), "rig 2: column 't': not increasing"),
])
def test_arrays_that_are_no_table_are_refused_naming_the_source(change, message):
    columns = actuator_columns()
    change(columns)
    with pytest.raises(DataError) as error:
        checks.as_table(columns, 'actuator', 'rig 2')
    assert str(error.value).startswith(message)
    assert '\n' not in str(error.value)


def test_a_mapping_becomes_a_table_of_the_systems_columns_and_a_table_passes_through():
    columns = dict(segment_columns(), psi_dot=np.zeros(10000), unknown=np.ones(10000))
    table = checks.as_table(columns, 'segment', 'bench run')
    assert isinstance(table, Table) and table.path == 'bench run'
    assert set(table.values) == {'t', 'psi', 'p1', 'p2', 'tau_ext', 'psi_dot'}  # optional kept
    assert checks.as_table(table, 'segment') is table


@pytest.mark.parametrize('change, message', [
    (lambda d: {k: v[:199] for k, v in d.items()}, 'only 199 samples; the doctor needs'),
    (lambda d: {k: v[:4000] for k, v in d.items()}, 'record lasts 4 s; the doctor needs at'),
    (lambda d: dict(d, p=np.where(d['t'] > 3.0, 5e6, d['p'])), "column 'p': 5e+06 Pa is out"),
    (lambda d: dict(d, x_c=0.02 + 0 * d['t']), "column 'x_c': not identifiable from this"),
])
def test_a_record_the_doctor_cannot_diagnose_is_refused(change, message):
    with pytest.raises(DataError) as error:
        checked(change(actuator_columns()), 'actuator')
    assert str(error.value).startswith('rig 2: ') and message in str(error.value)
    assert '\n' not in str(error.value)


def test_a_segment_angle_that_never_moves_by_a_degree_is_refused():
    columns = dict(segment_columns(), psi=np.radians(0.4) * np.sin(np.arange(10000) * DT))
    with pytest.raises(DataError, match="'psi': not identifiable.*never changes by 1 degree"):
        checked(columns, 'segment')


def test_a_gap_says_where_to_split_the_record():
    columns = actuator_columns()
    columns['t'] = np.where(columns['t'] > 4.0, columns['t'] + 0.5, columns['t'])
    with pytest.raises(DataError) as error:
        checked(columns, 'actuator')
    message = str(error.value)
    assert message.startswith("rig 2: column 't': gap of 0.501 s in the time column after t = 4 s")
    assert '--end 4`' in message and '--start 4.501' in message


def test_stamps_that_jitter_are_resampled_onto_an_even_grid():
    rng = np.random.default_rng(0)
    columns = actuator_columns()
    columns['t'] = columns['t'] + rng.uniform(-0.3, 0.3, len(columns['t'])) * DT
    columns['x_s'] = 0.002 * columns['t']                # linear in time: interpolated exactly
    record = checked(columns, 'actuator')
    assert record.resampled and record.dt == pytest.approx(DT, rel=0.02)
    np.testing.assert_allclose(np.diff(record['t']), record.dt, rtol=1e-9)
    np.testing.assert_allclose(record['x_s'], 0.002 * record['t'], rtol=0, atol=1e-12)
    steady = checked(actuator_columns(), 'actuator')
    assert not steady.resampled and steady.dt == pytest.approx(DT)
    np.testing.assert_array_equal(steady['x_c'], actuator_columns()['x_c'])


def test_block_means_keep_the_columns_aligned():
    record = checked(actuator_columns(), 'actuator')
    coarse = record.decimated(7)
    assert len(coarse) == len(record) // 7 and coarse.factor == 7
    assert coarse.dt == pytest.approx(7 * DT)
    np.testing.assert_allclose(coarse['x_c'][3], np.mean(record['x_c'][21:28]))
    np.testing.assert_allclose(coarse['t'][0], 3 * DT)       # the mean time of rows 0-6
    assert coarse.decimated(2).factor == 14 and record.decimated(1) is record
    assert 'x_c' in coarse and 'psi' not in coarse
    assert coarse.duration == pytest.approx(coarse['t'][-1] - coarse['t'][0])


def test_raw_chunks_are_checked_for_a_gap_across_their_border():
    columns = actuator_columns()
    raw = checks.RawChecks('actuator')

    def chunk(lo, hi, shift=0.0):
        values = {k: v[lo:hi] + (shift if k == 't' else 0.0) for k, v in columns.items()}
        return Table('big.csv', list(values), values, lines=list(range(lo + 2, hi + 2)))
    raw(chunk(0, 3000))
    raw(chunk(3000, 6000))
    with pytest.raises(DataError) as error:          # the next chunk starts 1 s late
        raw(chunk(6000, 9000, shift=1.0))
    assert str(error.value).startswith("big.csv:6002: column 't': gap of 1 s")
    hot = dict(columns, p=np.where(columns['t'] > 0.5, 3e6, columns['p']))
    with pytest.raises(DataError, match="big.csv:503: column 'p': 3e"):
        checks.RawChecks('actuator')(Table('big.csv', list(hot), hot,
                                           lines=list(range(2, 10002))))


def test_pressures_a_fold_never_trains_on_make_every_segment_cause_unscorable():
    # Chain 1 pressurised only in the last of the 20 blocks: fold 4 holds it out, and its refit
    # never sees the chains above ambient.
    record = checked(segment_columns(pressurised=(9.5, 10.0)), 'segment')
    reason = checks.pressure_coverage(record, P_ATM)
    assert 'without the blocks fold 4 holds out, only 0.00 bar' in reason
    assert 't = 9.5-10.0 s' in reason and 'extrapolation in pressure' in reason
    assert checks.identifiability(record, P_ATM) == dict.fromkeys(SEGMENT_CAUSES, reason)
    # A cause the record cannot show anyway keeps its own reason (an angle that never reverses).
    columns = segment_columns(pressurised=(9.5, 10.0))
    columns['psi'] = 0.03 * columns['t']
    reasons = checks.identifiability(checked(columns, 'segment'), P_ATM)
    assert reasons['contact_hysteresis'].startswith('the angle reverses only 0 time(s)')
    assert reasons['natural_curvature'] == reason


def test_a_record_pressurised_throughout_can_separate_the_causes_its_motion_shows():
    record = checked(segment_columns(), 'segment')
    assert checks.pressure_coverage(record, P_ATM) is None
    # swung both ways at pressures spanning 4 bar, with fast pressure changes: every cause
    assert checks.identifiability(record, P_ATM) == dict.fromkeys(SEGMENT_CAUSES)
    assert checks.identifiability(checked(actuator_columns(), 'actuator')) == {}
