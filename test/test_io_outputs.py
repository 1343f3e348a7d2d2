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
The package's outputs (bellows_ros/io/outputs.py): written whole or not at all, nothing lost.

A file is replaced only by a finished temporary beside it, so a failure at any step leaves the
old one; an output that is an input or no regular file is refused before any work; and the
package removes only what it wrote itself.
"""
import json
import os
import signal
import stat

import pytest

from bellows_ros.errors import BellowsError
from bellows_ros.io import outputs


def names(directory):
    return sorted(p.name for p in directory.iterdir())


def test_a_crash_at_the_rename_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    out = tmp_path / 'o.yaml'
    out.write_text('old: 1\n')

    def crash(source, target):
        assert open(source).read() == 'new: 2\n'     # the whole new file was there, flushed
        raise OSError(5, 'Input/output error')
    monkeypatch.setattr(os, 'replace', crash)
    with pytest.raises(OSError):
        outputs.write_text(out, 'new: 2\n')
    assert out.read_text() == 'old: 1\n'
    assert names(tmp_path) == ['o.yaml']
    monkeypatch.undo()
    outputs.write_text(out, 'new: 2\n')
    assert out.read_text() == 'new: 2\n' and names(tmp_path) == ['o.yaml']


def test_a_finished_file_its_check_refuses_replaces_nothing(tmp_path):
    out = tmp_path / 'o.yaml'
    out.write_text('old: 1\n')
    seen = []

    def reader(temporary):
        seen.append(open(temporary).read())
        raise BellowsError('the written file does not read back')
    with pytest.raises(BellowsError, match='does not read back'):
        with outputs.atomic_file(out, check=reader) as stream:
            stream.write('new: ')
            stream.write('2\n')
    assert seen == ['new: 2\n']                      # the check read the finished file
    assert out.read_text() == 'old: 1\n' and names(tmp_path) == ['o.yaml']


def test_the_old_files_mode_is_kept_and_a_new_file_follows_the_umask(tmp_path):
    old = tmp_path / 'old.csv'
    old.write_text('x')
    os.chmod(old, 0o640)
    outputs.write_text(old, 'y')
    assert stat.S_IMODE(old.stat().st_mode) == 0o640
    mask = os.umask(0o027)
    try:
        outputs.write_text(tmp_path / 'new.csv', 'z')
    finally:
        os.umask(mask)
    # mkstemp makes 0600; the output gets what open() would have made.
    assert stat.S_IMODE((tmp_path / 'new.csv').stat().st_mode) == 0o640


def test_an_output_that_is_an_input_is_refused_by_name_and_through_links(tmp_path):
    source = tmp_path / 'in.csv'
    source.write_text('t\n0\n')
    os.symlink(source, tmp_path / 'soft.csv')
    os.link(source, tmp_path / 'hard.csv')
    for output in (source, tmp_path / 'soft.csv', tmp_path / 'hard.csv',
                   tmp_path / 'sub' / '..' / 'in.csv'):
        (tmp_path / 'sub').mkdir(exist_ok=True)
        with pytest.raises(BellowsError, match=f'--output {output}: that is an input of this '
                                               rf'command \({source}\)'):
            outputs.check_output(output, inputs=(None, source))
    assert outputs.check_output(tmp_path / 'o.csv', inputs=(None, source)) == tmp_path / 'o.csv'
    assert source.read_text() == 't\n0\n'


def test_what_a_rename_would_destroy_is_refused_and_kept(tmp_path):
    fifo = tmp_path / 'fifo.csv'
    os.mkfifo(fifo)
    (tmp_path / 'dir.csv').mkdir()
    cases = {'/dev/null': 'is a character device', str(fifo): 'is a FIFO (named pipe)',
             str(tmp_path / 'dir.csv'): 'is a directory', str(tmp_path) + '/': 'names a directory',
             f'{tmp_path}/x/.': 'names a directory'}
    for output, needle in cases.items():
        with pytest.raises(BellowsError) as error:
            outputs.check_output(output)
        message = str(error.value)
        assert message.startswith(f'--output {output}') and needle in message, message
        assert '\n' not in message
        if output.startswith(str(tmp_path)):     # the writer refuses it again itself (never
            with pytest.raises(BellowsError):      # tried on /dev/null: a regression would
                outputs.write_text(output, 'x')    # replace the machine's)
    assert stat.S_ISCHR(os.stat('/dev/null').st_mode)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode) and (tmp_path / 'dir.csv').is_dir()
    assert names(tmp_path) == ['dir.csv', 'fifo.csv']
    with pytest.raises(BellowsError, match='no such directory'):
        outputs.check_output(tmp_path / 'missing' / 'o.csv')


def test_only_unheld_temporaries_of_the_output_itself_are_removed(tmp_path):
    # Named like the output's temporaries, but not files the package wrote: never removed.
    mine = tmp_path / 'notes.txt'
    mine.write_text('mine')
    os.symlink(mine, tmp_path / '.o.csv.link.tmp')
    (tmp_path / '.o.csv.dir.tmp').mkdir()
    (tmp_path / '.o.csv.keep.txt').write_text('not a temporary')
    os.mkfifo(tmp_path / '.o.csv.fifo.tmp')
    (tmp_path / '.o.csv.orphan.tmp').write_text('half')  # a killed writer's: goes
    outputs.write_text(tmp_path / 'o.csv', 'new\n')
    assert names(tmp_path) == ['.o.csv.dir.tmp', '.o.csv.fifo.tmp', '.o.csv.keep.txt',
                               '.o.csv.link.tmp', 'notes.txt', 'o.csv']
    assert mine.read_text() == 'mine'


def fake_report(directory, files):
    with outputs.report_directory(directory) as building:
        for name, text in files.items():
            (building / name).write_text(text)


@pytest.mark.parametrize('spoil, needle', [
    (lambda r: (r / 'sub').mkdir(), "'sub': the report did not write it"),
    # A link to a file with the very bytes the report wrote: still no file the report wrote.
    (lambda r: (os.replace(r / 'a.png', r.parent / 'user.png'),
                os.symlink(r.parent / 'user.png', r / 'a.png')),
     "'a.png': the report did not write it"),
    (lambda r: (r / outputs.MANIFEST).write_text('{"bellows_report": 1, "files": '),
     'its manifest is damaged'),
    (lambda r: (r / outputs.MANIFEST).write_text('{"bellows_report": 1, "files": [1]}'),
     'its manifest is damaged'),
])
def test_a_report_is_replaced_only_while_it_is_all_the_packages(tmp_path, spoil, needle):
    report = tmp_path / 'report'
    fake_report(report, {'report.json': '{}', 'a.png': 'plot'})
    assert outputs.is_report(report)
    assert json.loads((report / outputs.MANIFEST).read_text())['files'].keys() == {
        'report.json', 'a.png'}
    spoil(report)
    before = names(report)
    assert not outputs.is_report(report)
    with pytest.raises(BellowsError, match=needle):
        fake_report(report, {'report.json': '{"new": 1}'})
    assert names(report) == before and (report / 'report.json').read_text() == '{}'
    assert not [name for name in names(tmp_path) if name.startswith('.')]  # nothing built left


def test_an_empty_directory_takes_a_report_and_one_holding_an_input_does_not(tmp_path):
    report = tmp_path / 'report'
    report.mkdir()
    assert outputs.check_report_directory(report) == report
    (report / 'in.csv').write_text('t\n0\n')
    with pytest.raises(BellowsError, match=rf'--report {report}: holds an input'):
        outputs.check_report_directory(report, inputs=(report / 'in.csv',))
    with pytest.raises(BellowsError, match='is a file, not a directory'):
        outputs.check_report_directory(report / 'in.csv')


def test_sigterm_unwinds_as_an_exception_only_inside_the_block():
    previous = signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        with outputs.signals_as_exceptions():
            handler = signal.getsignal(signal.SIGTERM)
            with pytest.raises(outputs.Signalled) as caught:
                handler(signal.SIGTERM, None)        # as the interpreter calls it, no signal sent
            assert caught.value.signum == signal.SIGTERM and str(caught.value) == 'SIGTERM'
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
        # A handler someone else set (or an ignored signal) is left as it is.
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        with outputs.signals_as_exceptions():
            assert signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGTERM, previous)
