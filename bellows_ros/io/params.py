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
Parameters: the YAML files in `config/` are the one source of truth.

Files use the ROS 2 parameter format, so the very same file feeds `--ros-args --params-file`::

    /**:
      ros__parameters:
        segment:
          ogden: {mu: [.., ..], gamma: [.., ..]}

Nested maps flatten to dotted names (`segment.ogden.mu`), exactly as ROS 2 does. A file given by
the user (`--params P.yaml`, the output of `bellows identify`) is laid over the defaults; a name
that the defaults do not have is an error, never silently ignored.
"""
import dataclasses
import math
import os
from pathlib import Path
import re
import sys

import yaml

from bellows_ros.errors import ParameterError
from bellows_ros.io.outputs import atomic_file

WILDCARD = '/**'


def config_dir():
    """
    Directory holding the default YAML files.

    Looked up in order: ``$BELLOWS_CONFIG_DIR``; the source tree (editable installs, a checkout);
    ``<prefix>/share/bellows_ros/config`` (pip install); the ament index (colcon install).
    """
    candidates = []
    if os.environ.get('BELLOWS_CONFIG_DIR'):
        candidates.append(Path(os.environ['BELLOWS_CONFIG_DIR']))
    candidates.append(Path(__file__).resolve().parents[2] / 'config')  # bellows_ros/io/ -> top
    candidates.append(Path(sys.prefix) / 'share' / 'bellows_ros' / 'config')
    try:
        from ament_index_python.packages import get_package_share_directory
        candidates.append(Path(get_package_share_directory('bellows_ros')) / 'config')
    except Exception:  # ament_index is absent without ROS, or the package is not in the index
        pass
    for directory in candidates:
        if directory.is_dir():
            return directory
    raise ParameterError('cannot find the bellows_ros config directory; set BELLOWS_CONFIG_DIR')


def default_file(name):
    """Path of `config/<name>.yaml`."""
    return config_dir() / f'{name}.yaml'


PACKAGE_URL = 'package://'


def resolve(path):
    """
    Return the file a parameter file's name stands for.

    A path is itself; a `package://<package>/<path>` URL names a file of that package's share
    directory. The URL is ROS's convention (resource_retriever, URDF meshes), so a parameter
    file that names another one works from a checkout, a pip and a colcon install alike. This
    package is found as `config_dir` finds it (no ROS needed); another through the ament index.
    """
    text = str(path)
    if not text.startswith(PACKAGE_URL):
        return Path(path)
    package, _, inside = text[len(PACKAGE_URL):].partition('/')
    if package == 'bellows_ros':
        return config_dir().parent / inside
    try:
        from ament_index_python.packages import get_package_share_directory
        return Path(get_package_share_directory(package)) / inside
    except Exception:  # ament_index absent (no ROS), or no such package in the index
        raise ParameterError(f"{text}: no package '{package}' in the ament index") from None


def flatten(tree, prefix=''):
    """Flatten nested dicts into ROS 2 dotted parameter names."""
    flat = {}
    for key, value in tree.items():
        name = f'{prefix}{key}'
        if isinstance(value, dict):
            flat.update(flatten(value, name + '.'))
        else:
            flat[name] = value
    return flat


def unflatten(flat):
    """Inverse of `flatten`."""
    tree = {}
    for name, value in flat.items():
        node = tree
        *parents, leaf = name.split('.')
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = value
    return tree


class _RosLoader(yaml.SafeLoader):
    """YAML as rcl's parameter parser reads it (`_rcl_scalar`), not as YAML 1.1 would."""

    # Only `~`/`null` are resolved by pattern; every other plain scalar is a str node, which
    # `_construct_plain` reads as rcl does.
    yaml_implicit_resolvers = {
        first: [(tag, regexp) for tag, regexp in resolvers if tag == 'tag:yaml.org,2002:null']
        for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()}

    def construct_mapping(self, node, deep=False):
        # Keys are parameter names, taken as written (`on:` is the name 'on', not True). A key
        # given twice is an error, as rcl's parser makes it: YAML 1.1 would keep the last one,
        # and a gain written twice would be one the user did not read.
        seen = set()
        for key, _ in node.value:
            if isinstance(key, yaml.ScalarNode) and key.tag == 'tag:yaml.org,2002:str':
                key.style = key.style or "'"
                if key.value in seen:
                    raise yaml.constructor.ConstructorError(
                        None, None, f"key '{key.value}' is given twice", key.start_mark)
                seen.add(key.value)
        return super().construct_mapping(node, deep=deep)


_TRUE = {'Y', 'y', 'yes', 'Yes', 'YES', 'true', 'True', 'TRUE', 'on', 'On', 'ON'}
_FALSE = {'N', 'n', 'no', 'No', 'NO', 'false', 'False', 'FALSE', 'off', 'Off', 'OFF'}
_INTEGER = re.compile(r'[+-]?(?:0[xX][0-9a-fA-F]+|0[0-7]*|[1-9][0-9]*)')
_DOUBLE = re.compile(r'[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?'
                     r'|[+-]?\.?(?:inf|infinity|nan)', re.IGNORECASE)
_HEX_DOUBLE = re.compile(r'[+-]?0[xX](?:[0-9a-fA-F]+\.?[0-9a-fA-F]*|\.[0-9a-fA-F]+)'
                         r'(?:[pP][+-]?[0-9]+)?')


def _rcl_scalar(text):
    """
    Type a plain (unquoted) scalar as rcl's YAML parser does.

    Its bool words, then C's strtol (base 0: `0x1F`, `012` octal), then strtod (`1e-3`, `.5`,
    `inf`, hex), else a string. `1_000`, `1:20` and `2026-01-01` stay strings, as on rcl (YAML 1.1
    would make numbers and a date of them).
    """
    if text in _TRUE or text in _FALSE:
        return text in _TRUE
    if _INTEGER.fullmatch(text):
        sign, digits = (-1, text[1:]) if text[0] == '-' else (1, text.lstrip('+'))
        base = 16 if digits[:2] in ('0x', '0X') else 8 if digits[0] == '0' else 10
        return sign * int(digits, base)
    if _DOUBLE.fullmatch(text):
        # YAML's `.inf` / `.nan` spellings: Python's float wants them without the dot.
        return float(re.sub(r'\.(?=[a-zA-Z])', '', text))
    if _HEX_DOUBLE.fullmatch(text):
        return float.fromhex(text)
    return text


def _construct_plain(loader, node):
    text = loader.construct_scalar(node)
    return _rcl_scalar(text) if node.style is None else text


_RosLoader.add_constructor('tag:yaml.org,2002:str', _construct_plain)


def _construct_python_sequence(loader, suffix, node):
    """Read a `!!python/tuple` (launch_ros writes a list argument so) as rcl does: a sequence."""
    if suffix != 'tuple' or not isinstance(node, yaml.SequenceNode):
        raise yaml.constructor.ConstructorError(
            None, None, f"unsupported tag 'tag:yaml.org,2002:python/{suffix}'", node.start_mark)
    return loader.construct_sequence(node, deep=True)


_RosLoader.add_multi_constructor('tag:yaml.org,2002:python/', _construct_python_sequence)


# Limits of a YAML file the package reads (a parameter file, a bag's metadata.yaml), each named
# when reached: the config files are a few kB and a dozen levels deep. Aliases are counted as
# what they expand to, since flattening a parameter tree walks every copy: a "billion laughs"
# file of a few hundred bytes would otherwise expand to 10**9 nodes.
MAX_YAML_BYTES = 1 << 20
MAX_YAML_DEPTH = 64
MAX_YAML_NODES = 200_000


def _expanded_nodes(root):
    """Nodes of the tree `root` spans with every alias expanded (memoised: no expansion made)."""
    sizes, stack = {}, [(root, False)]
    while stack:
        node, done = stack.pop()
        if id(node) in sizes:
            continue
        children = ([child for pair in node.value for child in pair]
                    if isinstance(node, yaml.MappingNode) else
                    list(node.value) if isinstance(node, yaml.SequenceNode) else [])
        if done:
            sizes[id(node)] = min(1 + sum(sizes[id(child)] for child in children),
                                  MAX_YAML_NODES + 1)
            continue
        stack.append((node, True))
        stack.extend((child, False) for child in children if id(child) not in sizes)
    return sizes[id(root)]


class YamlLimit(yaml.YAMLError):
    """A YAML file beyond MAX_YAML_BYTES, MAX_YAML_DEPTH or MAX_YAML_NODES."""

    def __init__(self, problem, mark=None):
        super().__init__(problem)
        self.problem, self.problem_mark = problem, mark


def load_bounded(text, loader_class):
    """
    Load YAML `text` with `loader_class`, refusing one beyond the limits above (`YamlLimit`).

    The nesting is checked while composing (the composer recurses: a deep file would otherwise
    end in RecursionError), the alias expansion before anything is constructed.
    """
    if len(text) > MAX_YAML_BYTES:
        raise YamlLimit(f'over {MAX_YAML_BYTES >> 20} MiB (params.MAX_YAML_BYTES)')

    class Bounded(loader_class):
        depth = 0

        def compose_node(self, parent, index):
            self.depth += 1
            try:
                if self.depth > MAX_YAML_DEPTH:
                    raise YamlLimit(f'nested deeper than {MAX_YAML_DEPTH} levels '
                                    '(params.MAX_YAML_DEPTH)', self.peek_event().start_mark)
                return super().compose_node(parent, index)
            finally:
                self.depth -= 1

    loader = Bounded(text)
    try:
        root = loader.get_single_node()
        if root is None:
            return None
        if _expanded_nodes(root) > MAX_YAML_NODES:
            raise YamlLimit(f'more than {MAX_YAML_NODES} values with its aliases expanded '
                            '(params.MAX_YAML_NODES)')
        return loader.construct_document(root)
    finally:
        loader.dispose()


def parse_yaml(text):
    """Parse YAML text with rcl's reading of scalars (`yaml.YAMLError` on a syntax error)."""
    return load_bounded(text, _RosLoader)


def read_sections(path):
    """
    Read a ROS 2 parameter file: {section name: flat parameters}, in the file's order.

    Section names are normalised as rcl does (a leading slash added: `model_node` is
    `/model_node`). A malformed file raises ParameterError naming the file and line. `path` may
    be a `package://` URL (`resolve`).
    """
    path = resolve(path)
    try:
        if not path.is_file() and path.exists():  # a FIFO or /dev/zero: no end to read to
            raise ParameterError(f'{path}: not a regular file (a parameter file is a file)')
        with open(path, 'rb') as stream:
            raw = stream.read(MAX_YAML_BYTES + 1)
        if len(raw) > MAX_YAML_BYTES:
            raise ParameterError(f'{path}: over {MAX_YAML_BYTES >> 20} MiB '
                                 '(params.MAX_YAML_BYTES): not a parameter file')
        text = raw.decode()
    except IsADirectoryError:
        raise ParameterError(f'{path}: is a directory, not a parameter file') from None
    except OSError as exc:
        raise ParameterError(f'{path}: cannot read parameter file ({exc.strerror})') from None
    except UnicodeDecodeError:
        raise ParameterError(f'{path}: not a text file') from None
    except ValueError:  # a path no file can have (a NUL byte in it)
        raise ParameterError(f'{path!r}: not a valid file name') from None
    try:
        document = parse_yaml(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, 'problem_mark', None)
        where = f'{path}:{mark.line + 1}' if mark else str(path)
        problem = getattr(exc, 'problem', None) or 'invalid YAML'
        raise ParameterError(f'{where}: {problem}') from None
    except ValueError as exc:  # a tag the value does not fit (`!!int abc`)
        raise ParameterError(f'{path}: {exc}') from None
    if not isinstance(document, dict):
        raise ParameterError(f"{path}: expected a map of node names to 'ros__parameters'")
    sections = {}
    for section, body in document.items():
        if not isinstance(body, dict) or not isinstance(body.get('ros__parameters'), dict):
            raise ParameterError(f"{path}: section {str(section)!r} has no 'ros__parameters' map")
        flat = flatten(body['ros__parameters'])
        for name, value in flat.items():
            # A blank, a control character or an empty part between dots names no parameter (and
            # would break the one-line message).
            if not name.isprintable() or ' ' in name or '' in name.split('.'):
                raise ParameterError(f'{path}: {name!r} is not a parameter name')
            _check_value(path, name, value)
        key = '/' + str(section).lstrip('/')
        sections[key] = {**sections.get(key, {}), **flat}
    return sections


def section_matches(section, node_fqn):
    """
    Tell whether parameter-file section `section` applies to the node `node_fqn` (`/ns/name`).

    rcl's rule: a section is the node's fully qualified name, where `*` stands for one name token
    and `**` for any number of them (`/**` = every node, `/*` = every node in `/`).
    """
    def match(pattern, tokens):
        if not pattern:
            return not tokens
        head, rest = pattern[0], pattern[1:]
        if head == '**':
            return any(match(rest, tokens[i:]) for i in range(len(tokens) + 1))
        return bool(tokens) and head in ('*', tokens[0]) and match(rest, tokens[1:])
    return match(section.strip('/').split('/'), node_fqn.strip('/').split('/'))


def read_file(path, node_name=None):
    """
    Read a ROS 2 parameter file into a flat dict of dotted names.

    Without `node_name`: the ``/**`` section. With it: every section that applies to that node
    (`section_matches`; a bare name is a node in `/`), later sections over earlier ones, as rcl
    merges them. Other nodes' sections are skipped.
    """
    sections = read_sections(path)
    if node_name is None:
        if WILDCARD not in sections:
            raise ParameterError(f"{path}: no '/**' section with 'ros__parameters'")
        return dict(sections[WILDCARD])
    fqn = '/' + node_name.lstrip('/')
    flat = {}
    for section, values in sections.items():
        if section_matches(section, fqn):
            flat.update(values)
    return flat


def _check_value(path, name, value):
    values = value if isinstance(value, list) else [value]
    for item in values:
        if isinstance(item, float) and not math.isfinite(item):
            raise ParameterError(f"{path}: parameter '{name}' is not finite ({item})")
        if isinstance(item, int) and not isinstance(item, bool) and abs(item) > _LARGEST_INT:
            raise ParameterError(f"{path}: parameter '{name}' is beyond float range (2**1023)")
        if not isinstance(item, (bool, int, float, str)):
            raise ParameterError(f"{path}: parameter '{name}' has an unsupported value {item!r}")


# A YAML integer past float range would overflow the first time the model computes with it.
_LARGEST_INT = 2 ** 1023


def _kind(value):
    """'bool', 'number', 'string' or 'list'."""
    if isinstance(value, list):
        return 'list'
    if isinstance(value, bool):  # before int: YAML's true is not the number 1
        return 'bool'
    return 'number' if isinstance(value, (int, float)) else 'string'


def _check_kind(source, name, default, value):
    """
    `value` must be of the default's kind, a list's items of the kind of the default's items.

    A string where a number belongs would otherwise reach the model as a TypeError deep inside.
    """
    expected = _kind(default)
    if expected != _kind(value):
        raise ParameterError(f"{source}: parameter '{name}' expects a {expected} (like "
                             f'{default!r}), got {value!r}')
    if expected == 'list' and default:
        item_kind = _kind(default[0])
        wrong = next((item for item in value if _kind(item) != item_kind), None)
        if wrong is not None:
            raise ParameterError(f"{source}: parameter '{name}' expects a list of {item_kind}s "
                                 f'(like {default!r}), got {wrong!r} in it')


def overlay(defaults, overrides, source, open_sections=()):
    """
    Lay `overrides` over `defaults`.

    A name the defaults lack, or a value of another kind (a string for a number, a scalar for a
    list), raises ParameterError. Names under `open_sections` (prefixes such as
    'actuator.effects.') are the business of what reads that section, which checks them.
    """
    unknown = sorted(name for name in set(overrides) - set(defaults)
                     if not name.startswith(tuple(open_sections)))
    if unknown:
        raise ParameterError(f"{source}: unknown parameter '{unknown[0]}'"
                             + (f' (and {len(unknown) - 1} more)' if len(unknown) > 1 else ''))
    for name, value in overrides.items():
        if name in defaults:
            _check_kind(source, name, defaults[name], value)
    merged = dict(defaults)
    merged.update(overrides)
    return merged


def load(name, params_path=None, check=None, open_sections=()):
    """
    Defaults of `config/<name>.yaml`, with the user's file (if any) laid over them.

    `check(flat, source)` (e.g. `config.ranges.check_ranges`) sees each file's own values, so that
    its error names the file a bad value came from. `open_sections`: see `overlay`.
    """
    path = default_file(name)
    flat = read_file(path)
    if check is not None:
        check(flat, path)
    if params_path is not None:
        user = read_file(params_path)
        flat = overlay(flat, user, params_path, open_sections)
        if check is not None:
            check(user, params_path)
    return flat


def section(flat, prefix):
    """Return the parameters under `prefix.`, with the prefix stripped."""
    start = prefix + '.'
    return {name[len(start):]: value for name, value in flat.items() if name.startswith(start)}


def build(cls, values, source):
    """
    Construct dataclass `cls` from a flat mapping; unknown or missing names raise ParameterError.

    Lists become tuples of float so the dataclass stays hashable and immutable.
    """
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(set(values) - set(fields))
    if unknown:
        raise ParameterError(f"{source}: unknown parameter '{unknown[0]}'")
    kwargs = {}
    for name, field in fields.items():
        if name in values:
            value = values[name]
            kwargs[name] = tuple(float(v) for v in value) if isinstance(value, list) else value
        elif field.default is dataclasses.MISSING and field.default_factory is dataclasses.MISSING:
            raise ParameterError(f"{source}: missing parameter '{name}'")
    return cls(**kwargs)


def write_file(path, flat, header=None, check=None):
    """
    Write a flat parameter dict as a ROS 2 parameter file (section ``/**``), atomically.

    `check(path)` reads the finished file back (e.g. with its loader) before it replaces `path`.
    """
    def plain(value):
        if isinstance(value, (list, tuple)):
            return [plain(v) for v in value]
        if hasattr(value, 'item'):  # NumPy scalar
            return value.item()
        return value
    tree = unflatten({name: plain(value) for name, value in flat.items()})
    text = yaml.safe_dump({WILDCARD: {'ros__parameters': tree}}, sort_keys=False,
                          default_flow_style=None)
    with atomic_file(path, check=check) as stream:
        if header:
            stream.write(''.join(f'# {line}\n' for line in header.splitlines()))
        stream.write(text)
