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
The package's import graph (from the source, with ast): no cycles, every import goes down.

The shape: a base (errors, the interface contract, io: files in and out), the models, the
configuration that builds their parameters and the papers' experiments on the simulated devices;
then two stacks side by side on them: offline, for records (identify, doctor), and online, for a
robot (hardware -> control -> runtime and nodes). The online stack reaches the offline one only
through the doctor live (`doctor.live`, for the nodes). On top, the tools that use both (cli,
bench). The models read no file: they import nothing of the package but other models and the
errors; the config layer reads config/*.yaml and builds their parameter objects. The README
draws this picture; this module is its one definition.

Every import counts, also one inside a function: a deferred import still ties the two modules
together, it only hides the cycle until run time.
"""
import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / 'bellows_ros'

# Rank of each top-level part of the package; a module may import only its own rank or lower.
LAYERS = {
    'errors': 0, 'interfaces': 0, 'io': 0,
    'models': 1,
    'config': 2, 'papers': 2,
    'identify': 3, 'doctor': 3,                               # offline stack
    'hardware': 3, 'control': 4, 'nodes': 5, 'runtime': 5,   # online stack
    'bench': 6, 'cli': 6,
}
STACKS = {'offline': {'identify', 'doctor'},
          'online': {'hardware', 'control', 'nodes', 'runtime'}}
# The one way from the online stack to the offline one: the doctor live, for the nodes.
BRIDGE = 'bellows_ros.doctor.live'


def _modules():
    modules = {}
    for path in PACKAGE.rglob('*.py'):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix('').parts)
        if parts[-1] == '__init__':
            parts.pop()
        modules['.'.join(parts)] = path
    return modules


def import_graph():
    """Return {module: set of bellows_ros modules it imports} for every module of the package."""
    modules = _modules()

    def resolve(name):
        while name and name not in modules:
            name = name.rpartition('.')[0]
        return name

    graph = {}
    for name, path in modules.items():
        package = name if path.name == '__init__.py' else name.rpartition('.')[0]
        targets = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                targets.update(resolve(a.name) for a in node.names
                               if a.name.split('.')[0] == 'bellows_ros')
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ''
                if node.level:
                    parts = package.split('.')[:len(package.split('.')) - node.level + 1]
                    base = '.'.join(parts + ([node.module] if node.module else []))
                if base.split('.')[0] != 'bellows_ros':
                    continue
                for alias in node.names:
                    full = f'{base}.{alias.name}'
                    targets.add(full if full in modules else resolve(base))
        targets.discard(name)
        targets.discard('')
        graph[name] = targets
    return graph


def cycles(graph):
    """Strongly connected components with more than one module (Tarjan), each sorted."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def _layer(module):
    parts = module.split('.')
    return LAYERS.get(parts[1]) if len(parts) > 1 else None


def test_the_graph_sees_the_package():
    graph = import_graph()
    assert 'bellows_ros.models.segment' in graph['bellows_ros.identify.segment']
    assert 'bellows_ros.runtime' in graph['bellows_ros.nodes.model_node']
    assert 'bellows_ros.io.bag' in graph['bellows_ros.io.data']  # a deferred import counts


def test_the_cycle_finder_finds_a_cycle():
    assert cycles({'a': {'b'}, 'b': {'c'}, 'c': {'a'}, 'd': {'a'}}) == [['a', 'b', 'c']]
    assert cycles({'a': {'b'}, 'b': set()}) == []


def test_no_import_cycle_in_the_package():
    assert cycles(import_graph()) == []


def test_every_part_of_the_package_has_a_layer():
    unplaced = {m.split('.')[1] for m in import_graph() if m.count('.') >= 1} - set(LAYERS)
    assert not unplaced, f'add {sorted(unplaced)} to LAYERS'


def test_the_two_stacks_do_not_import_each_other():
    stack_of = {part: name for name, parts in STACKS.items() for part in parts}

    def stack(module):
        return stack_of.get(module.split('.')[1]) if module.count('.') else None
    across = sorted(f'{source} -> {target}' for source, targets in import_graph().items()
                    for target in targets - {BRIDGE}
                    if stack(source) and stack(target) and stack(source) != stack(target))
    assert across == []


def test_the_online_stack_reaches_the_offline_one_only_through_the_live_doctor():
    """The nodes reach the doctor through `BRIDGE` alone: the stiffness controller, model node."""
    graph = import_graph()
    offline = {m for m in graph if m.count('.') and m.split('.')[1] in STACKS['offline']}
    online = [m for m in graph if m.count('.') and m.split('.')[1] in STACKS['online']]
    without_bridge = {m: t - {BRIDGE} for m, t in graph.items()}
    assert [m for m in online if reachable(without_bridge, m) & offline] == []
    users = sorted(m for m in online if BRIDGE in graph[m])
    assert users == ['bellows_ros.nodes.model_node', 'bellows_ros.nodes.stiffness_controller_node']
    assert reachable(graph, BRIDGE) & offline    # the rule is not vacuous


def test_layers_import_only_downward():
    upward = sorted(f'{source} -> {target}' for source, targets in import_graph().items()
                    for target in targets
                    if _layer(source) is not None and _layer(target) is not None
                    and _layer(target) > _layer(source))
    assert upward == []


# What the models may import from the package: each other and the errors. Everything that reads a
# file (params, data, bag, table, config, the CLI...) lies outside this set.
MODEL_IMPORTS = ('bellows_ros.models', 'bellows_ros.errors')
# Calls that read or write a file, wherever they come from.
FILE_CALLS = {'open', 'read_text', 'write_text', 'read_bytes', 'write_bytes', 'loadtxt',
              'genfromtxt', 'savetxt', 'safe_load', 'load', 'atomic_file'}


def _is_model(module):
    return module == 'bellows_ros.models' or module.startswith('bellows_ros.models.')


def test_the_models_import_nothing_that_reads_files():
    outside = sorted(f'{source} -> {target}' for source, targets in import_graph().items()
                     if _is_model(source) for target in targets
                     if not target.startswith(MODEL_IMPORTS))
    assert outside == []


def test_the_models_call_no_file_function():
    calls = []
    for name, path in _modules().items():
        if not _is_model(name):
            continue
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Call):
                func = node.func
                called = func.id if isinstance(func, ast.Name) else getattr(func, 'attr', None)
                if called in FILE_CALLS:
                    calls.append(f'{name}:{node.lineno} {called}()')
    assert calls == []


def test_the_file_rules_see_a_violation():
    """The two rules above are not vacuous: the config layer breaks both, as it should."""
    graph = import_graph()
    assert 'bellows_ros.io.params' in graph['bellows_ros.config.segment']
    assert not all(t.startswith(MODEL_IMPORTS) for t in graph['bellows_ros.config.segment'])
    source = (PACKAGE / 'io' / 'params.py').read_text()
    assert any(isinstance(n, ast.Call)
               and (getattr(n.func, 'id', None) or getattr(n.func, 'attr', None)) in FILE_CALLS
               for n in ast.walk(ast.parse(source)))


def reachable(graph, start):
    """Every module `start` imports, directly or through others."""
    seen, todo = set(), [start]
    while todo:
        for target in graph.get(todo.pop(), ()):
            if target not in seen:
                seen.add(target)
                todo.append(target)
    return seen


# The drivers' configuration path and the one piece of physics it may touch: the drive train
# (`Drive.metres_per_count`, the encoder scale), which solves nothing.
DRIVER_MODULES = ('bellows_ros.config.hardware', 'bellows_ros.hardware.actuator_board',
                  'bellows_ros.hardware.arm_bus', 'bellows_ros.hardware.sim_arm_bus',
                  'bellows_ros.hardware.sim_actuator_board', 'bellows_ros.nodes.driver_node')
# models.limits holds plain numbers (the parameter ranges' physical limits) and computes nothing.
DRIVER_MODELS = {'bellows_ros.models.actuator_drive', 'bellows_ros.models.derivatives',
                 'bellows_ros.models.limits'}


def test_the_drivers_configuration_imports_no_physics_model():
    graph = import_graph()
    assert 'bellows_ros.models.actuator' in reachable(graph, 'bellows_ros.config.actuator')
    for module in DRIVER_MODULES:
        models = {m for m in reachable(graph, module) if _is_model(m)}
        assert models <= DRIVER_MODELS, f'{module} reaches {sorted(models - DRIVER_MODELS)}'


# The runtime holds what runs a node on rclpy, and nothing else.
RUNTIME_MODULES = {'__init__', 'node', 'messages', 'joint_state_cdr', 'parameters', 'realtime',
                   'record', 'managed_launch'}


def test_the_runtime_holds_only_the_rclpy_node_base():
    assert {p.stem for p in (PACKAGE / 'runtime').glob('*.py')} == RUNTIME_MODULES
    assert not [p for p in (PACKAGE / 'runtime').iterdir() if p.is_dir()
                and p.name != '__pycache__']


def _ros_imports(path):
    """Return the ROS 2 modules (rclpy, rosidl message packages) `path` imports anywhere."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        names = [a.name for a in node.names] if isinstance(node, ast.Import) else (
            [node.module or ''] if isinstance(node, ast.ImportFrom) and not node.level else [])
        found.update(n for n in names if n.split('.')[0] == 'rclpy'
                     or n.split('.')[0].endswith(('_msgs', '_srvs', '_interfaces')))
    return found


# The parts that work on files, without ROS 2: they never import rclpy (nor a message package),
# not even deferred, so that identify, doctor and the file commands run where ROS is absent.
WITHOUT_ROS = ('models', 'config', 'identify', 'doctor', 'errors', 'outputs', 'params', 'table',
               'data', 'bag', 'bag_repair')


def test_the_offline_parts_never_import_rclpy():
    offenders = {name: _ros_imports(path) for name, path in _modules().items()
                 if name.count('.') and name.split('.')[1] in WITHOUT_ROS}
    assert {name: found for name, found in offenders.items() if found} == {}
    assert len(offenders) > 20  # the rule sees the modules


def test_the_file_commands_run_without_importing_rclpy(tmp_path):
    """`bellows export`, `identify`, `diagnose` (through the CLI's own parser) load no rclpy."""
    import subprocess
    import sys
    missing = tmp_path / 'not_a_bag'  # a directory: the bag reader is loaded, and refuses it
    missing.mkdir()
    (missing / 'metadata.yaml').write_text('rosbag2_bagfile_information: {}\n')
    script = (
        'import sys\n'
        'from bellows_ros.cli import main\n'
        f"for argv in (['export', 'segment', '{missing}', '--output', '{tmp_path}/o.csv'],\n"
        f"             ['identify', 'segment', '{missing}', '--output', '{tmp_path}/p.yaml'],\n"
        f"             ['diagnose', 'segment', '{missing}', '--report', '{tmp_path}/r']):\n"
        '    assert main(argv) == 2, argv  # the missing input: a one-line error\n'
        "ros = sorted(m for m in sys.modules if m.split('.')[0] == 'rclpy')\n"
        "print('rclpy modules:', ros)\n")
    result = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == 'rclpy modules: []', result.stdout
    assert result.stderr.count('error:') == 3, result.stderr


def test_every_package_states_what_it_holds():
    """Each sub-package says what it holds (docstring) and what is public (`__all__`, REP-2004)."""
    problems = []
    for init in sorted(PACKAGE.glob('*/**/__init__.py')):
        tree = ast.parse(init.read_text(), str(init))
        if not ast.get_docstring(tree):
            problems.append(f'{init.parent.name}: no docstring')
        listed = [node.value for node in ast.walk(tree) if isinstance(node, ast.Assign)
                  and any(getattr(t, 'id', None) == '__all__' for t in node.targets)]
        if not listed:
            problems.append(f'{init.parent.name}: no __all__')
            continue
        names = ast.literal_eval(listed[0])
        defined = {getattr(n, 'name', None) for n in tree.body} | {
            t.id for n in tree.body if isinstance(n, ast.Assign) for t in n.targets
            if isinstance(t, ast.Name)} | {
            (a.asname or a.name) for n in tree.body if isinstance(n, ast.ImportFrom)
            for a in n.names}
        problems += [f'{init.parent.name}: {name} is neither a module nor defined there'
                     for name in names
                     if name not in defined and not (init.parent / f'{name}.py').exists()
                     and not (init.parent / name / '__init__.py').exists()]
    assert problems == []
