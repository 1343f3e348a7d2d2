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
The user's errors (bellows_ros/errors.py): one line that says what is wrong and where.

A `DataError` names the file, then its line and column where known; every `BellowsError` becomes
one line on stderr and exit status 2 at the `bellows` command, while any other exception is a bug
and keeps its traceback.
"""
from pathlib import Path

import pytest

from bellows_ros import cli
from bellows_ros.cli import reindex
from bellows_ros.errors import BellowsError, DataError, ParameterError


@pytest.mark.parametrize('line, column, text', [
    (None, None, 'rec.csv: no data rows'),
    (7, None, 'rec.csv:7: no data rows'),
    (None, 'p', "rec.csv: column 'p': no data rows"),
    (7, 'p', "rec.csv:7: column 'p': no data rows"),
])
def test_a_data_error_names_file_line_and_column(line, column, text):
    error = DataError(Path('rec.csv'), 'no data rows', line, column)
    assert str(error) == text
    # The parts stay apart for a caller that points at the place (the path as text).
    assert (error.path, error.line, error.column) == ('rec.csv', line, column)


def test_line_0_and_an_empty_column_name_are_places_too():
    # `line is None` and `column is None` decide, not truthiness: line 0 or a column '' that a
    # header really holds must be shown.
    assert str(DataError('f.csv', 'bad', 0, '')) == "f.csv:0: column '': bad"


def test_every_users_error_is_a_bellows_error():
    for kind in (DataError, ParameterError):
        assert issubclass(kind, BellowsError)
    assert issubclass(BellowsError, Exception)
    assert not issubclass(BellowsError, (ValueError, OSError))  # never caught as a bug's type


def raising(error):
    def run(args):
        raise error
    return run


@pytest.mark.parametrize('error', [
    BellowsError('the board does not answer'),
    ParameterError("p.yaml: unknown parameter 'segment.bogus'"),
    DataError('rec.csv', 'not a number: 1,5', 3, 'p'),
], ids=['BellowsError', 'ParameterError', 'DataError'])
def test_main_turns_a_users_error_into_one_line_and_status_2(monkeypatch, capsys, error):
    monkeypatch.setattr(reindex, 'run', raising(error))
    assert cli.main(['reindex', 'bag']) == 2
    captured = capsys.readouterr()
    assert captured.err == f'bellows reindex: error: {error}\n'
    assert captured.out == ''


def test_any_other_exception_is_a_bug_and_keeps_its_traceback(monkeypatch):
    monkeypatch.setattr(reindex, 'run', raising(ZeroDivisionError('a bug')))
    with pytest.raises(ZeroDivisionError, match='a bug'):
        cli.main(['reindex', 'bag'])


def test_a_real_users_error_reaches_the_command_line_as_one_line(tmp_path, capsys):
    # Not stubbed: the package's own refusal of a missing input, through main().
    missing = tmp_path / 'missing.csv'
    status = cli.main(['export', 'actuator', str(missing), '--output', str(tmp_path / 'o.csv')])
    err = capsys.readouterr().err
    assert status == 2
    assert err.startswith(f'bellows export: error: {missing}: ') and err.count('\n') == 1
    assert not (tmp_path / 'o.csv').exists()
