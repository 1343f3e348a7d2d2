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
Every input is bounded (issue #30, class 5): numbers, effects, files.

- A numeric option or an effect strength takes the range of the node parameter it matches
  (`config.ranges`: one table for the CLI and the nodes); nan and inf are refused wherever a
  finite number is meant; the same effect or effect parameter given twice is refused.
- A file the package reads has limits of size and structure (CSV rows, bytes and line length; YAML
  bytes, nesting and alias expansion; a bag's messages) and is a regular file: reading stops
  with one line naming the limit, never a traceback, minutes of work or a machine out of memory.
- CSV cells are plain decimal numbers: Python's `1_0`, `0x10`, `infinity` and other scripts'
  digits are named, not read.
Each case: exit 2, one line on stderr, no traceback, nothing written.
"""

import errno
import os
from pathlib import Path
import shlex
import threading

from hypothesis import given, HealthCheck, settings, strategies as st
import numpy as np
import pytest
from tables import write_csv

from bellows_ros.cli import main
from bellows_ros.config.actuator import (EFFECT_RANGES, load_actuator_params,
                                         load_actuator_plant_params)
from bellows_ros.errors import BellowsError, DataError, ParameterError
from bellows_ros.io import data, params
from bellows_ros.papers.actuator_experiments import actuator_record


@pytest.fixture(scope='module')
def workdir(tmp_path_factory):
    root = tmp_path_factory.mktemp('bounds')
    record = actuator_record(load_actuator_params(), load_actuator_plant_params(), seed=3,
                             duration=0.3)
    write_csv(root / 'r.csv', record)
    t = np.arange(400) * 1e-3
    write_csv(root / 's.csv', {'t': t, 'psi': 0.3 * np.sin(t * 5), 'p1': 2e5 + 0 * t,
                               'p2': 1.2e5 + 0 * t, 'tau_ext': 0 * t})
    return root


def run(argv, capsys):
    try:
        status = main(argv)
    except SystemExit as exit_:
        status = exit_.code
    err = capsys.readouterr().err
    return status, err


def assert_one_line(status, err, *fragments):
    assert status == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and 'Traceback' not in err, err
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


SIM = 'simulate actuator --input r.csv --output o.csv '
SEG = 'simulate segment --input s.csv --output o.csv '
# (arguments, fragments of the one error line)
OPTIONS = [
    ('stiffness r.csv --window inf', ['--window', 'finite']),
    ('stiffness r.csv --window nan', ['--window', 'finite']),
    ('stiffness r.csv --window 1e-9', ['--window', 'range']),
    ('stiffness r.csv --window 1e9', ['--window', 'range']),
    ('stiffness r.csv --setpoint nan', ['--setpoint', 'finite']),
    ('stiffness r.csv --setpoint inf', ['--setpoint', 'finite']),
    ('stiffness r.csv --setpoint -1', ['--setpoint', 'range']),
    ('stiffness r.csv --setpoint 0', ['--setpoint', 'range']),
    ('stiffness r.csv --window 0.01', ['fewer than 20 samples']),
    ('record --output bag --duration inf', ['--duration', 'finite']),
    ('record --output bag --duration 1e300', ['--duration', 'range']),
    ('record --output bag --topics /joint_states /joint_states', ['/joint_states', 'twice']),
    (SIM + '--effect air_leak:conductance=1e30', ['conductance', 'range']),
    (SIM + '--effect wall_bulging:scale=1e300', ['scale', 'range']),
    (SIM + '--effect backlash:width=1', ['width', 'range 0..0.01 m']),
    (SIM + '--effect heat_exchange:gamma=3', ['gamma', 'range']),
    (SIM + '--effect air_leak:conductance=nan', ['conductance', 'finite']),
    (SIM + '--effect air_leak:conductance=inf', ['conductance', 'finite']),
    (SIM + '--effect air_leak:conductance=1_0', ['conductance', 'decimal']),
    (SIM + '--effect air_leak:conductance=0x10', ['conductance', 'decimal']),
    (SIM + '--effect air_leak --effect air_leak', ['air_leak', 'twice']),
    (SIM + '--effect air_leak:conductance=1e-9,conductance=2e-9', ['conductance', 'twice']),
    (SEG + '--effect sensor_lag:tau=1e30', ['tau', 'range']),
    (SEG + '--effect pressure_friction:c_fp=-1', ['c_fp', 'range']),
    (SEG + '--effect natural_curvature:c_psi0_p=100', ['c_psi0_p', 'range']),
    (SEG + '--effect sensor_lag --effect sensor_lag', ['sensor_lag', 'twice']),
]


@pytest.mark.parametrize('arguments, fragments', OPTIONS, ids=[a for a, _ in OPTIONS])
def test_a_number_out_of_its_range_is_one_line_before_any_work(workdir, monkeypatch, capsys,
                                                               arguments, fragments):
    monkeypatch.chdir(workdir)
    status, err = run(shlex.split(arguments), capsys)
    assert_one_line(status, err, *fragments)
    assert not (workdir / 'o.csv').exists() and not (workdir / 'bag').exists()


ACTUATOR_EFFECT_KEYS = sorted(name[len('actuator.effects.'):] for name in EFFECT_RANGES)


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.sampled_from(ACTUATOR_EFFECT_KEYS),
       st.one_of(st.floats(), st.sampled_from([0.0, 1e-12, 1e30, -1e-300, 5e-3, 1.0])))
def test_an_effect_value_runs_iff_the_nodes_range_holds_it(workdir, monkeypatch, capsys, key,
                                                           value):
    """The CLI's range of an effect parameter is the YAML's, which the node's strength takes."""
    monkeypatch.chdir(workdir)
    effect, parameter = key.split('.')
    rule = EFFECT_RANGES['actuator.effects.' + key]
    status, err = run(['simulate', 'actuator', '--input', 'r.csv', '--output', 'o.csv',
                       '--effect', f'{effect}:{parameter}={value!r}'], capsys)
    inside = rule.low <= value <= rule.high
    if status == 0:
        assert inside, (key, value)
        (workdir / 'o.csv').unlink()
    else:
        assert_one_line(status, err)
        assert not (workdir / 'o.csv').exists()
        if not inside:
            assert parameter in err


# --- CSV cells ----------------------------------------------------------------------------------
@pytest.mark.parametrize('cell, needle', [
    ('1_0', "not a number: '1_0'"), ('0x10', "not a number: '0x10'"),
    ('\u0661', "not a number: '\u0661'"), ('infinity', 'infinity is not a finite number'),
    ('1e5.5', "not a number: '1e5.5'"), ('- 1', "not a number: '- 1'"),
])
@pytest.mark.parametrize('extra', [False, True], ids=['fast path', 'careful path'])
def test_a_cell_python_reads_and_no_instrument_writes_is_named(tmp_path, cell, needle, extra):
    rows = [['0.0', '1.0'], ['0.001', cell], ['0.002', '3.0']]
    header = 't,x_c' + (',note' if extra else '')
    text = header + '\n' + ''.join(','.join(row + (['n'] if extra else [])) + '\n'
                                   for row in rows)
    path = tmp_path / 'd.csv'
    path.write_text(text)
    with pytest.raises(DataError, match=f"d.csv:3: column 'x_c': {needle}"):
        data.read_csv(path, ('t', 'x_c'))


@pytest.mark.parametrize('cell, value', [(' 2.5 ', 2.5), ('+3', 3.0), ('.5', 0.5), ('5.', 5.0),
                                         ('1E5', 1e5), ('\t7', 7.0), ('-0', 0.0)])
def test_plain_decimal_numbers_are_read(tmp_path, cell, value):
    path = tmp_path / 'd.csv'
    path.write_text(f't,x_c\n0,1\n1,{cell}\n')
    assert data.read_csv(path, ('t', 'x_c'))['x_c'][1] == value


# --- files that are no regular file, or too large -----------------------------------------------
def fifo_with_endless_writer(path):
    """Make a FIFO whose writer sends a header and then rows, forever: a read never ends."""
    os.mkfifo(path)
    stop = threading.Event()

    def write():
        try:
            fd = os.open(path, os.O_WRONLY)
        except OSError:
            return
        try:
            os.write(fd, b't,x_c,x_s,p,f\n')
            k = 0
            while not stop.is_set():
                os.write(fd, f'{k * 1e-3},0,0,1e5,0\n'.encode() * 100)
                k += 1
        except OSError:
            pass
        finally:
            os.close(fd)
    thread = threading.Thread(target=write, daemon=True)
    thread.start()
    return stop


@pytest.mark.timeout(60)
@pytest.mark.parametrize('arguments', [
    'simulate actuator --input {f} --output o.csv',
    'identify actuator {f} --output p.yaml --quiet',
    'diagnose actuator {f} --report rep --quiet',
    'export actuator {f} --output o.csv',
    'stiffness {f}',
    'simulate actuator --input r.csv --output o.csv --params {f}',
])
def test_an_input_that_never_ends_is_refused(workdir, tmp_path, monkeypatch, capsys, arguments):
    monkeypatch.chdir(workdir)
    fifo = tmp_path / 'endless'
    stop = fifo_with_endless_writer(fifo)
    try:
        status, err = run(shlex.split(arguments.format(f=fifo)), capsys)
    finally:
        stop.set()
        with open(fifo, 'rb') as drain:  # let the writer thread see the end, if it waits
            drain.read(1)
    assert_one_line(status, err, str(fifo), 'regular file')
    assert not (workdir / 'o.csv').exists() and not (workdir / 'p.yaml').exists()


def test_a_line_over_the_limit_is_named_with_its_line(tmp_path):
    path = tmp_path / 'd.csv'
    path.write_bytes(b't,x_c,note\n0,1,a\n1,2,' + b'x' * (data.MAX_LINE_BYTES + 10) + b'\n')
    for read in (lambda: data.read_csv(path, ('t', 'x_c')),
                 lambda: list(data.read_chunks(path, 'actuator', ('t', 'x_c')))):
        with pytest.raises(DataError, match=r'd\.csv:3: a line longer than 1 MiB'):
            read()


def test_a_file_over_the_whole_table_limit_is_refused_before_reading(tmp_path, monkeypatch):
    path = write_csv(tmp_path / 'd.csv', {'t': np.arange(100) * 1e-3, 'x_c': np.zeros(100)})
    monkeypatch.setattr(data, 'MAX_TABLE_BYTES', 1000)
    with pytest.raises(DataError, match=r'MAX_TABLE_BYTES'):
        data.read_csv(path, ('t', 'x_c'))


def test_a_record_over_the_row_limit_is_refused_before_work(tmp_path, monkeypatch):
    t = np.arange(300) * 1e-3
    path = write_csv(tmp_path / 'd.csv', {'t': t, 'x_c': 0.01 + 0 * t, 'x_s': 0.002 + 0 * t,
                                          'p': 1.2e5 + 0 * t, 'f': 3 + 0 * t})
    monkeypatch.setattr(data, 'MAX_RECORD_ROWS', 100)
    with pytest.raises(DataError, match=r'over 100 rows'):
        data.read_record(path, 'actuator')
    with pytest.raises(DataError, match=r'over 100 rows'):
        list(data.read_chunks(path, 'actuator', rows=50))


def test_a_binary_file_is_named_without_its_bytes(workdir, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(workdir)
    garbage = tmp_path / 'photo.jpg'
    garbage.write_bytes(b'\xff\xd8\xff\xe0' + bytes(range(256)) * 200)
    for argv in (['simulate', 'actuator', '--input', str(garbage), '--output', 'o.csv'],
                 ['export', 'actuator', str(garbage), '--output', 'o.csv'],
                 ['stiffness', str(garbage)]):
        status, err = run(argv, capsys)
        assert_one_line(status, err, 'not a CSV text file')
        assert len(err) < 300 and '\\x' not in err and '\ufffd' not in err, err


def test_an_error_shows_a_long_cell_cut_short(tmp_path):
    path = tmp_path / 'd.csv'
    path.write_text('t,x_c\n0,1\n1,' + 'z' * 5000 + '\n')
    with pytest.raises(DataError) as error:
        data.read_csv(path, ('t', 'x_c'))
    assert len(str(error.value)) < 200 + len(str(path)), str(error.value)


def test_a_read_error_mid_file_is_one_line(tmp_path, monkeypatch):
    """EIO half-way through a record (a failing disk, a dropped network mount)."""
    t = np.arange(300) * 1e-3
    path = Path(write_csv(tmp_path / 'd.csv', {'t': t, 'x_c': 0.01 + 0 * t, 'x_s': 0.002 + 0 * t,
                                               'p': 1.2e5 + 0 * t, 'f': 3 + 0 * t}))

    class Failing:
        def __init__(self, stream):
            self.stream, self.lines = stream, 0

        def readline(self, *size):
            self.lines += 1
            if self.lines > 100:
                raise OSError(errno.EIO, os.strerror(errno.EIO))
            return self.stream.readline(*size)

        def __iter__(self):
            return iter(self.readline, b'')

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.stream.close()

    real_open = type(path).open

    def failing_open(self, *args, **kwargs):
        return Failing(real_open(self, *args, **kwargs))
    monkeypatch.setattr(type(path), 'open', failing_open)
    with pytest.raises(DataError, match='cannot read file .Input/output error.'):
        list(data.read_chunks(path, 'actuator', rows=50))


# --- YAML ---------------------------------------------------------------------------------------
def laughs(levels=9):
    text = '/**:\n  ros__parameters:\n    a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n'
    previous = 'a'
    for level in range(levels):
        text += f'    b{level}: &b{level} [' + ', '.join([f'*{previous}'] * 10) + ']\n'
        previous = f'b{level}'
    return text


@pytest.mark.timeout(60)
@pytest.mark.parametrize('text, needle', [
    (laughs(), 'aliases expanded'),
    ('/**:\n  ros__parameters:\n    a: ' + '[' * 5000 + ']' * 5000 + '\n', 'nested deeper'),
    ('/**:\n  ros__parameters:\n' + '    # padding\n' * 200_000, 'MAX_YAML_BYTES'),
])
def test_a_parameter_file_beyond_the_yaml_limits_is_one_line(workdir, tmp_path, monkeypatch,
                                                             capsys, text, needle):
    monkeypatch.chdir(workdir)
    path = tmp_path / 'p.yaml'
    path.write_text(text)
    with pytest.raises(ParameterError, match=needle):
        params.read_sections(path)
    status, err = run(['simulate', 'actuator', '--input', 'r.csv', '--output', 'o.csv',
                       '--params', str(path)], capsys)
    assert_one_line(status, err, str(path), needle)


@pytest.mark.timeout(60)
def test_a_bag_metadata_beyond_the_yaml_limits_is_one_line(tmp_path, capsys):
    bag = tmp_path / 'bag'
    bag.mkdir()
    (bag / 'metadata.yaml').write_text(laughs().replace('/**:\n  ros__parameters:\n',
                                                        'rosbag2_bagfile_information:\n'))
    status, err = run(['export', 'actuator', str(bag), '--output', str(tmp_path / 'o.csv')],
                      capsys)
    assert_one_line(status, err, 'metadata.yaml', 'aliases expanded')


def test_a_bag_over_the_message_limit_is_refused_before_reading(tmp_path, monkeypatch):
    from test_io_bag_lock import write_bag

    from bellows_ros.io import bag as bag_reader
    monkeypatch.setattr(bag_reader, 'MAX_BAG_MESSAGES', 100)
    for layout, n in (('sample', 150), ('split', 50)):  # split: 3 topics, each counted
        path = write_bag(tmp_path / layout, n=n, layout=layout)
        with pytest.raises(BellowsError, match=r'150 messages .* over 100'):
            data.read_table(path, 'actuator')


@pytest.mark.parametrize('module, system', [('sim_actuator_node', 'actuator'),
                                            ('sim_arm_node', 'segment')])
def test_the_nodes_strengths_and_the_cli_effects_share_their_ranges(module, system):
    """A strength the node takes live is one `--effect` takes too (0 = off only on the node)."""
    from importlib import import_module

    effect_range = import_module(f'bellows_ros.config.{system}').effect_range
    specs = getattr(import_module(f'bellows_ros.nodes.{module}'), 'PARAMETERS', None)
    if specs is None:
        pytest.skip(f'{module} has no PARAMETERS table (rewritten): compare its ranges by hand')
    strengths = [spec for spec in specs if spec.name.startswith('effect.')]
    assert strengths
    for spec in strengths:
        _, effect, key = spec.name.split('.')
        rule = effect_range(effect, key)
        assert spec.high == rule.high, spec.name
        assert spec.low <= rule.low and spec.low in (0.0, rule.low), spec.name


@pytest.mark.parametrize('compression', ['zstd', 'lz4'])
def test_a_chunk_inflates_no_further_than_it_declares(compression):
    # 64 MiB of zeros compress to a few kilobytes: a bomb for a reader that inflates first.
    import lz4.frame
    from rosbags.rosbag2 import storage_mcap

    from bellows_ros.io import bag  # noqa: F401 (bounds rosbags' decompressors)
    compress = {'zstd': storage_mcap.zstd.compress, 'lz4': lz4.frame.compress}[compression]
    bomb = compress(bytes(64 * 2**20))
    assert len(bomb) < 2**20
    inflated = storage_mcap.DECOMPRESSORS[compression](bomb, 1000)
    assert len(inflated) == 1001    # rosbags then refuses the chunk: its size is not the declared
    with pytest.raises(ValueError, match='MAX_CHUNK_BYTES'):
        storage_mcap.DECOMPRESSORS[compression](bomb, 2**40)


def test_a_bag_with_a_chunk_over_the_limit_is_refused(tmp_path, monkeypatch, capsys):
    from test_io_bag_lock import write_bag

    from bellows_ros.io import bag as bag_reader
    path = write_bag(tmp_path / 'bag', n=200)
    monkeypatch.setattr(bag_reader, 'MAX_CHUNK_BYTES', 1000)
    status, err = run(['export', 'actuator', str(path), '--output', str(tmp_path / 'o.csv')],
                      capsys)
    assert_one_line(status, err, str(path), 'bag.MAX_CHUNK_BYTES')
    assert not (tmp_path / 'o.csv').exists()
