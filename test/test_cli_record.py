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
`bellows record --output DIR [--topics T ...] [--namespace NS] [--duration S]` (cli/record.py).

In this process, with no recording made: the arguments as the recorder gets them, `--duration`
refused outside a millisecond to thirty days, and the refusals that come before any ROS node or
file is made (a topic unknown in the namespace, a topic twice, an output that exists, even as a
dangling link, or whose directory does not): one line, exit status 2, nothing touched. A real
recording, stopped by its duration and by signals, is test_runtime_record.py's and
test_record_signals.py's.
"""
import os

import pytest

from bellows_ros.cli import build_parser, main


@pytest.fixture
def recorder(monkeypatch):
    """Stand in for runtime.record.record: keep its arguments, call ready(), count 3 and 0."""
    calls = []

    def record(output, topics=None, duration=None, ready=None, namespace='/'):
        calls.append((output, topics, duration, namespace))
        ready()
        return {'/joint_states': 3, '/bellows/estop': 0}
    monkeypatch.setattr('bellows_ros.runtime.record.record', record)
    return calls


def one_line(capsys):
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'Traceback' not in err, err
    return err


def test_the_defaults_record_every_topic_in_the_root_namespace_until_stopped():
    args = build_parser().parse_args(['record', '--output', 'bag'])
    assert (args.output, args.topics, args.namespace, args.duration) == ('bag', None, '/', None)


def test_the_recorder_gets_the_arguments_and_the_counts_are_printed(recorder, tmp_path, capsys):
    bag = str(tmp_path / 'bag')
    assert main(['record', '--output', bag, '--topics', '/joint_states', '/bellows/estop',
                 '--namespace', '/arm_a', '--duration', '1.5']) == 0
    assert recorder == [(bag, ['/joint_states', '/bellows/estop'], 1.5, '/arm_a')]
    out, err = capsys.readouterr()
    assert err == f'bellows record: recording 2 topics to {bag} for 1.5 s\n'
    assert out == '/joint_states: 3 messages\n/bellows/estop: 0 messages\n'
    assert main(['record', '--output', bag]) == 0
    assert recorder[-1] == (bag, None, None, '/')
    assert capsys.readouterr().err.endswith(' until Ctrl-C\n')


@pytest.mark.parametrize('text, words', [
    ('0', 'outside its range'),
    ('2592000.5', 'outside its range'),   # thirty days and a half second
    ('nan', "expected a finite number in s, got 'nan'"),
    ('inf', "expected a finite number in s, got 'inf'"),
    ('ten', "expected a number in s, got 'ten'"),
])
def test_a_bad_duration_is_one_line_and_exit_2(recorder, tmp_path, capsys, text, words):
    with pytest.raises(SystemExit) as stopped:
        main(['record', '--output', str(tmp_path / 'bag'), '--duration', text])
    assert stopped.value.code == 2
    err = one_line(capsys)
    assert 'argument --duration' in err and words in err, err
    assert recorder == []


def test_the_bounds_of_the_duration_are_allowed(recorder, tmp_path):
    for text in ('0.001', '2592000'):
        assert main(['record', '--output', str(tmp_path / 'bag'), '--duration', text]) == 0
    assert [call[2] for call in recorder] == [0.001, 2592000.0]


def test_output_is_required(capsys):
    with pytest.raises(SystemExit) as stopped:
        main(['record', '--topics', '/joint_states'])
    assert stopped.value.code == 2
    assert 'the following arguments are required: --output' in one_line(capsys)


@pytest.mark.parametrize('argv, words', [
    # the namespace moves the contract's relative topics: /joint_states is /arm_a/joint_states
    (['--namespace', '/arm_a', '--topics', '/joint_states'],
     "record: unknown topic '/joint_states' (known in namespace /arm_a: /arm_a/joint_states,"),
    (['--topics', '/joint_states', '/bellows/estop', '/joint_states'],
     '--topics: /joint_states is given twice'),
])
def test_topics_outside_the_contract_or_twice_are_refused(tmp_path, capsys, argv, words):
    bag = tmp_path / 'bag'
    assert main(['record', '--output', str(bag), *argv]) == 2
    assert one_line(capsys).startswith(f'bellows record: error: {words}')
    assert not bag.exists()


@pytest.mark.parametrize('kind', ['directory', 'file', 'dangling link'])
def test_an_existing_output_is_refused_and_left_as_it_was(tmp_path, capsys, kind):
    bag = tmp_path / 'bag'
    if kind == 'directory':
        bag.mkdir()
        (bag / 'metadata.yaml').write_text('an earlier recording\n')
    elif kind == 'file':
        bag.write_text('notes\n')
    else:
        bag.symlink_to(tmp_path / 'elsewhere')
    before = sorted(os.walk(tmp_path))
    assert main(['record', '--output', str(bag)]) == 2
    assert one_line(capsys) == (f'bellows record: error: {bag}: already exists (rosbag2 writes '
                                'a new directory)\n')
    assert sorted(os.walk(tmp_path)) == before
    if kind == 'directory':
        assert (bag / 'metadata.yaml').read_text() == 'an earlier recording\n'
    assert not (tmp_path / 'elsewhere').exists()


def test_an_output_in_a_missing_directory_is_refused(tmp_path, capsys):
    bag = tmp_path / 'missing' / 'bag'
    assert main(['record', '--output', str(bag)]) == 2
    assert f'--output {bag}' in one_line(capsys)
    assert not (tmp_path / 'missing').exists()
