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
Bad input to the readers: one line naming the file (exit 2 at the CLI), never a traceback.

Never a number read in the wrong unit either.

The rosbag2 recordings are written here with rosbags' own writer and the ROS 2 Jazzy type store.
"""
import math
import subprocess
import sys
import warnings

from bag_messages import (ACTUATOR_LAYOUTS, ARM_LAYOUTS, wrench, write_actuator_bag,
                          write_arm_bag, write_bag)
import numpy as np
import pytest
from rosbags.rosbag2 import StoragePlugin
import yaml

from bellows_ros.cli import main as bellows
from bellows_ros.errors import DataError, ParameterError
from bellows_ros.io import data, params


def actuator_rows(n=20, p_scale=1.0):
    start = 5 * 10 ** 9
    return [(start + k * 1_000_000, 0.01 + 1e-4 * k, 0.002, (1.2e5 + 100.0 * k) * p_scale,
             3.0 + 0.1 * k) for k in range(n)]


def arm_rows(n=20):
    """(stamp ns, psi, psi_dot, p1, p2, tau_ext) of segment_1 at 1 kHz."""
    start = 5 * 10 ** 9
    return [(start + k * 1_000_000, 0.3 * math.sin(k / 9), 0.3 / 9 * math.cos(k / 9),
             2e5 + 300.0 * k, 1.5e5 - 200.0 * k, -0.01 * k) for k in range(n)]


def write_csv(path, header, rows):
    path.write_text(header + '\n' + ''.join(','.join(repr(float(v)) for v in row) + '\n'
                                            for row in rows))
    return path


def segment_rows(n=100, p_scale=1.0, angle_scale=1.0, dt=0.01):
    t = np.arange(n) * dt
    return np.column_stack([t, 0.5 * np.sin(t) * angle_scale,
                            (101325.0 + 2e5 * (1 + np.sin(t))) * p_scale,
                            (101325.0 + 1e5 * (1 + np.cos(t))) * p_scale, 0.1 * np.sin(t)])


def run_cli(argv, capsys):
    """Exit status and stderr of the `bellows` command run in this process."""
    status = bellows(argv)
    return status, capsys.readouterr().err


def assert_one_line(err, *needles):
    assert err.count('\n') == 1 and 'Traceback' not in err, err
    for needle in needles:
        assert needle in err, err


# --- rosbag2 directories ------------------------------------------------------------------------

@pytest.mark.parametrize('metadata, needle', [
    ('rosbag2_bagfile_information:\n  version: [1, 2\n',
     "metadata.yaml:3: not valid YAML: expected ','"),
    ('rosbag2_bagfile_information:\n  version: \xe3\n', 'metadata.yaml: not valid YAML: '),
    ('foo: 1\n', "metadata.yaml: no 'rosbag2_bagfile_information' map"),
    ('', "metadata.yaml: no 'rosbag2_bagfile_information' map"),
    ('rosbag2_bagfile_information: {version: 8}\n', 'cannot open the rosbag2 recording ('),
])
@pytest.mark.parametrize('command', ['identify', 'diagnose'])
def test_a_broken_metadata_file_is_one_line_and_exit_2(tmp_path, capsys, metadata, needle,
                                                       command):
    bag = tmp_path / 'bag'
    bag.mkdir()
    (bag / 'metadata.yaml').write_bytes(metadata.encode('latin-1'))
    out = ['--output', str(tmp_path / 'o.yaml')] if command == 'identify' \
        else ['--report', str(tmp_path / 'report')]
    status, err = run_cli([command, 'actuator', str(bag), '--quiet', *out], capsys)
    assert status == 2
    assert_one_line(err, f'bellows {command}: error: {bag}', needle)


def test_a_directory_without_metadata_is_not_a_bag(tmp_path):
    (tmp_path / 'empty').mkdir()
    with pytest.raises(DataError, match=r'empty: not a rosbag2 directory \(it has no metadata'):
        data.read_table(tmp_path / 'empty', 'actuator')


@pytest.mark.parametrize('storage', [StoragePlugin.SQLITE3, StoragePlugin.MCAP])
def test_a_truncated_storage_file_is_one_line(tmp_path, storage):
    bag = tmp_path / 'bag'
    write_actuator_bag(bag, actuator_rows(200), storage)
    assert len(data.read_table(bag, 'actuator')) == 200  # whole, it reads
    (stored,) = [f for f in bag.iterdir() if f.name != 'metadata.yaml']
    stored.write_bytes(stored.read_bytes()[:len(stored.read_bytes()) // 2])
    with pytest.raises(DataError) as error:
        data.read_table(bag, 'actuator')
    assert str(error.value).startswith(str(bag)) and '\n' not in str(error.value)


def test_a_topic_of_the_wrong_type_is_named(tmp_path):
    write_bag(tmp_path / 'bag', [[('/actuator/joint_states', wrench(ns, x_c))]
                                 for ns, x_c, *_ in actuator_rows()])
    with pytest.raises(DataError, match='/actuator/joint_states holds geometry_msgs/msg/'
                                        'WrenchStamped, expected sensor_msgs/msg/JointState'):
        data.read_table(tmp_path / 'bag', 'actuator')


@pytest.mark.parametrize('system', ['segment', 'actuator'])
def test_the_same_samples_in_every_format_read_and_export_alike(tmp_path, capsys, system):
    """
    One message per sample, and the older formats (pressures and force on topics of their own).

    A value the sample lacks (NaN in a sample message, no message on a topic of its own) is held
    alike, and marked alike as held.
    """
    if system == 'segment':
        rows, layouts, write, lacks = arm_rows(50), ARM_LAYOUTS, write_arm_bag, (3, 4)
    else:
        rows, layouts, write, lacks = actuator_rows(50), ACTUATOR_LAYOUTS, write_actuator_bag, (3,)
    rows = [list(row) for row in rows]
    for k in (0, 20, 21, 22):  # the first sample, and three in a row: held, within the limit
        for column in lacks:
            rows[k][column] = None
    rows[30][-1] = None  # the force or torque
    tables = {}
    for layout in layouts:
        write(tmp_path / layout, rows, layout=layout)
        tables[layout] = data.read_table(tmp_path / layout, system)
        status, err = run_cli(['export', system, str(tmp_path / layout), '--output',
                               str(tmp_path / f'{layout}.csv')], capsys)
        assert status == 0 and '50 rows' in err, err
    now = tables['sample']
    for layout in layouts:
        assert tables[layout].names == now.names and tables[layout].held.keys() == now.held.keys()
        for name in now.names:
            np.testing.assert_array_equal(tables[layout][name], now[name], err_msg=name)
        for name, (_, age, step) in now.held.items():
            np.testing.assert_array_equal(tables[layout].held[name][1], age, err_msg=name)
            assert tables[layout].held[name][2] == step
        assert (tmp_path / f'{layout}.csv').read_text() == (tmp_path / 'sample.csv').read_text()
    # Held: the first sample's from the next, the three's from the one before them.
    lacked, force = {'segment': ('p1', 'tau_ext'), 'actuator': ('p', 'f')}[system]
    assert now[lacked][0] == rows[1][lacks[0]] and now[lacked][22] == rows[19][lacks[0]]
    assert now[force][30] == rows[29][-1]


def test_a_force_no_sample_holds_is_refused_as_a_missing_wrench_was(tmp_path):
    rows = [(ns, x_c, x_s, p, None) for ns, x_c, x_s, p, _ in actuator_rows()]
    for layout, needle in (('sample', 'no effort of spring on /actuator/joint_states: NaN in '
                                      'every message'),
                           ('split', "no messages on /bellows/wrench with frame_id 'actuator'")):
        write_actuator_bag(tmp_path / layout, rows, layout=layout)
        with pytest.raises(DataError, match=needle):
            data.read_table(tmp_path / layout, 'actuator')


# In a sample message a NaN pressure or force is one the device did not measure (the test above).
NON_FINITE = [(layout, column, bad) for layout in ('sample', 'split') for column in (1, 3, 4)
              for bad in (math.nan, math.inf, -math.inf)
              if not (layout == 'sample' and column > 1 and math.isnan(bad))]


@pytest.mark.parametrize('layout, column, bad', NON_FINITE)  # column: x_c, p, f
def test_a_non_finite_value_in_a_bag_is_refused_like_in_a_csv(tmp_path, layout, column, bad):
    rows = [list(row) for row in actuator_rows()]
    rows[7][column] = bad
    write_actuator_bag(tmp_path / 'bag', rows, layout=layout)
    name = {1: 'x_c', 3: 'p', 4: 'f'}[column]
    with pytest.raises(DataError, match=rf"column '{name}': {bad} is not a finite number \(stamp "
                                        rf'{rows[7][0]} ns\)'):
        data.read_table(tmp_path / 'bag', 'actuator')


def test_stamps_that_repeat_are_refused(tmp_path):
    rows = actuator_rows()
    rows[5] = (rows[4][0],) + rows[5][1:]
    write_actuator_bag(tmp_path / 'bag', rows)
    with pytest.raises(DataError, match="column 't': not increasing"):
        data.read_table(tmp_path / 'bag', 'actuator')


# --- units --------------------------------------------------------------------------------------

@pytest.mark.parametrize('scale, unit', [(1e-2, 'hPa'), (1e-3, 'kPa'), (1e-5, 'bar')])
def test_pressures_in_kpa_or_bar_are_named_as_a_unit_mistake(tmp_path, capsys, scale, unit):
    path = write_csv(tmp_path / f'in_{unit}.csv', 't,psi,p1,p2,tau_ext',
                     segment_rows(p_scale=scale))
    status, err = run_cli(['identify', 'segment', str(path), '--output', str(tmp_path / 'o.yaml'),
                           '--quiet'], capsys)
    assert status == 2
    assert_one_line(err, f"in_{unit}.csv: column 'p1': every value is below 20000 Pa",
                    'pressures are absolute, in Pa - was the file written in hPa, kPa or bar?')
    assert not (tmp_path / 'o.yaml').exists()


def test_gauge_pressures_are_named_as_a_unit_mistake(tmp_path, capsys):
    # A gauge sensor reads 0 at ambient: the chains start vented, then pressurise.
    rows = [(t, psi, p1 - 301325.0, p2, tau) for t, psi, p1, p2, tau in segment_rows()]
    path = write_csv(tmp_path / 'gauge.csv', 't,psi,p1,p2,tau_ext', rows)
    status, err = run_cli(['identify', 'segment', str(path), '--output', str(tmp_path / 'o.yaml'),
                           '--quiet'], capsys)
    assert status == 2
    assert_one_line(err, "gauge.csv:2: column 'p1'", 'was the file written as gauge pressure?')


@pytest.mark.parametrize('scale', [1e-3, 1e-5])
def test_actuator_pressures_in_kpa_or_bar_are_refused_from_csv_and_bag(tmp_path, scale):
    rows = actuator_rows(p_scale=scale)
    path = write_csv(tmp_path / 'in.csv', 't,x_c,x_s,p,f',
                     [((ns - rows[0][0]) * 1e-9, *rest) for ns, *rest in rows])
    write_actuator_bag(tmp_path / 'bag', rows)
    for source in (path, tmp_path / 'bag'):
        with pytest.raises(DataError, match="column 'p': every value is below 20000 Pa"):
            data.read_table(source, 'actuator')


def test_the_same_pressures_in_pa_are_accepted(tmp_path):
    rows = segment_rows()
    table = data.read_table(write_csv(tmp_path / 'in.csv', 't,psi,p1,p2,tau_ext', rows), 'segment')
    np.testing.assert_array_equal(table['p1'], rows[:, 2])
    # A simulation input without pressures it reads (p, f are outputs there) is not checked.
    act = [(k * 1e-3, 0.01, 0.002, 0.0, 0.0) for k in range(5)]
    table = data.read_table(write_csv(tmp_path / 'a.csv', 't,x_c,x_s,p,f', act), 'actuator',
                            ('t', 'x_c', 'x_s'))
    assert len(table) == 5


def test_angles_in_degrees_are_named_as_a_unit_mistake(tmp_path):
    rows = segment_rows(angle_scale=180 / math.pi)
    path = write_csv(tmp_path / 'deg.csv', 't,psi,p1,p2,tau_ext', rows)
    # 0.5 sin(t) rad written as 28.6 sin(t) degrees: the first row past pi is named (header: 1)
    line = int(np.flatnonzero(rows[:, 1] > math.pi)[0]) + 2
    assert 2 < line < len(rows)  # the rows before it are within a half turn, so not the first row
    with pytest.raises(DataError, match=rf"deg\.csv:{line}: column 'psi': 3\.\d+ is beyond a "
                                        'half turn: angles are in rad - was the file written in '
                                        'degrees'):
        data.read_table(path, 'segment')


# --- CSV ----------------------------------------------------------------------------------------

def test_a_header_only_csv_gives_its_error_and_no_warning(tmp_path):
    path = tmp_path / 'h.csv'
    path.write_text('t,x_c,x_s,p,f\n')
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        with pytest.raises(DataError, match=r'h\.csv:2: no data rows after the header'):
            data.read_table(path, 'actuator')
    assert [str(w.message) for w in caught] == []


@pytest.mark.slow
def test_the_cli_prints_only_the_error_for_a_header_only_csv(tmp_path):
    (tmp_path / 'h.csv').write_text('t,x_c,x_s,p,f\n')
    command = 'import sys; from bellows_ros.cli import main; sys.exit(main())'
    result = subprocess.run([sys.executable, '-c', command, 'identify', 'actuator', 'h.csv',
                             '--output', 'o.yaml', '--quiet'], cwd=tmp_path,
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2
    assert result.stderr == 'bellows identify: error: h.csv:2: no data rows after the header\n'


@pytest.mark.parametrize('text, needle', [
    ('t,a,a\n0,1,5\n1,2,6\n', r"d\.csv:1: column 'a' appears twice in the header"),
    ('t,a\n0,1 # note\n1,2\n', r"d\.csv:2: column 'a': not a number: '1 # note'"),
    ('t,a,n\n0,1,' + 'x' * 200_000 + '\n1,2,y\n', r'd\.csv:2: field larger than field limit'),
])
def test_csv_mistakes_are_one_line_not_a_traceback_or_a_guess(tmp_path, text, needle):
    path = tmp_path / 'd.csv'
    path.write_text(text)
    with pytest.raises(DataError, match=needle):
        data.read_csv(path, ('t', 'a'))


def test_a_byte_order_mark_is_not_part_of_the_first_column_name(tmp_path):
    path = tmp_path / 'bom.csv'
    path.write_bytes('\ufefft,a\n0,1\n1,2\n'.encode())
    np.testing.assert_array_equal(data.read_csv(path, ('t', 'a'))['a'], [1.0, 2.0])


# --- parameter files ----------------------------------------------------------------------------

def _check_named(tmp_path, capsys, system, body, needle):
    """`bellows simulate SYSTEM --params` with `body` under `SYSTEM:`: one line naming it."""
    user = tmp_path / 'u.yaml'
    user.write_text('/**:\n  ros__parameters:\n    ' + system + ': {' + body + '}\n')
    status, err = run_cli(['simulate', system, '--input', str(tmp_path / 'none.csv'),
                           '--output', str(tmp_path / 'o.csv'), '--params', str(user)], capsys)
    assert status == 2
    assert_one_line(err, f'{user}: parameter {needle}')


@pytest.mark.parametrize('body, needle', [
    ('p_max: high', "'segment.p_max' expects a number (like 750000.0), got 'high'"),
    ('p_max: true', "'segment.p_max' expects a number (like 750000.0), got True"),
    ('p_max: [1.0, 2.0]', "'segment.p_max' expects a number (like 750000.0), got [1.0, 2.0]"),
    ('ogden: {mu: 5.0}', "'segment.ogden.mu' expects a list (like [4000.0, 400.0]), got 5.0"),
    ('ogden: {mu: [a, 400.0]}', "'segment.ogden.mu' expects a list of numbers (like [4000.0, "
                                "400.0]), got 'a' in it"),
    ('p_max: 1' + '0' * 400, "'segment.p_max' is beyond float range"),
    ('dynamics: {inertia: -1.0}', "'segment.dynamics.inertia' is -1, outside its physical "
                                  'range 0..100'),
])
def test_a_parameter_of_the_wrong_kind_is_named(tmp_path, capsys, body, needle):
    _check_named(tmp_path, capsys, 'segment', body, needle)


@pytest.mark.parametrize('body, needle', [
    ('air_chamber: {h0: 0.0}', "'actuator.air_chamber.h0' is 0, outside its physical range "
                               '0.001..1 m'),
    ('spring: {n: 4.5}', "'actuator.spring.n' must be a whole number of segments in 1..1000, "
                         'got 4.5'),
    ('air_chamber: {r_small: 0.03}', "'actuator.air_chamber.r_big' must exceed r_small > 0"),
    ('air_chamber: {x_max: 0.2}', "'actuator.air_chamber.x_max' must exceed x_min and stay below "
                                  'n*h0 = 0.0746 m'),
    ('air_chamber: {x_min: -0.2}', "'actuator.air_chamber.x_min' -0.2 m lies beyond the frustum "
                                   'geometry (3)'),
    ('gas: {x_c_ref: 0.047, p_ref: 0.0}', "'actuator.gas.p_ref' is 0, outside its physical range"),
])
def test_an_inadmissible_actuator_parameter_is_named(tmp_path, capsys, body, needle):
    _check_named(tmp_path, capsys, 'actuator', body, needle)


def test_a_parameter_of_the_right_kind_is_laid_over_the_defaults(tmp_path):
    user = tmp_path / 'u.yaml'
    user.write_text('/**:\n  ros__parameters:\n'
                    '    segment: {p_max: 700000, ogden: {mu: [3, 4]}}\n')
    flat = params.load('segment', user)
    assert flat['segment.p_max'] == 700000 and flat['segment.ogden.mu'] == [3, 4]
    with pytest.raises(ParameterError):
        params.overlay({'a': 1.0}, {'a': 'x'}, 'src')


def test_a_good_bag_reads_back_what_was_written(tmp_path):
    """The bags the tests above spoil read, whole, to exactly what was written."""
    rows = actuator_rows()
    write_actuator_bag(tmp_path / 'bag', rows)
    table = data.read_table(tmp_path / 'bag', 'actuator')
    np.testing.assert_allclose(table['t'], [(r[0] - rows[0][0]) * 1e-9 for r in rows])
    for i, name in enumerate(('x_c', 'x_s', 'p', 'f'), start=1):
        np.testing.assert_array_equal(table[name], [r[i] for r in rows])


@pytest.mark.parametrize('name', ['a\nb', '', 'a..b', 'a b'])
def test_a_name_that_is_no_parameter_name_is_one_line(tmp_path, name):
    """Found by the YAML fuzzing: a key holding a newline broke the one-line message."""
    path = tmp_path / 'p.yaml'
    path.write_text(yaml.safe_dump({'/**': {'ros__parameters': {name: 1.0}}}))
    with pytest.raises(ParameterError, match='is not a parameter name') as error:
        params.read_file(path)
    assert '\n' not in str(error.value) and repr(name) in str(error.value)


@pytest.mark.parametrize('rate', [100.0, 1000.0])
@pytest.mark.parametrize('command', ['identify', 'simulate', 'diagnose'])
def test_times_in_ms_are_named_as_a_unit_mistake(tmp_path, capsys, rate, command):
    """A record at 100 Hz or 1 kHz whose t was written in ms: steps of 10 or 1 'seconds'."""
    rows = [(row[0] * 1e3, *row[1:]) for row in segment_rows(dt=1.0 / rate)]
    path = write_csv(tmp_path / 'ms.csv', 't,psi,p1,p2,tau_ext', rows)
    output = tmp_path / 'out'
    arguments = {'identify': ['identify', 'segment', str(path), '--output', str(output),
                              '--quiet'],
                 'simulate': ['simulate', 'segment', '--input', str(path), '--output',
                              str(output)],
                 'diagnose': ['diagnose', 'segment', str(path), '--report', str(output)]}
    status, err = run_cli(arguments[command], capsys)
    assert status == 2
    assert_one_line(err, "ms.csv: column 't': the median time step is", 'written in ms?')
    assert not output.exists()


def test_a_record_at_the_slowest_device_rate_with_a_pause_is_not_refused(tmp_path):
    """100 Hz with a two-minute pause in it: the median step is still 0.01 s."""
    rows = [tuple(row) for row in segment_rows(dt=0.01)]
    half = len(rows) // 2
    rows = rows[:half] + [(row[0] + 120.0, *row[1:]) for row in rows[half:]]
    path = write_csv(tmp_path / 'pause.csv', 't,psi,p1,p2,tau_ext', rows)
    assert len(data.read_table(path, 'segment')) == len(rows)
