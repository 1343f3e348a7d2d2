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
`--ros-args` on the DDS runtime: the subset of rcl's syntax the nodes use, with rcl's meaning.

    node --ros-args --params-file F.yaml -p [node:]name:=value -r [node:]from:=to
         -r __node:=name -r __ns:=/ns --log-level LEVEL [--]

Everything outside `--ros-args ... [--]` is handed back untouched, as rclpy does. Values after `-p`
are YAML (`-p gain:=2.5`, `-p names:="[a, b]"`), scalars typed as rcl types them
(`params.parse_yaml`: `yes` is a bool, `012` an integer, `1e-3` a double). Mistakes raise
`ParameterError` with one line naming the argument.

What rcl does, and this module does the same (test_runtime_parameters.py runs the same cases on
rclpy and on the DDS runtime):

- Parameters. Every `--params-file` section and every `-p` rule is an entry keyed by a node name
  (`-p name:=v` is `/**`, `-p node:name:=v` is `/node`). Entries are kept in the order their key
  first appeared on the command line; a later value for the same key and name replaces the earlier
  one in place. A node takes every entry that matches its fully qualified name
  (`params.section_matches`), in that order, the later over the earlier. So a node's own section in
  a file wins over `-p name:=v` given after it (that lands in the earlier `/**` entry); to override
  a node's own section from the command line, name the node: `-p node:name:=v`.
- Remapping. `from` and `to` are expanded in the node's namespace (`joint_states` in `/` is
  `/joint_states`, `~` is the node's own name); the first matching rule wins; `node:from:=to`
  applies to that node only, named as it is after `__node`.
- `__node` and `__ns`: the first matching rule of each wins; `node:__ns:=/ns` names the node as it
  is after `__node`; a namespace must be fully qualified (`/arm`, not `arm`).
- Values. An array's elements have one type (`[1, 2.0]` is an error) and an empty array has none
  (rcl leaves it unset): both are errors here, in a file or after `-p`. A later array of another
  element type for the same node and name replaces the earlier one here (rcl silently keeps the
  earlier one: a quirk not copied), so the declared type reports it.
"""
from dataclasses import dataclass, field

import yaml

from bellows_ros import params as params_module
from bellows_ros.errors import ParameterError

LOG_LEVELS = ('debug', 'info', 'warn', 'error', 'fatal')


@dataclass
class RosArgs:
    """
    What `--ros-args` said, in order.

    `parameter_rules` holds ('file', path, {section: flat parameters}) and
    ('param', node or None, name, value); `remaps` holds
    (node or None, from, to); `renames` holds (node or None, '__node' or '__ns', value).
    """

    parameter_rules: list = field(default_factory=list)
    remaps: list = field(default_factory=list)
    renames: list = field(default_factory=list)
    log_level: str = 'info'


def parse(argv, strict=True):
    """
    Split `argv` into (RosArgs, the other arguments); ParameterError on a malformed argument.

    Parameter files are read here, so a bad one is reported before any node starts. With
    `strict=False` an argument this parser does not know is passed over (rclpy checks the
    arguments this way first, so both runtimes word the same mistakes the same way, then lets rcl
    judge the arguments only it knows).
    """
    try:
        return _parse(argv, strict)
    except ParameterError as exc:
        # Messages quote the argument: keep them one line whatever it holds (a newline, ESC).
        raise ParameterError(''.join(c if c.isprintable() else repr(c)[1:-1]
                                     for c in str(exc))) from None


def _parse(argv, strict):
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
            path = _value(items, arg)
            sections = params_module.read_sections(path)
            for values in sections.values():
                for name, value in values.items():
                    _check_array(path, name, value)
            ros.parameter_rules.append(('file', path, sections))
        elif arg in ('-p', '--param'):
            text = _value(items, arg)
            rule = _parameter(text)
            _check_array(f"--ros-args -p '{text}'", rule[1], rule[2])
            ros.parameter_rules.append(('param', *rule))
        elif arg in ('-r', '--remap'):
            _remap(ros, _value(items, arg))
        elif arg == '--log-level':
            level = _value(items, arg).lower()
            if level not in LOG_LEVELS:
                raise ParameterError(f"--ros-args --log-level: unknown level '{level}' "
                                     f"(one of {', '.join(LOG_LEVELS)})")
            ros.log_level = level
        elif strict:
            raise ParameterError(f"--ros-args: unknown argument '{arg}' (the DDS runtime "
                                 'takes --params-file, -p, -r and --log-level)')
    return ros, rest


def _check_array(where, name, value):
    """Check an array as rcl does: not empty (it could not tell the type), one element type."""
    if not isinstance(value, list):
        return
    if not value:
        raise ParameterError(f"{where}: parameter '{name}' is an empty array (rcl cannot tell "
                             'its type)')
    if len({type(item) for item in value}) > 1:
        raise ParameterError(f"{where}: parameter '{name}': array elements must all have one "
                             f'type, got {value!r}')


def _value(items, flag):
    value = next(items, None)
    if value is None or value.startswith('--'):
        raise ParameterError(f'--ros-args {flag}: missing value')
    return value


def _is_name_token(text):
    """Check rcl's name token: letters, digits and underscores, not starting with a digit."""
    return bool(text) and text.replace('_', 'a').isalnum() and text.isascii() \
        and not text[0].isdigit()


def _node_prefix(text, flag):
    """'node:rest' -> ('node', 'rest'); 'rest' -> (None, 'rest'). rcl takes a bare node name."""
    node, sep, rest = text.partition(':')
    if not sep or rest.startswith('='):
        return None, text
    if not _is_name_token(node):
        raise ParameterError(f"--ros-args {flag} '{text}': '{node}' is not a node name")
    return node, rest


def _parameter(text):
    """'name:=value' or 'node:name:=value' -> (node or None, name, value)."""
    node, rule = _node_prefix(text, '-p')
    name, sep, value_text = rule.partition(':=')
    if not sep or not name:
        raise ParameterError(f"--ros-args -p '{text}': expected [node:]name:=value")
    try:
        value = params_module.parse_yaml(value_text) if value_text.strip() else ''
    except (yaml.YAMLError, ValueError):  # ValueError: a tag that does not fit (`!!int a`)
        raise ParameterError(f"--ros-args -p '{text}': value is not valid YAML") from None
    items = value if isinstance(value, list) else [value]
    if not all(isinstance(item, (bool, int, float, str)) for item in items):
        raise ParameterError(f"--ros-args -p '{text}': value must be a scalar or a list")
    return node, name, value


def _remap(ros, text):
    node, rule = _node_prefix(text, '-r')
    source, sep, target = rule.partition(':=')
    if not sep or not source or not target:
        raise ParameterError(f"--ros-args -r '{text}': expected [node:]from:=to")
    if source in ('__node', '__name'):
        if not _is_name_token(target):
            raise ParameterError(f"--ros-args -r '{text}': '{target}' is not a valid node name")
        ros.renames.append((node, '__node', target))
    elif source == '__ns':
        if not target.startswith('/'):
            raise ParameterError(f"--ros-args -r '{text}': the namespace must be fully "
                                 f"qualified ('/{target}')")
        namespace = target
        if namespace != '/' and not all(_is_name_token(t) for t in namespace[1:].split('/')):
            raise ParameterError(f"--ros-args -r '{text}': '{target}' is not a valid namespace")
        ros.renames.append((node, '__ns', namespace))
    else:
        ros.remaps.append((node, source, target))


def node_identity(ros, name, namespace='/'):
    """
    (name, namespace) of a node created as `name` in `namespace`, after `__node` / `__ns`.

    As rcl: the first matching rule of each kind wins, and `__ns` rules see the new name.
    """
    name = _first_rename(ros, '__node', name) or name
    return name, _first_rename(ros, '__ns', name) or namespace


def _first_rename(ros, kind, name):
    return next((value for node, rule_kind, value in ros.renames
                 if rule_kind == kind and node in (None, name)), None)


def expand(topic, node_name, namespace):
    """Qualify a topic name fully in the node's namespace (`~` is the node's own name)."""
    base = namespace.rstrip('/')
    if topic.startswith('~'):
        return f'{base}/{node_name}' + topic[1:]
    return topic if topic.startswith('/') else f'{base}/{topic}'


def resolve_topic(ros, topic, node_name, namespace):
    """Return the fully qualified topic a node (named as after `__node`) uses, after remapping."""
    resolved = expand(topic, node_name, namespace)
    for node, source, target in ros.remaps:
        if node is not None and node != node_name:
            continue
        if expand(source, node_name, namespace) == resolved:
            return expand(target, node_name, namespace)
    return resolved


def parameter_overrides(ros, node_fqn):
    """{name: (value, source)} of every parameter given for the node `node_fqn` (rcl's order)."""
    entries = {}  # node key -> {name: (value, source)}, in order of first appearance
    for rule in ros.parameter_rules:
        if rule[0] == 'file':
            for section, values in rule[2].items():
                entry = entries.setdefault(section, {})
                entry.update({name: (value, rule[1]) for name, value in values.items()})
        else:
            _, node, name, value = rule
            entries.setdefault('/' + node if node else params_module.WILDCARD, {})[name] = \
                (value, '-p')
    overrides = {}
    for section, values in entries.items():
        if params_module.section_matches(section, node_fqn):
            overrides.update(values)
    return overrides
