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
`--ros-args` on the DDS runtime (ros_args): parsing, parameter precedence, names, remapping.

The same rules run end to end on both runtimes in test_runtime_parameters.py; these are the unit
tests of the pieces, and a fuzz of the parser (any tokens: a result or one ParameterError line).
"""
from hypothesis import example, given, settings
from hypothesis import strategies as st
import pytest

from bellows_ros.errors import ParameterError
from bellows_ros.runtime import ros_args
from bellows_ros.runtime.ros_args import node_identity, parameter_overrides, parse, resolve_topic


def test_parse_full_syntax(tmp_path):
    path = tmp_path / 'a.yaml'
    path.write_text('/**: {ros__parameters: {gain: 1.0}}\n')
    ros, rest = parse(['prog', 'positional', '--ros-args', '--params-file', str(path), '-p',
                       'gain:=2.5', '-p', 'names:=[a, b]', '-p', 'other_node:x:=1', '-r',
                       '__node:=renamed', '-r', 'joint_states:=/js', '-r', 'n:__ns:=/arm',
                       '--log-level', 'WARN', '--', 'tail'])
    assert rest == ['prog', 'positional', 'tail']
    assert ros.parameter_rules == [('file', str(path), {'/**': {'gain': 1.0}}),
                                   ('param', None, 'gain', 2.5),
                                   ('param', None, 'names', ['a', 'b']),
                                   ('param', 'other_node', 'x', 1)]
    assert ros.renames == [(None, '__node', 'renamed'), ('n', '__ns', '/arm')]
    assert ros.remaps == [(None, 'joint_states', '/js')] and ros.log_level == 'warn'


def test_outside_ros_args_is_untouched():
    ros, rest = parse(['prog', '-p', 'x:=1', '--ros-args', '-p', 'y:=2', '--', '-r', 'a:=b'])
    assert rest == ['prog', '-p', 'x:=1', '-r', 'a:=b']
    assert ros.parameter_rules == [('param', None, 'y', 2)] and ros.remaps == []


@pytest.mark.parametrize('argv, message', [
    (['--ros-args', '-p', 'gain'], 'expected [node:]name:=value'),
    (['--ros-args', '-p'], 'missing value'),
    (['--ros-args', '--params-file'], 'missing value'),
    (['--ros-args', '--params-file', 'no_such.yaml'], 'cannot read parameter file'),
    (['--ros-args', '-r', 'a:='], 'expected [node:]from:=to'),
    (['--ros-args', '-r', '__ns:=arm'], "must be fully qualified ('/arm')"),
    (['--ros-args', '-r', '__node:=a/b'], "'a/b' is not a valid node name"),
    (['--ros-args', '--log-level', 'loud'], "unknown level 'loud'"),
    (['--ros-args', '--enclave', 'x'], "unknown argument '--enclave'"),
    (['--ros-args', '-p', 'x:=[1, 2'], 'not valid YAML'),
    (['--ros-args', '-p', 'x:={a: 1}'], 'must be a scalar or a list'),
    (['--ros-args', '-p', 'x:=[1, 2.0]'], 'array elements must all have one type'),
    (['--ros-args', '-p', 'x:=[true, 1]'], 'array elements must all have one type'),
    (['--ros-args', '-p', 'x:=[]'], "parameter 'x' is an empty array"),
    (['--ros-args', '-p', 'x:=[[1]]'], 'must be a scalar or a list'),
    (['--ros-args', '-p', 'x:=!!int abc'], 'not valid YAML'),
    (['--ros-args', '-p', 'x:=!!binary YWJj'], 'must be a scalar or a list'),
    (['--ros-args', '-p', '/node:x:=1'], "'/node' is not a node name"),
])
def test_parse_errors_are_one_line(argv, message):
    with pytest.raises(ParameterError) as info:
        parse(argv)
    assert message in str(info.value) and '\n' not in str(info.value)


@pytest.mark.parametrize('text, value', [
    ('yes', True), ('n', False), ('Off', False), ('tRue', 'tRue'), ("'3'", '3'), ('0x1F', 31),
    ('012', 10), ('08', 8.0), ('+12', 12), ('1_000', '1_000'), ('1:20', '1:20'),
    ('2026-01-01', '2026-01-01'), ('1e-3', 0.001), ('.5', 0.5), ('1.', 1.0), ('0x1p3', 8.0),
    ('[1e5, .5]', [100000.0, 0.5]),
])
def test_values_typed_as_rcl_types_them(text, value):
    """Measured on rclpy (Jazzy): rcl's bool words, C's strtol and strtod, else a string."""
    ros, _ = parse(['--ros-args', '-p', f'x:={text}'])
    assert ros.parameter_rules[0][3] == value
    assert type(ros.parameter_rules[0][3]) is type(value)


@pytest.mark.parametrize('text, message', [
    ('a: {ros__parameters: {x: !!int abc}}', "invalid literal for int() with base 10: 'abc'"),
    ('a: {ros__parameters: {x: [1, 2}}', "expected ',' or ']'"),
    ('a: {ros__parameters: {x: []}}', "parameter 'x' is an empty array"),
    ('a: {ros__parameters: {x: [a, 1]}}', "parameter 'x': array elements must all have one type"),
    ('a: {x: 1}', "section 'a' has no 'ros__parameters' map"),
])
def test_bad_files_are_one_line(tmp_path, text, message):
    path = tmp_path / 'bad.yaml'
    path.write_text(text + '\n')
    with pytest.raises(ParameterError) as info:
        parse(['--ros-args', '--params-file', str(path)])
    assert str(info.value).startswith(str(path)) and message in str(info.value)
    assert '\n' not in str(info.value)


def test_lenient_parse_passes_over_what_only_rcl_knows():
    ros, rest = parse(['--ros-args', '--enclave', '/e', '-p', 'a:=1'], strict=False)
    assert ros.parameter_rules == [('param', None, 'a', 1)]


def overrides(tmp_path, *argv, fqn='/probe'):
    """{name: value} the node `fqn` gets from `--ros-args *argv` (files named by their text)."""
    args = []
    for arg in argv:
        if arg.startswith('{'):  # a file's content, written to a file of its own
            path = tmp_path / f'{len(list(tmp_path.iterdir()))}.yaml'
            path.write_text(arg)
            args += ['--params-file', str(path)]
        else:
            args.append(arg)
    ros, _ = parse(['--ros-args', *args])
    return {name: value for name, (value, _) in parameter_overrides(ros, fqn).items()}


STAR = '{/**: {ros__parameters: {port: /star, gain: 1.5}}, probe: {ros__parameters: {port: /sec}}}'


@pytest.mark.parametrize('argv, fqn, port', [
    ((STAR, '-p', 'port:=/cli'), '/probe', '/sec'),
    ((STAR, '-p', 'probe:port:=/cli'), '/probe', '/cli'),
    (('-p', 'probe:port:=/cli', STAR), '/probe', '/star'),
    (('-p', 'port:=/cli', STAR), '/other', '/star'),
    ((STAR, '-p', 'port:=/cli'), '/other', '/cli'),
    ((STAR,), '/arm/probe', '/star'),
    (('{/*: {ros__parameters: {port: /one}}}',), '/arm/probe', None),
    (('{arm/*: {ros__parameters: {port: /arm}}}',), '/arm/probe', '/arm'),
    (('{/**/probe: {ros__parameters: {port: /deep}}}',), '/a/b/probe', '/deep'),
])
def test_parameter_precedence(tmp_path, argv, fqn, port):
    assert overrides(tmp_path, *argv, fqn=fqn).get('port') == port


def test_source_is_named(tmp_path):
    path = tmp_path / 'f.yaml'
    path.write_text('probe: {ros__parameters: {a: 1, b: 2}}\n')
    ros, _ = parse(['--ros-args', '--params-file', str(path), '-p', 'probe:b:=3'])
    assert parameter_overrides(ros, '/probe') == {'a': (1, str(path)), 'b': (3, '-p')}


@pytest.mark.parametrize('argv, identity', [
    ([], ('probe', '/')),
    (['-r', '__node:=a', '-r', '__node:=b'], ('a', '/')),
    (['-r', 'other:__node:=a', '-r', 'probe:__name:=b'], ('b', '/')),
    (['-r', '__ns:=/p', '-r', '__ns:=/q'], ('probe', '/p')),
    (['-r', 'probe:__node:=n', '-r', 'probe:__ns:=/y', '-r', 'n:__ns:=/x'], ('n', '/x')),
])
def test_node_identity(argv, identity):
    ros, _ = parse(['--ros-args', *argv])
    assert node_identity(ros, 'probe') == identity


@pytest.mark.parametrize('argv, topic, name, namespace, resolved', [
    ([], 'foo', 'probe', '/', '/foo'),
    ([], 'foo', 'probe', '/arm', '/arm/foo'),
    ([], '~/out', 'probe', '/arm', '/arm/probe/out'),
    (['-r', 'foo:=bar'], 'foo', 'probe', '/arm', '/arm/bar'),
    (['-r', 'foo:=bar'], '/foo', 'probe', '/arm', '/foo'),
    (['-r', '/arm/foo:=/z'], 'foo', 'probe', '/arm', '/z'),
    (['-r', 'foo:=~/x'], 'foo', 'probe', '/', '/probe/x'),
    (['-r', '~/out:=/o'], '~/out', 'probe', '/', '/o'),
    (['-r', 'foo:=/a', '-r', 'foo:=/b'], 'foo', 'probe', '/', '/a'),
    (['-r', 'other:foo:=/a', '-r', 'foo:=/b'], 'foo', 'probe', '/', '/b'),
    (['-r', 'probe:foo:=/a', '-r', 'foo:=/b'], 'foo', 'probe', '/', '/a'),
])
def test_resolve_topic(argv, topic, name, namespace, resolved):
    ros, _ = parse(['--ros-args', *argv])
    assert resolve_topic(ros, topic, name, namespace) == resolved


TOKENS = st.one_of(
    st.sampled_from(['--ros-args', '--', '-p', '--param', '-r', '--remap', '--params-file',
                     '--log-level', '--enclave', 'info', 'a:=1', 'n:a:=[1, 2]', '__ns:=/x',
                     '__node:=n', 'n:__ns:=x', 'x:=[', 'x:=!!float a', 'x:={a: 1}', ':=', '']),
    st.text(max_size=12),
    st.builds(lambda a, b: f'{a}:={b}', st.text(max_size=6), st.text(max_size=10)))


@settings(max_examples=400, deadline=None)
@given(st.lists(TOKENS, max_size=8), st.booleans())
@example(['--ros-args', '-p', 'x:=!!int abc'], True)
@example(['--ros-args', '--params-file', 'a\x00b'], True)
@example(['--ros-args', '-p', 'x:=!!binary YWJj'], True)
@example(['--ros-args', '-p', "0:='\n"], True)
def test_fuzz_parse(argv, strict):
    try:
        ros, rest = parse(argv, strict=strict)
    except ParameterError as exc:
        assert str(exc) and '\n' not in str(exc)
        return
    assert isinstance(rest, list) and isinstance(ros, ros_args.RosArgs)
    node_identity(ros, 'probe')
    parameter_overrides(ros, '/probe')
