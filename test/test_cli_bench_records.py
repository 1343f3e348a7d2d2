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

"""`bellows bench`'s records (cli/bench_records.py): written, read back, rendered, refused."""
import json

import pytest

from bellows_ros.cli import bench_records, main


@pytest.fixture(scope='module')
def records(tmp_path_factory):
    """Two records of the quick segment bench, the second without one of the results."""
    directory = tmp_path_factory.mktemp('records')
    first, second = directory / 'first.json', directory / 'second.json'
    for path in (first, second):
        assert main(['bench', '--only', 'segment', '--quick', '--output', str(path)]) == 0
    data = json.loads(second.read_text())
    data['results'] = data['results'][1:]
    second.write_text(json.dumps(data))
    return first, second


def test_a_record_says_what_ran_where_and_holds_the_results(records):
    data = bench_records.read(records[0])
    assert data['format'] == bench_records.FORMAT
    assert data['command'] == ['bellows', 'bench', '--only', 'segment', '--quick', '--output',
                               str(records[0])]
    assert data['host']['cpus'] >= 1 and data['started'].endswith('+00:00')
    assert [r['name'] for r in data['results']][0] == 'segment: previous model (34) step'
    assert all(r['value'] > 0 for r in data['results'])


def test_json_prints_the_record_and_a_table_is_the_default(capsys):
    assert main(['bench', '--only', 'segment', '--quick', '--json']) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed['format'] == bench_records.FORMAT and printed['results']
    assert main(['bench', '--only', 'segment', '--quick']) == 0
    assert capsys.readouterr().out.startswith('benchmark')


def test_records_render_side_by_side_with_a_gap_where_one_lacks_a_result(records, capsys,
                                                                         tmp_path):
    plot = tmp_path / 'records.png'
    assert main(['bench', '--render', *map(str, records), '--plot', str(plot)]) == 0
    text = capsys.readouterr().out
    rows = [line for line in text.splitlines() if line.startswith('| segment: ')]
    assert len(rows) == len(bench_records.read(records[0])['results'])
    missing = next(row for row in rows if row.startswith('| segment: previous model (34) step'))
    assert missing.split('|')[3].strip() == ''          # the second record lacks it
    assert all(str(path) in text for path in records)
    assert plot.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'


@pytest.mark.parametrize('content, message', [
    ('{"format": "x"}', 'not a bench record'),
    ('{"a": ', 'line 1 column 7: not JSON'),
    (json.dumps({**dict.fromkeys(bench_records.KEYS, None), 'format': bench_records.FORMAT,
                 'results': [{'name': 'x'}]}), 'result 1 is not a result'),
])
def test_what_is_not_a_record_is_one_line_naming_the_file(tmp_path, capsys, content, message):
    path = tmp_path / 'bad.json'
    path.write_text(content)
    assert main(['bench', '--render', str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and str(path) in err and message in err


def test_a_plot_never_goes_over_a_record_nor_a_device(records, capsys):
    assert main(['bench', '--render', str(records[0]), '--plot', str(records[0])]) == 2
    assert 'input' in capsys.readouterr().err
    assert main(['bench', '--only', 'segment', '--quick', '--output', '/dev/null']) == 2
    err = capsys.readouterr().err
    assert '/dev/null' in err and 'bench: segment' not in err   # refused before any bench ran
    assert main(['bench', '--plot', 'x.png']) == 2
