"""`--ros-args` command-line parsing, the subset of ROS 2's syntax the nodes use.

    node --ros-args --params-file F.yaml -p name:=value -r from:=to -r __node:=name
         [--log-level LEVEL] [--]

Everything outside `--ros-args ... [--]` is handed back untouched, as rclpy does. Values after `-p`
are YAML (`-p gain:=2.5`, `-p names:="[a, b]"`), as in ROS 2. Mistakes raise `ParameterError`
with one line naming the argument.
"""
from dataclasses import dataclass, field

import yaml

from bellows_ros.errors import ParameterError

LOG_LEVELS = ('debug', 'info', 'warn', 'error', 'fatal')


@dataclass
class RosArgs:
    """What `--ros-args` said. `params` holds (node name or None, parameter name, value)."""
    params_files: list = field(default_factory=list)
    params: list = field(default_factory=list)
    remaps: dict = field(default_factory=dict)
    node_name: str = None
    namespace: str = None
    log_level: str = 'info'


def parse(argv):
    """Split `argv` (without the program name) into (RosArgs, the other arguments)."""
    ros, rest = RosArgs(), []
    inside = False
    items = iter(argv)
    for arg in items:
        if not inside:
            if arg == '--ros-args':
                inside = True
            else:
                rest.append(arg)
            continue
        if arg == '--':
            inside = False
        elif arg == '--ros-args':
            continue
        elif arg == '--params-file':
            ros.params_files.append(_value(items, arg))
        elif arg in ('-p', '--param'):
            ros.params.append(_parameter(_value(items, arg)))
        elif arg in ('-r', '--remap'):
            _remap(ros, _value(items, arg))
        elif arg == '--log-level':
            level = _value(items, arg).lower()
            if level not in LOG_LEVELS:
                raise ParameterError(f"--ros-args --log-level: unknown level '{level}' "
                                     f"(one of {', '.join(LOG_LEVELS)})")
            ros.log_level = level
        else:
            raise ParameterError(f"--ros-args: unsupported argument '{arg}' "
                                 "(supported: --params-file, -p, -r, --log-level)")
    return ros, rest


def _value(items, flag):
    value = next(items, None)
    if value is None or value.startswith('--'):
        raise ParameterError(f'--ros-args {flag}: missing value')
    return value


def _parameter(text):
    """'name:=value' or 'node:name:=value' -> (node or None, name, value)."""
    name, sep, value_text = text.partition(':=')
    if not sep or not name:
        raise ParameterError(f"--ros-args -p '{text}': expected name:=value")
    node, _, name = name.rpartition(':')
    try:
        value = yaml.safe_load(value_text) if value_text.strip() else ''
    except yaml.YAMLError:
        raise ParameterError(f"--ros-args -p '{text}': value is not valid YAML") from None
    if not name:
        raise ParameterError(f"--ros-args -p '{text}': empty parameter name")
    return (node or None, name, value)


def _remap(ros, text):
    source, sep, target = text.partition(':=')
    if not sep or not source or not target:
        raise ParameterError(f"--ros-args -r '{text}': expected from:=to")
    if source == '__node' or source == '__name':
        ros.node_name = target
    elif source == '__ns':
        ros.namespace = target if target.startswith('/') else '/' + target
    else:
        ros.remaps[source] = target
