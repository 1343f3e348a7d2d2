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
Outputs are regular files or new paths (issue #30, class 1).

A rename replaces whatever has the output's name: a device node, a FIFO, a socket, `/dev/stdout`.
Each such output is refused before any work, one line, exit 2, and is left what it was. Device
nodes are made with mknod in tmp_path only (never a path under /dev). Also: a report directory
is replaced only when its manifest says the package wrote every entry, a report given as a link
is resolved, and no temporary file survives SIGTERM or SIGHUP.
"""
import errno
import fcntl
import json
import os
import signal
import socket
import stat
import subprocess
import sys
import tempfile
import time

import numpy as np
import pytest
from tables import write_csv

from bellows_ros.cli import main
from bellows_ros.config.actuator import load_actuator_params, load_actuator_plant_params
from bellows_ros.errors import BellowsError
from bellows_ros.io import outputs
from bellows_ros.io.outputs import atomic_file, check_report_directory, report_directory
from bellows_ros.papers.actuator_experiments import actuator_record

BELLOWS = [sys.executable, '-c', 'import sys; from bellows_ros.cli import main; sys.exit(main())']


@pytest.fixture(scope='module')
def record(tmp_path_factory):
    data = actuator_record(load_actuator_params(), load_actuator_plant_params(), seed=5,
                           duration=2.0)
    return write_csv(tmp_path_factory.mktemp('rec') / 'r.csv', data)


def one_error_line(capsys, *fragments):
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert 'Traceback' not in err
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    return lines[0]


def make_special(tmp_path, kind):
    """Make an output path of `kind` in tmp_path; return (path, what it must stay)."""
    target = tmp_path / 'special'
    if kind in ('fifo', 'link to fifo'):
        os.mkfifo(target)
    elif kind in ('char device', 'link to char device'):
        os.mknod(target, 0o600 | stat.S_IFCHR, os.makedev(1, 3))  # /dev/null's numbers, in tmp
    elif kind == 'socket':
        server = socket.socket(socket.AF_UNIX)
        server.bind(str(target))
        server.close()
    if kind.startswith('link to'):
        link = tmp_path / 'link'
        os.symlink(target, link)
        return link, stat.S_IFMT(os.stat(target).st_mode)
    return target, stat.S_IFMT(os.lstat(target).st_mode)


KINDS = ['fifo', 'char device', 'socket', 'link to fifo', 'link to char device']
COMMANDS = {
    'simulate': 'simulate actuator --input {record} --output {out}',
    'identify': 'identify actuator {record} --output {out} --quiet',
    'export': 'export actuator {record} --output {out}',
}


@pytest.mark.parametrize('kind', KINDS)
@pytest.mark.parametrize('command', sorted(COMMANDS))
def test_an_output_that_is_no_regular_file_is_refused_and_kept(
        record, tmp_path, capsys, kind, command):
    if kind.endswith('char device') and os.geteuid() != 0:
        pytest.skip('mknod of a character device needs root')
    out, mode = make_special(tmp_path, kind)
    argv = COMMANDS[command].format(record=record, out=out).split()
    assert main(argv) == 2
    one_error_line(capsys, str(out), 'not a regular file')
    assert stat.S_IFMT(os.stat(out).st_mode) == mode
    assert not [p for p in tmp_path.iterdir() if p.name.endswith('.tmp')]


def test_the_fig10_plot_refuses_a_fifo(tmp_path):
    fifo = tmp_path / 'plot.png'
    os.mkfifo(fifo)
    result = subprocess.run([sys.executable, '-m', 'bellows_ros.papers.fig10', '--plot',
                             str(fifo)], capture_output=True, text=True, timeout=120,
                            env={**os.environ, 'MPLBACKEND': 'Agg'})
    assert result.returncode == 2, result.stderr
    assert 'not a regular file' in result.stderr and 'Traceback' not in result.stderr
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


def test_atomic_file_refuses_a_fifo_itself(tmp_path):
    """Every writer goes through atomic_file: its own check holds without check_output."""
    fifo = tmp_path / 'out'
    os.mkfifo(fifo)
    with pytest.raises(BellowsError, match='not a regular file'):
        with atomic_file(fifo) as stream:
            stream.write('x')
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert [p.name for p in tmp_path.iterdir()] == ['out']


def test_a_link_to_a_regular_file_is_followed_and_stays_a_link(record, tmp_path, capsys):
    real = tmp_path / 'real.csv'
    real.write_text('old\n')
    link = tmp_path / 'link.csv'
    os.symlink(real, link)
    assert main(['simulate', 'actuator', '--input', record, '--output', str(link)]) == 0
    assert link.is_symlink() and os.readlink(link) == str(real)
    assert real.read_text().startswith('t,')


@pytest.mark.parametrize('output', ['o.csv/', 'o.csv/.', 'sub/'])
def test_an_output_with_a_trailing_slash_is_refused(record, tmp_path, capsys, monkeypatch,
                                                    output):
    monkeypatch.chdir(tmp_path)
    (tmp_path / 'sub').mkdir()
    assert main(['simulate', 'actuator', '--input', record, '--output', output]) == 2
    one_error_line(capsys, output)
    assert sorted(p.name for p in tmp_path.iterdir()) == ['sub']


# --- report directories -------------------------------------------------------------------------
def fake_report(directory, files):
    with report_directory(directory) as building:
        for name, text in files.items():
            (building / name).write_text(text)


def test_a_users_file_in_a_report_is_never_deleted(tmp_path):
    report = tmp_path / 'report'
    fake_report(report, {'report.json': '{}', 'fit.png': 'plot'})
    (report / 'rig_photo.png').write_bytes(b'a photo')
    with pytest.raises(BellowsError, match='rig_photo.png'):
        check_report_directory(report)
    with pytest.raises(BellowsError, match='rig_photo.png'):
        fake_report(report, {'report.json': '{"new": 1}'})
    assert (report / 'rig_photo.png').read_bytes() == b'a photo'
    assert sorted(p.name for p in tmp_path.iterdir()) == ['report']


def test_a_report_file_the_user_edited_is_not_ours_any_more(tmp_path):
    report = tmp_path / 'report'
    fake_report(report, {'report.json': '{}', 'report.md': 'generated'})
    (report / 'report.md').write_text('generated, and my notes')
    with pytest.raises(BellowsError, match='report.md'):
        fake_report(report, {'report.json': '{"new": 1}'})
    assert (report / 'report.md').read_text() == 'generated, and my notes'


def test_a_report_without_a_manifest_is_not_ours(tmp_path):
    """report.json and plots by name prove nothing: a user may have put them there."""
    report = tmp_path / 'report'
    report.mkdir()
    (report / 'report.json').write_text('{}')
    (report / 'fit.png').write_bytes(b'a user plot')
    with pytest.raises(BellowsError, match='manifest'):
        check_report_directory(report)


def test_a_report_is_replaced_when_every_entry_is_ours(tmp_path):
    report = tmp_path / 'report'
    fake_report(report, {'report.json': '{}', 'old.png': 'old'})
    fake_report(report, {'report.json': '{"new": 1}', 'new.png': 'new'})
    names = sorted([outputs.MANIFEST, 'new.png', 'report.json'])
    assert sorted(p.name for p in report.iterdir()) == names
    manifest = json.loads((report / outputs.MANIFEST).read_text())
    assert manifest['files'].keys() == {'new.png', 'report.json'}
    assert sorted(p.name for p in tmp_path.iterdir()) == ['report']


def test_a_report_given_as_a_link_is_resolved_and_the_link_stays(tmp_path):
    real = tmp_path / 'real_report'
    fake_report(real, {'report.json': '{}'})
    link = tmp_path / 'report'
    os.symlink(real, link)
    fake_report(link, {'report.json': '{"new": 1}'})
    assert link.is_symlink() and os.readlink(link) == str(real)
    assert (real / 'report.json').read_text() == '{"new": 1}'
    assert sorted(p.name for p in tmp_path.iterdir()) == ['real_report', 'report']
    dangling = tmp_path / 'dangling'
    os.symlink(tmp_path / 'new_report', dangling)
    fake_report(dangling, {'report.json': '{}'})
    assert dangling.is_symlink() and (tmp_path / 'new_report' / 'report.json').exists()


def test_a_link_to_a_file_as_report_is_refused_before_work(record, tmp_path, capsys):
    (tmp_path / 'notes.txt').write_text('mine')
    os.symlink(tmp_path / 'notes.txt', tmp_path / 'report')
    assert main(['diagnose', 'actuator', record, '--report', str(tmp_path / 'report'),
                 '--quiet']) == 2
    one_error_line(capsys, 'not a directory')
    assert (tmp_path / 'notes.txt').read_text() == 'mine'


# --- temporary files ----------------------------------------------------------------------------
@pytest.mark.slow
@pytest.mark.parametrize('signum', [signal.SIGTERM, signal.SIGHUP])
def test_a_signal_leaves_no_temporary_file(tmp_path, signum):
    process, out_dir = simulate_then_signal(tmp_path, signum, signal.SIG_DFL)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 128 + signum, err
    assert 'Traceback' not in err and len(err.strip().splitlines()) == 1, err
    assert list(out_dir.iterdir()) == []


@pytest.mark.slow
def test_an_ignored_hangup_stays_ignored(tmp_path):
    # Under nohup (SIGHUP ignored, as the user asked) the command goes on to its output.
    process, out_dir = simulate_then_signal(tmp_path, signal.SIGHUP, signal.SIG_IGN)
    _, err = process.communicate(timeout=120)
    assert process.returncode == 0, err
    assert [p.name for p in out_dir.iterdir()] == ['out.csv']


def test_the_writability_probe_has_no_name_a_signal_could_leave(tmp_path, monkeypatch):
    """The probe of an output's directory is an unnamed file where the file system has them."""
    try:
        os.close(os.open(tmp_path, os.O_TMPFILE | os.O_WRONLY, 0o600))
    except (AttributeError, OSError):
        pytest.skip('no unnamed files (O_TMPFILE) here: the named probe is used')

    def named(*args, **kwargs):
        raise AssertionError('a named probe in the output directory')
    monkeypatch.setattr(tempfile, 'NamedTemporaryFile', named)
    assert outputs.check_output(tmp_path / 'out.csv') == tmp_path / 'out.csv'
    assert list(tmp_path.iterdir()) == []


def test_without_unnamed_files_the_named_probe_is_removed(tmp_path, monkeypatch):
    refused, real_open = [], os.open

    def no_unnamed_files(path, flags, *args, **kwargs):
        if flags & getattr(os, 'O_TMPFILE', -1) == getattr(os, 'O_TMPFILE', 0):
            refused.append(path)
            raise OSError(errno.EOPNOTSUPP, os.strerror(errno.EOPNOTSUPP))
        return real_open(path, flags, *args, **kwargs)
    monkeypatch.setattr(os, 'open', no_unnamed_files)
    assert outputs.check_output(tmp_path / 'out.csv') == tmp_path / 'out.csv'
    assert list(tmp_path.iterdir()) == []
    if hasattr(os, 'O_TMPFILE'):
        assert refused == [tmp_path]


def simulate_then_signal(tmp_path, signum, disposition):
    """
    Start a long `bellows simulate` with `signum` set to `disposition`; signal it mid-write.

    Returns the process and its output directory. The disposition is set in the child rather
    than inherited: a test session run under nohup ignores SIGHUP, and the command rightly keeps
    an ignored signal ignored.
    """
    t = np.arange(200_000) * 1e-3
    source = write_csv(tmp_path / 'in.csv', {'t': t, 'psi': 0.3 * np.sin(t), 'p1': 2e5 + 0 * t,
                                             'p2': 1.5e5 + 0 * t, 'tau_ext': 0 * t})
    out_dir = tmp_path / 'out'
    out_dir.mkdir()
    process = subprocess.Popen(BELLOWS + ['simulate', 'segment', '--input', source, '--output',
                                          str(out_dir / 'out.csv')],
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signum, disposition))
    end = time.monotonic() + 120
    while process.poll() is None and not any(out_dir.iterdir()) and time.monotonic() < end:
        time.sleep(0.001)
    assert process.poll() is None
    process.send_signal(signum)
    return process, out_dir


def signal_once_made(monkeypatch, name):
    """Make `tempfile.<name>` SIGTERM this process right after it made its file or directory."""
    make = getattr(tempfile, name)

    def make_then_signal(*args, **kwargs):
        made = make(*args, **kwargs)
        os.kill(os.getpid(), signal.SIGTERM)  # the handler runs before this returns
        return made
    monkeypatch.setattr(tempfile, name, make_then_signal)


def test_a_signal_as_the_temporary_file_is_made_leaves_nothing(tmp_path, monkeypatch):
    """SIGTERM between the temporary file's creation and its clean-up's `try`: held, then run."""
    signal_once_made(monkeypatch, 'mkstemp')
    with pytest.raises(outputs.Signalled), outputs.signals_as_exceptions():
        with outputs.atomic_file(tmp_path / 'o.csv') as stream:
            stream.write('never written\n')
    assert list(tmp_path.iterdir()) == []


def test_a_signal_as_the_report_directory_is_made_leaves_nothing(tmp_path, monkeypatch):
    signal_once_made(monkeypatch, 'mkdtemp')
    with pytest.raises(outputs.Signalled), outputs.signals_as_exceptions():
        with outputs.report_directory(tmp_path / 'report') as building:
            (building / 'report.json').write_text('{}')
    assert list(tmp_path.iterdir()) == []


def test_an_orphan_temporary_file_goes_with_the_next_write_a_held_one_stays(tmp_path):
    out = tmp_path / 'o.csv'
    orphan = tmp_path / '.o.csv.killed.tmp'        # left by a SIGKILL: nobody holds it
    orphan.write_text('half')
    held = tmp_path / '.o.csv.writing.tmp'         # another writer's, still being written
    held.write_text('half')
    other = tmp_path / '.other.csv.x.tmp'          # another output's: not ours to judge
    other.write_text('x')
    with open(held) as holder:
        fcntl.flock(holder, fcntl.LOCK_EX)
        with atomic_file(out) as stream:
            stream.write('new\n')
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([held.name, other.name, 'o.csv'])


def test_a_report_build_a_sigkill_left_goes_with_the_next_report(tmp_path):
    report = tmp_path / 'report'
    orphan = tmp_path / '.report.x1y2.new'          # a diagnosis killed while it wrote
    orphan.mkdir()
    (orphan / 'report.json').write_text('{}')
    building = tmp_path / '.report.z3.new'          # another run, building now: it holds it
    building.mkdir()
    other = tmp_path / '.notes.a.new'               # not a report of this path: not judged here
    other.mkdir()
    held = os.open(building, os.O_RDONLY | os.O_DIRECTORY)
    try:
        fcntl.flock(held, fcntl.LOCK_EX)
        fake_report(report, {'report.json': '{}'})
    finally:
        os.close(held)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([building.name, other.name,
                                                                 'report'])
