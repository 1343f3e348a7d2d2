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
The `bellows` command under careless and hostile input: one line, exit 2, nothing changed.

Table-driven over every subcommand's options with bad values, plus hypothesis over argument
lists. Each case runs in a directory holding a measurement and an earlier output; afterwards no
file there may have changed (a user mistake never touches a file it did not name as output),
stderr is one line that names the option or the file, and there is no traceback.
"""
import csv
import hashlib
import os
import shlex

from hypothesis import given, HealthCheck, settings, strategies as st
import numpy as np
import pytest

from bellows_ros.cli import main, SUBCOMMANDS
from bellows_ros.config.actuator import load_actuator_params, load_actuator_plant_params
from bellows_ros.papers.actuator_experiments import actuator_record


@pytest.fixture(scope='module')
def workdir(tmp_path_factory):
    """Make a directory with a measurement (r.csv), a segment record and files to protect."""
    root = tmp_path_factory.mktemp('hostile')
    record = actuator_record(load_actuator_params(), load_actuator_plant_params(), seed=3,
                             duration=2.0)
    with open(root / 'r.csv', 'w', newline='') as stream:
        writer = csv.writer(stream)
        writer.writerow(list(record))
        writer.writerows(zip(*record.values()))
    t = np.arange(400) * 1e-3
    with open(root / 's.csv', 'w', newline='') as stream:
        writer = csv.writer(stream)
        writer.writerow(['t', 'psi', 'p1', 'p2', 'tau_ext'])
        writer.writerows(zip(t, 0.3 * np.sin(t * 5), 2e5 + 0 * t, 1.2e5 + 0 * t, 0 * t))
    (root / 'old.csv').write_text('an earlier output\n')
    (root / 'p.yaml').write_text('/**:\n  ros__parameters:\n    actuator:\n      gas:\n'
                                 '        v_tube: 5.0e-6\n')
    (root / 'dir').mkdir()
    (root / 'notreport').mkdir()      # a user's directory that looks like a report by its names
    (root / 'notreport' / 'report.json').write_text('{}')
    (root / 'notreport' / 'rig_photo.png').write_bytes(b'a photo')
    os.mkfifo(root / 'fifo')          # a named pipe: never read or replaced by a mistake
    return root


def snapshot(root):
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            if p.is_file() else os.lstat(p).st_mode
            for p in sorted(root.rglob('*')) if p.is_file() or p.is_fifo()}


# (arguments, a fragment the one error line must hold)
CASES = [
    ('', 'required'),
    ('frobnicate', 'invalid choice'),
    ('simulate', 'required'),
    ('simulate actuator --input r.csv', '--output'),
    ('simulate actuator --input missing.csv --output o.csv', 'missing.csv'),
    ('simulate actuator --input dir --output o.csv', 'dir'),
    ('simulate actuator --input r.csv --output r.csv', 'input of this command'),
    ('simulate actuator --input r.csv --output dir', 'is a directory'),
    ('simulate actuator --input r.csv --output no/such/o.csv', 'no such directory'),
    ('simulate actuator --input r.csv --output o.csv --params missing.yaml', 'missing.yaml'),
    ('simulate actuator --input r.csv --output o.csv --params r.csv', 'r.csv'),
    ('simulate actuator --input r.csv --output o.csv --effect warp_drive', 'warp_drive'),
    ('simulate actuator --input r.csv --output o.csv --effect air_leak:speed=1', 'speed'),
    ('simulate actuator --input r.csv --output o.csv --effect air_leak:conductance=-1',
     'conductance'),
    ('simulate actuator --input r.csv --output o.csv --effect air_leak:conductance=abc',
     'conductance'),
    ('simulate segment --input r.csv --output o.csv', 'r.csv'),
    ('simulate segment --input s.csv --output o.csv --effect sensor_lag:tau=nan', 'tau'),
    ('identify actuator r.csv', '--output'),
    ('identify actuator r.csv --output r.csv', 'input of this command'),
    ('identify actuator r.csv --output p.yaml --params p.yaml', 'input of this command'),
    ('identify actuator r.csv --output o.yaml --seed -1', '--seed'),
    ('identify actuator r.csv --output o.yaml --seed 1.5', '--seed'),
    ('identify actuator r.csv --output o.yaml --seed 99999999999', '--seed'),
    ('identify actuator missing.csv --output o.yaml', 'missing.csv'),
    ('identify segment s.csv --output o.yaml --params p.yaml', 'p.yaml'),
    ('diagnose actuator r.csv', '--report'),
    ('diagnose actuator r.csv --report r.csv', 'r.csv'),
    ('diagnose actuator r.csv --report dir/../r.csv', 'r.csv'),
    ('diagnose actuator missing.csv --report rep', 'missing.csv'),
    ('record --output dir', 'already exists'),
    ('record --output no/such/bag', 'no such directory'),
    ('record --output bag --duration -3', '--duration'),
    ('record --output bag --duration nan', '--duration'),
    ('record --output bag --duration abc', '--duration'),
    ('record --output bag --topics /nope', '/nope'),
    ('reindex missing', 'missing'),
    ('reindex r.csv', 'r.csv'),
    ('bench --only no_such_bench', 'no_such_bench'),
    ('bench --only segment,no_such_bench', 'no_such_bench'),
    ('bench --only segment,', "''"),
    ('export actuator r.csv', '--output'),
    ('export actuator r.csv --output r.csv', 'input of this command'),
    ('export actuator missing --output o.csv', 'missing'),
    ('export segment r.csv --output o.csv', 'r.csv'),
    ('stiffness missing.csv', 'missing.csv'),
    ('stiffness r.csv --window abc', '--window'),
    ('stiffness r.csv --window -1', 'window'),
    ('stiffness r.csv', 'no window'),
    ('stiffness r.csv --params missing.yaml', 'missing.yaml'),
    # issue #30: special outputs, bounds, doubles
    ('simulate actuator --input r.csv --output fifo', 'not a regular file'),
    ('simulate actuator --input r.csv --output o.csv/', 'names a directory'),
    ('export actuator r.csv --output fifo', 'not a regular file'),
    ('identify actuator r.csv --output fifo', 'not a regular file'),
    ('simulate actuator --input fifo --output o.csv', 'regular file'),
    ('stiffness r.csv --window inf', '--window'),
    ('stiffness r.csv --window 1e-9', '--window'),
    ('stiffness r.csv --setpoint nan', '--setpoint'),
    ('stiffness r.csv --setpoint -1', '--setpoint'),
    ('record --output bag --duration inf', '--duration'),
    ('record --output bag --topics /joint_states /joint_states', 'twice'),
    ('simulate actuator --input r.csv --output o.csv --effect air_leak:conductance=1e30',
     'conductance'),
    ('simulate actuator --input r.csv --output o.csv --effect backlash:width=1', 'width'),
    ('simulate actuator --input r.csv --output o.csv --effect air_leak --effect air_leak',
     'twice'),
    ('diagnose actuator r.csv --report notreport', 'not a bellows report'),
]


@pytest.mark.parametrize('arguments, fragment', CASES, ids=[a or '(none)' for a, _ in CASES])
def test_a_bad_argument_is_one_line_and_exit_2_and_changes_nothing(
        workdir, monkeypatch, capsys, arguments, fragment):
    monkeypatch.chdir(workdir)
    before = snapshot(workdir)
    with pytest.raises(SystemExit) if arguments in ('', 'frobnicate', 'simulate') or \
            fragment in ('required', '--output', '--report') and ' --' not in arguments[-9:] \
            else _no_raise():
        status = main(shlex.split(arguments))
        assert status == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    assert 'Traceback' not in captured.err
    assert fragment in lines[0], lines[0]
    assert snapshot(workdir) == before


class _no_raise:
    def __enter__(self):
        return self

    def __exit__(self, kind, value, traceback):
        if kind is SystemExit:  # argparse's own errors end so: the same contract
            assert value.code == 2
            return True
        return False


def test_every_subcommand_is_in_the_table():
    named = {arguments.split()[0] for arguments, _ in CASES if arguments}
    assert set(SUBCOMMANDS) <= named


WORDS = ['simulate', 'identify', 'diagnose', 'record', 'reindex', 'bench', 'segment', 'actuator',
         '--input', '--output', '--params', '--effect', '--seed', '--report', '--duration',
         '--topics', '--only', 'r.csv', 's.csv', 'p.yaml', 'old.csv', 'dir', 'missing.csv', '-1',
         'nan', '1e400', 'air_leak:conductance=-1', '/joint_states', '', '\x00', '--quiet',
         'fifo', 'o.csv/', 'inf', '--window', '--setpoint', 'stiffness',
         'backlash:width=1', 'notreport']


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.sampled_from(WORDS), min_size=0, max_size=6))
def test_any_argument_list_ends_in_success_or_one_error_line(workdir, monkeypatch, capsys,
                                                             arguments):
    """Whatever the user types: no traceback, and no file changed unless named as --output."""
    if arguments[:1] in (['bench'], ['record'], ['diagnose'], ['identify']) and \
            '--output' not in arguments and '--report' not in arguments:
        arguments = arguments + ['--output', 'missing_dir/x']  # no real work in this test
    if arguments[:1] in (['bench'], ['record'], ['identify'], ['simulate'], ['diagnose']):
        arguments = arguments + ['--output', 'no/such/dir/x']   # every run stops before work
    monkeypatch.chdir(workdir)
    before = snapshot(workdir)
    try:
        status = main(arguments)
    except SystemExit as exit_:
        status = exit_.code
    captured = capsys.readouterr()
    assert 'Traceback' not in captured.err
    assert status in (0, 2), (arguments, captured.err)
    if status == 2:
        assert len(captured.err.strip().splitlines()) == 1, (arguments, captured.err)
    assert snapshot(workdir) == before
