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
rcl's parameter and remapping rules, and the bellows node base's checks on top of them, one table.

Each case starts `parameter_probe.py` (a bellows node declaring `gain` in 0..10, `label`, `port`,
`segments` as Specs and publishing on a few topics) with the case's `--ros-args`, and checks what
the node got: parameter values, its name and namespace, the topics as its publishers resolved
them, or exit status 2 with one line on stderr. Precedence and remapping are rcl's (Jazzy); the
base adds the errors rcl leaves silent: a parameter given (file or -p) that the node does not
declare, a value of another type than the declared default (no conversion, not even integer to
double), a value outside its bounds.
"""
from dataclasses import dataclass, field
import json
from pathlib import Path
import random
import subprocess
import sys

from node_processes import node_env
import pytest

from bellows_ros.runtime.parameters import Spec

PROBE = Path(__file__).resolve().parent / 'parameter_probe.py'
DEFAULTS = {'gain': 0.5, 'label': 'none', 'port': '/default', 'segments': [0, 0]}
BOUNDS = {'gain': [0, 10]}
TOPICS = ['foo', '/abs', '~/priv', 'a/b']

FILES = {
    'p.yaml': '/**:\n  ros__parameters: {gain: 1.5, label: star, port: /star}\n'
              'probe:\n  ros__parameters: {port: /section}\n',
    'A.yaml': 'probe: {ros__parameters: {port: /a}}\n',
    'B.yaml': '/**: {ros__parameters: {port: /b}}\n',
    'S.yaml': '/probe: {ros__parameters: {port: /slash}}\n',
    'O.yaml': '/*: {ros__parameters: {port: /onestar}}\n',
    'AP.yaml': '/arm/probe: {ros__parameters: {port: /arm_probe}}\n',
    'AS.yaml': 'arm/*: {ros__parameters: {port: /arm_star}}\n',
    'Q.yaml': 'probe: {ros__parameters: {segments: [1, 2, 3, 4], gain: 1.5}}\n',
    'E.yaml': 'probe: {ros__parameters: {segments: []}}\n',
    'M.yaml': 'probe: {ros__parameters: {segments: [1, 2.5]}}\n',
    'X.yaml': '/**: {ros__parameters: {gain: 1e-3}}\n',
    'H.yaml': 'probe: {ros__parameters: {gain: 10.5}}\n',
}


@dataclass
class Case:
    """`argv` after `--ros-args`; what the node must report, or `error`: a fragment of its line."""

    id: str  # noqa: A003 (pytest's word for a case name)
    argv: list
    parameters: dict = field(default_factory=dict)
    name: str = 'probe'
    namespace: str = '/'
    topics: dict = field(default_factory=dict)
    error: str = ''
    known_bug: str = ''  # a product bug that makes the case fail: strict xfail, until fixed


# rclpy declares every override before the node can check it (automatically_declare_parameters_
# from_overrides=True, runtime/node.py); an empty array has no type in rcl (PARAMETER_NOT_SET),
# which the node base turns into one line naming it (rclpy does not say which parameter).
CASES = [
    # precedence: entries keyed by node, in order of first appearance; later matching over earlier
    Case('node_section_beats_p', ['--params-file', 'p.yaml', '-p', 'port:=/cli'],
         {'port': '/section', 'gain': 1.5, 'label': 'star'}),
    Case('node_scoped_p_after_file', ['--params-file', 'p.yaml', '-p', 'probe:port:=/cli_node'],
         {'port': '/cli_node', 'label': 'star'}),
    Case('node_scoped_p_before_file', ['-p', 'probe:port:=/cli_node', '--params-file', 'p.yaml'],
         {'port': '/star'}),
    Case('A_then_B', ['--params-file', 'A.yaml', '--params-file', 'B.yaml'], {'port': '/b'}),
    Case('B_then_A', ['--params-file', 'B.yaml', '--params-file', 'A.yaml'], {'port': '/a'}),
    Case('scoped_p_then_B', ['-p', 'probe:port:=/x', '--params-file', 'B.yaml'], {'port': '/b'}),
    Case('B_then_scoped_p', ['--params-file', 'B.yaml', '-p', 'probe:port:=/x'], {'port': '/x'}),
    Case('p_then_A', ['-p', 'port:=/x', '--params-file', 'A.yaml'], {'port': '/a'}),
    Case('A_then_p', ['--params-file', 'A.yaml', '-p', 'port:=/x'], {'port': '/x'}),
    Case('A_then_slash', ['--params-file', 'A.yaml', '--params-file', 'S.yaml'],
         {'port': '/slash'}),
    Case('slash_then_A', ['--params-file', 'S.yaml', '--params-file', 'A.yaml'], {'port': '/a'}),
    Case('onestar_then_B', ['--params-file', 'O.yaml', '--params-file', 'B.yaml'],
         {'port': '/b'}),
    Case('B_then_onestar', ['--params-file', 'B.yaml', '--params-file', 'O.yaml'],
         {'port': '/onestar'}),
    # sections against the node's name and namespace after __node / __ns
    Case('ns_hides_bare_section', ['-r', '__ns:=/arm', '--params-file', 'A.yaml'],
         {'port': '/default'}, namespace='/arm'),
    Case('ns_full_section', ['-r', '__ns:=/arm', '--params-file', 'AP.yaml'],
         {'port': '/arm_probe'}, namespace='/arm'),
    Case('ns_star_section', ['-r', '__ns:=/arm', '--params-file', 'AS.yaml'],
         {'port': '/arm_star'}, namespace='/arm'),
    Case('onestar_not_in_ns', ['-r', '__ns:=/arm', '--params-file', 'O.yaml'],
         {'port': '/default'}, namespace='/arm'),
    Case('renamed_hides_section', ['-r', '__node:=other', '--params-file', 'A.yaml'],
         {'port': '/default'}, name='other'),
    Case('renamed_scoped_p', ['-r', '__node:=other', '-p', 'other:port:=/other',
                              '-p', 'probe:label:=old'],
         {'port': '/other', 'label': 'none'}, name='other'),
    # typing
    Case('yaml_exponent_is_double', ['--params-file', 'X.yaml'], {'gain': 0.001}),
    Case('p_exponent_is_double', ['-p', 'gain:=1e-3'], {'gain': 0.001}),
    Case('use_sim_time', ['-p', 'use_sim_time:=true'], {'use_sim_time': True}),
    Case('use_sim_time_default', [], {'use_sim_time': False, 'segments': [0, 0]}),
    Case('rcl_scalars', ['-p', 'label:=2026-01-01', '-p', 'port:=1_000', '-p', 'gain:=.5',
                         '-p', 'segments:=[0x1F, 012]'],
         {'label': '2026-01-01', 'port': '1_000', 'gain': 0.5, 'segments': [31, 10]}),
    Case('yes_is_a_bool', ['-p', 'label:=yes'], error="'label' must be a string, got a bool True"),
    Case('integer_for_double', ['-p', 'gain:=3'],
         error="parameter 'gain' must be a double, got an integer 3"),
    Case('scalar_of_other_type_replaces', ['--params-file', 'Q.yaml', '-p', 'probe:gain:=2'],
         error="parameter 'gain' must be a double, got an integer 2"),
    Case('string_for_array', ['-p', 'segments:=abc'],
         error="parameter 'segments' must be an integer array, got a string"),
    Case('mixed_array_p', ['-p', 'segments:=[1, 2.0]'],
         error='Sequence should be of same type'),
    Case('mixed_array_file', ['--params-file', 'M.yaml'],
         error='Sequence should be of same type'),
    Case('empty_array_file', ['--params-file', 'E.yaml'], error='is given as an empty array'),
    Case('empty_array_p', ['-p', 'segments:=[]'], error='is given as an empty array'),
    # bounds (the Spec's, inclusive), for a value given in a file or with -p
    Case('at_the_bounds', ['-p', 'gain:=0.0'], {'gain': 0.0}),
    Case('at_the_upper_bound', ['-p', 'gain:=10.0'], {'gain': 10.0}),
    Case('below_the_bounds', ['-p', 'gain:=-0.5'],
         error="parameter 'gain' = -0.5: expected 0..10, got -0.5"),
    Case('above_the_bounds_in_file', ['--params-file', 'H.yaml'],
         error="parameter 'gain' = 10.5: expected 0..10, got 10.5"),
    Case('out_of_bounds_overridden', ['--params-file', 'H.yaml', '-p', 'probe:gain:=2.0'],
         {'gain': 2.0}),
    # a parameter the node does not declare
    Case('undeclared', ['-p', 'extra:=1'], error="unknown parameter 'extra' for node 'probe'"),
    Case('undeclared_in_section', ['--params-file', 'FILE_WITH_EXTRA'],
         error="unknown parameter 'extra' for node 'probe'"),
    # rcl's own parse errors: its messages name the rule, not what is wrong with it
    Case('fqn_in_p_is_rejected', ['-p', '/probe:port:=/x'],
         error="Couldn't parse parameter override rule: '-p /probe:port:=/x'"),
    # remapping: from and to expanded in the node's namespace, the first matching rule wins
    Case('remap', ['-r', 'foo:=bar', '-r', '~/priv:=/private', '-r', 'a/b:=c'],
         topics={'foo': '/bar', '/abs': '/abs', '~/priv': '/private', 'a/b': '/c'}),
    Case('remap_first_wins_and_scoped', ['-r', 'foo:=x', '-r', 'foo:=y', '-r',
                                         'probe:/abs:=/node_abs', '-r', 'other:a/b:=nope'],
         topics={'foo': '/x', '/abs': '/node_abs', '~/priv': '/probe/priv', 'a/b': '/a/b'}),
    Case('remap_global_before_scoped', ['-r', 'foo:=/g', '-r', 'probe:foo:=/s'],
         topics={'foo': '/g'}),
    Case('remap_scoped_before_global', ['-r', 'probe:foo:=/s', '-r', 'foo:=/g'],
         topics={'foo': '/s'}),
    Case('remap_in_namespace', ['-r', '__ns:=/arm', '-r', 'foo:=bar', '-r', '/arm/a/b:=/z'],
         namespace='/arm',
         topics={'foo': '/arm/bar', '/abs': '/abs', '~/priv': '/arm/probe/priv', 'a/b': '/z'}),
    Case('remap_to_private', ['-r', 'foo:=~/bar'], topics={'foo': '/probe/bar'}),
    Case('remap_scoped_by_new_name', ['-r', '__node:=other', '-r', 'probe:foo:=/old',
                                      '-r', 'other:/abs:=/new'], name='other',
         topics={'foo': '/foo', '/abs': '/new', '~/priv': '/other/priv'}),
    Case('rename_first_wins', ['-r', '__node:=a', '-r', '__node:=b', '-r', '__ns:=/p',
                               '-r', '__ns:=/q'],
         name='a', namespace='/p', topics={'foo': '/p/foo'}),
    Case('ns_rule_sees_new_name', ['-r', 'probe:__node:=other', '-r', 'probe:__ns:=/y',
                                   '-r', 'other:__ns:=/x'], name='other', namespace='/x'),
    Case('relative_namespace', ['-r', '__ns:=arm'],
         error="Couldn't parse remap rule: '-r __ns:=arm'"),
    Case('bad_node_name', ['-r', '__node:=9bad'],
         error="Couldn't parse remap rule: '-r __node:=9bad'"),
]


def probe(cwd, argv, parameters=DEFAULTS, topics=TOPICS):
    """Run the probe node with `--ros-args *argv`: the finished process."""
    spec = json.dumps({'parameters': parameters, 'bounds': BOUNDS, 'topics': topics})
    env = node_env(ROS_DOMAIN_ID=str(random.randint(60, 99)), PROBE_SPEC=spec)
    return subprocess.run([sys.executable, str(PROBE), '--ros-args', *argv], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=60)


@pytest.fixture
def files(tmp_path):
    for name, text in FILES.items():
        (tmp_path / name).write_text(text)
    (tmp_path / 'FILE_WITH_EXTRA').write_text('probe: {ros__parameters: {port: /p, extra: 1}}\n')
    return tmp_path


def check_error(result, fragment):
    """Exit status 2 and one error line; rcl may log its own line first (its C logger)."""
    assert result.returncode == 2, (result.stdout, result.stderr)
    lines = [line for line in result.stderr.strip().splitlines() if '] [rcl]: ' not in line]
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith('parameter_probe.py: error: ') and fragment in lines[0], lines[0]


@pytest.mark.slow  # a node process per case
@pytest.mark.parametrize('case', [
    pytest.param(case, marks=pytest.mark.xfail(strict=True, reason=case.known_bug))
    if case.known_bug else case for case in CASES], ids=[case.id for case in CASES])
def test_rcl_rules(case, files):
    result = probe(files, case.argv)
    if case.error:
        check_error(result, case.error)
        return
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout.strip().splitlines()[-1])
    assert (report['name'], report['namespace']) == (case.name, case.namespace)
    for name, value in case.parameters.items():
        assert report['parameters'][name] == value, name
        assert type(report['parameters'][name]) is type(value), name
    for topic, resolved in case.topics.items():
        assert report['topics'][topic] == resolved, topic


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason='rcl drops a later array of another element type '
                   'silently, before the node sees its overrides; the node cannot report it')
def test_array_of_another_type_later(files):
    """
    A later array of another element type than the earlier one: an error, not silently dropped.

    rcl (Jazzy) keeps the earlier array (segments [1, 2, 3, 4]) and drops `-p segments:=[1.0]`
    without a word; the user gets a value other than the one given last.
    """
    result = probe(files, ['--params-file', 'Q.yaml', '-p', 'probe:segments:=[1.0]'])
    check_error(result, "parameter 'segments' must be an integer array, got a double array")


@pytest.mark.parametrize('low, high, value, expected', [
    (0.0, None, -1.0, 'expected >= 0, got -1'),
    (None, 5, 6, 'expected <= 5, got 6'),
    (1, 99, 100, 'expected 1..99, got 100'),
    (0.0, None, [1.0, -2.0], 'expected >= 0, got -2'),
])
def test_a_bound_on_one_side_is_stated_with_that_side(low, high, value, expected):
    spec = Spec('x', value, 'a number', low=low, high=high)
    assert spec.problem(value) == expected
