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
Nothing lost: outputs are written whole or not at all, never over an input, checked before work.

The rules are in io/outputs.py; these tests drive them through the `bellows` command as a
user would (in a subprocess where a signal or a read-only file system is part of the case).
"""
import csv
import hashlib
import os
from pathlib import Path
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from bellows_ros.cli import main
from bellows_ros.config.actuator import load_actuator_params, load_actuator_plant_params
from bellows_ros.errors import BellowsError
from bellows_ros.io.outputs import atomic_file, MANIFEST, report_directory
from bellows_ros.papers.actuator_experiments import actuator_record

BELLOWS = [str(Path(sys.executable).parent / 'bellows')]


def write_csv(path, columns):
    with open(path, 'w', newline='') as stream:
        writer = csv.writer(stream)
        writer.writerow(list(columns))
        writer.writerows(zip(*columns.values()))
    return path


def digest(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


@pytest.fixture(scope='module')
def record(tmp_path_factory):
    data = actuator_record(load_actuator_params(), load_actuator_plant_params(), seed=5,
                           duration=2.0)
    return str(write_csv(tmp_path_factory.mktemp('rec') / 'r.csv', data))


def one_error_line(capsys, *fragments):
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


@pytest.mark.parametrize('how', ['same path', 'symlink', 'hard link', 'relative path'])
@pytest.mark.parametrize('command', ['simulate', 'identify'])
def test_an_output_that_is_the_input_is_refused_before_any_work(
        record, tmp_path, how, command, capsys, monkeypatch):
    measured = tmp_path / 'r.csv'
    measured.write_bytes(Path(record).read_bytes())
    before = digest(measured)
    output = {'same path': measured, 'symlink': tmp_path / 'link.csv',
              'hard link': tmp_path / 'hard.csv', 'relative path': Path('r.csv')}[how]
    if how == 'symlink':
        os.symlink(measured, output)
    elif how == 'hard link':
        os.link(measured, output)
    monkeypatch.chdir(tmp_path)
    args = (['simulate', 'actuator', '--input', str(measured), '--output', str(output)]
            if command == 'simulate' else
            ['identify', 'actuator', str(measured), '--output', str(output), '--quiet'])
    assert main(args) == 2
    one_error_line(capsys, 'that is an input of this command')
    assert digest(measured) == before


@pytest.mark.parametrize('command', ['simulate', 'identify', 'diagnose'])
def test_a_missing_output_directory_is_an_error_before_any_work(
        record, tmp_path, command, capsys):
    missing = tmp_path / 'no' / 'such'
    args = {'simulate': ['simulate', 'actuator', '--input', record, '--output',
                         str(missing / 'o.csv')],
            'identify': ['identify', 'actuator', record, '--output', str(missing / 'p.yaml')],
            'diagnose': ['diagnose', 'actuator', record, '--report', str(missing / 'report')]}
    assert main(args[command]) == 2
    # One line and nothing else: no progress bar, so no fit or diagnosis had started.
    one_error_line(capsys, 'no such directory')


@pytest.mark.parametrize('command', ['identify actuator {record} --output {mount}/p.yaml',
                                     'simulate actuator --input {record} --output {mount}/o.csv',
                                     'diagnose actuator {record} --report {mount}/report',
                                     'record --output {mount}/bag --duration 1'])
def test_a_read_only_file_system_is_an_error_before_any_work(record, tmp_path, command):
    """A real read-only mount (permission bits do not stop root): one line, exit 2."""
    mount = tmp_path / 'ro'
    mount.mkdir()
    script = (f'mount -t tmpfs -o ro tmpfs {mount} && exec {" ".join(BELLOWS)} '
              + command.format(record=record, mount=mount))
    try:
        result = subprocess.run(['unshare', '-m', 'sh', '-c', script], capture_output=True,
                                text=True, timeout=120)
    except FileNotFoundError:
        pytest.skip('no unshare here')
    if 'mount' in result.stderr and result.returncode != 2:
        pytest.skip(f'cannot mount a read-only file system here: {result.stderr.strip()}')
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and 'cannot write' in lines[0] and 'Read-only' in lines[0], lines


def directory_state(directory):
    return {p.name: (p.stat().st_size, p.stat().st_mtime_ns) for p in directory.iterdir()}


@pytest.mark.slow
@pytest.mark.parametrize('signum', [signal.SIGKILL, signal.SIGINT, signal.SIGTERM])
def test_an_interrupted_write_leaves_the_old_output_whole(tmp_path, signum):
    """
    A signal while `bellows simulate` writes over an old output: the old bytes, or the new file.

    The signal is sent the moment anything in the output's directory changes (a temporary file
    appears, or the output itself is touched), so it lands while the output is being written.
    """
    rows = 200_000
    t = np.arange(rows) * 1e-3
    data = {'t': t, 'psi': 0.3 * np.sin(t), 'p1': 2e5 + 0 * t, 'p2': 1.5e5 + 0 * t,
            'tau_ext': 0 * t}
    source = write_csv(tmp_path / 'in.csv', data)
    out_dir = tmp_path / 'out'
    out_dir.mkdir()
    output = out_dir / 'out.csv'
    output.write_text('the old output\n')
    before = directory_state(out_dir)
    process = subprocess.Popen(BELLOWS + ['simulate', 'segment', '--input', str(source),
                                          '--output', str(output)],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    end = time.monotonic() + 120
    while process.poll() is None and directory_state(out_dir) == before \
            and time.monotonic() < end:
        time.sleep(0.001)
    interrupted = process.poll() is None
    if interrupted:
        process.send_signal(signum)
    process.wait()
    assert interrupted   # the signal landed while it wrote
    text = output.read_text()
    assert text == 'the old output\n' or text.count('\n') == rows + 1, len(text)


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    path = tmp_path / 'p.yaml'
    path.write_text('old: 1\n')
    with pytest.raises(RuntimeError):
        with atomic_file(path) as stream:
            stream.write('new: ')
            raise RuntimeError('interrupted')
    assert path.read_text() == 'old: 1\n'
    assert [p.name for p in tmp_path.iterdir()] == ['p.yaml']


def test_a_report_is_replaced_whole(tmp_path):
    report = tmp_path / 'report'
    with report_directory(report) as building:  # the old report, with its manifest
        (building / 'report.json').write_text('{"old": true}')
        (building / 'old_plot.png').write_bytes(b'old')
    with report_directory(report) as building:
        (building / 'report.json').write_text('{"new": true}')
        (building / 'new_plot.png').write_bytes(b'new')
    assert sorted(p.name for p in report.iterdir()) == sorted([MANIFEST, 'new_plot.png',
                                                               'report.json'])
    assert (report / 'report.json').read_text() == '{"new": true}'
    assert sorted(p.name for p in tmp_path.iterdir()) == ['report']


def test_an_interrupted_report_leaves_the_old_one(tmp_path):
    report = tmp_path / 'report'
    with report_directory(report) as building:
        (building / 'report.json').write_text('{"old": true}')
    with pytest.raises(KeyboardInterrupt):
        with report_directory(report) as building:
            (building / 'report.json').write_text('{"new": true}')
            raise KeyboardInterrupt
    assert sorted(p.name for p in report.iterdir()) == sorted([MANIFEST, 'report.json'])
    assert (report / 'report.json').read_text() == '{"old": true}'
    assert sorted(p.name for p in tmp_path.iterdir()) == ['report']


def test_a_directory_that_is_not_a_report_is_never_replaced(record, tmp_path, capsys):
    mine = tmp_path / 'mine'
    mine.mkdir()
    (mine / 'thesis.tex').write_text('years of work')
    assert main(['diagnose', 'actuator', record, '--report', str(mine), '--quiet']) == 2
    one_error_line(capsys, 'not a bellows report')
    assert (mine / 'thesis.tex').read_text() == 'years of work'
    with pytest.raises(BellowsError, match='not a bellows report'):
        with report_directory(mine):
            pass
