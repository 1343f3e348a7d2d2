"""--ros-args parsing and parameter overrides on the DDS runtime."""
import pytest

from bellows_ros.errors import ParameterError
from bellows_ros.runtime import dds_node
from bellows_ros.runtime.ros_args import parse


def test_parse_full_syntax():
    ros, rest = parse(['prog', 'positional', '--ros-args', '--params-file', 'a.yaml', '-p',
                       'gain:=2.5', '-p', 'names:=[a, b]', '-p', 'other_node:x:=1', '-r',
                       '__node:=renamed', '-r', 'joint_states:=/js', '-r', '__ns:=arm',
                       '--log-level', 'WARN', '--', 'tail'])
    assert rest == ['prog', 'positional', 'tail']
    assert ros.params_files == ['a.yaml']
    assert ros.params == [(None, 'gain', 2.5), (None, 'names', ['a', 'b']), ('other_node', 'x', 1)]
    assert ros.node_name == 'renamed' and ros.namespace == '/arm'
    assert ros.remaps == {'joint_states': '/js'} and ros.log_level == 'warn'


@pytest.mark.parametrize('argv, message', [
    (['--ros-args', '-p', 'gain'], 'expected name:=value'),
    (['--ros-args', '-p'], 'missing value'),
    (['--ros-args', '--params-file'], 'missing value'),
    (['--ros-args', '-r', 'a:='], 'expected from:=to'),
    (['--ros-args', '--log-level', 'loud'], "unknown level 'loud'"),
    (['--ros-args', '--enclave', 'x'], "unsupported argument '--enclave'"),
    (['--ros-args', '-p', 'x:=[1, 2'], 'not valid YAML'),
])
def test_parse_errors_are_one_line(argv, message):
    with pytest.raises(ParameterError, match=message) as info:
        parse(argv)
    assert '\n' not in str(info.value)


@pytest.fixture
def domain(monkeypatch):
    monkeypatch.setenv('ROS_DOMAIN_ID', '187')
    yield
    dds_node.shutdown()


def test_params_file_then_p_override(tmp_path, domain):
    path = tmp_path / 'p.yaml'
    path.write_text('/**:\n  ros__parameters:\n    gain: 1.0\n    label: shared\n'
                    'my_node:\n  ros__parameters:\n    gain: 2\n    limits: [1, 2.5]\n'
                    'someone_else:\n  ros__parameters:\n    gain: 99.0\n')
    dds_node.init(['prog', '--ros-args', '--params-file', str(path), '-p', 'label:=cli',
                   '-p', 'someone_else:gain:=7.0'])
    node = dds_node.Node('my_node')
    assert node.declare_parameter('gain', 0.5).value == 2.0  # node section beats /**, int -> double
    assert isinstance(node.get_parameter('gain').value, float)
    assert node.declare_parameter('label', 'x').value == 'cli'  # -p beats the file
    assert node.declare_parameter('limits', [0.0]).value == [1.0, 2.5]
    assert node.declare_parameter('untouched', 3).value == 3
    assert node.undeclared_overrides() == []


def test_unknown_and_mistyped_parameters(tmp_path, domain):
    dds_node.init(['prog', '--ros-args', '-p', 'gian:=3.0', '-p', 'rate:=fast'])
    node = dds_node.Node('my_node')
    with pytest.raises(ParameterError, match="-p: parameter 'rate': expected a double, got a string"):
        node.declare_parameter('rate', 1000.0)
    assert node.undeclared_overrides() == [('gian', '-p'), ('rate', '-p')]
    with pytest.raises(ParameterError, match="'nope' is not declared"):
        node.get_parameter('nope')


def test_node_rename_and_topic_remap(domain):
    dds_node.init(['prog', '--ros-args', '-r', '__node:=other', '-r', 'joint_states:=/sim/js'])
    node = dds_node.Node('driver_node')
    assert node.get_name() == 'other'
    assert node.resolve_topic_name('joint_states') == '/sim/js'
    assert node.resolve_topic_name('/bellows/wrench') == '/bellows/wrench'
    publisher = node.create_publisher(dds_node.message_class('std_msgs/msg/Float64'), 'x/y', 10)
    assert publisher.topic_name == '/x/y'
