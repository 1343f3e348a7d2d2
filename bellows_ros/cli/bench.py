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

"""`bellows bench [--json]`: run every benchmark module in `bellows_ros.bench`."""
import importlib
import json
import pkgutil
import sys

import bellows_ros.bench as bench_package
from bellows_ros.errors import BellowsError


def add_arguments(parser):
    parser.add_argument('--json', action='store_true', help='print results as JSON')
    parser.add_argument('--only', metavar='TEXT',
                        help='run only benchmark modules whose name contains TEXT')
    parser.add_argument('--quick', action='store_true',
                        help='fewer calls (a smoke run, less precise)')


def run(args):
    results = []
    names = sorted(info.name for info in pkgutil.iter_modules(bench_package.__path__))
    chosen = [name for name in names if not args.only or args.only in name]
    if not chosen:
        raise BellowsError(f"--only {args.only!r}: no benchmark module's name contains it "
                           f"(modules: {', '.join(names)})")
    for name in chosen:
        print(f'bench: {name} ...', file=sys.stderr)
        module = importlib.import_module(f'bellows_ros.bench.{name}')
        results.extend(module.run(quick=args.quick))
    if args.json:
        print(json.dumps([r.as_dict() for r in results], indent=2))
    else:
        print(format_table(results))
    return 0


def _show(value, unit):
    if unit == 's':
        return f'{value * 1e6:10.2f} µs' if value < 1e-2 else f'{value:10.3f} s '
    return f'{value:10.4g} {unit}'


def format_table(results):
    lines = [f"{'benchmark':<48} {'median':>13} {'ratio':>8}  {'target':>13}  reference"]
    for r in results:
        ratio = f'{r.ratio:8.2f}' if r.ratio is not None else ' ' * 8
        target = _show(r.target, r.unit) if r.target is not None else ' ' * 13
        lines.append(f'{r.name:<48} {_show(r.value, r.unit)} {ratio}  {target}  '
                     f'{r.reference or ""}')
        for key, value in r.extra.items():
            shown = (_show(value, r.extra_units.get(key, r.unit)) if isinstance(value, float)
                     else value)
            lines.append(f'    {key}: {shown}')
    return '\n'.join(lines)
