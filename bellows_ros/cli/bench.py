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
`bellows bench`: run every benchmark module in `bellows_ros.bench`, or render kept records.

`--json` prints the run's record (`bench_records.record`: package, commit, date, host, command,
results); `--output FILE` writes it. `--render FILE...` renders records instead of running
anything: the results side by side, and with `--plot PNG` a figure of them.
"""
import datetime
import fnmatch
import importlib
import inspect
import json
import pkgutil
import sys
import time

import bellows_ros.bench as bench_package
from bellows_ros.cli import bench_records
from bellows_ros.errors import BellowsError
from bellows_ros.io.outputs import check_output, write_text


def add_arguments(parser):
    parser.add_argument('--json', action='store_true', help='print results as JSON')
    parser.add_argument('--only', metavar='NAME[,NAME...]',
                        help='run only these benchmark modules: names or shell patterns '
                             "('graph*'), comma-separated for one seeded run of several")
    parser.add_argument('--quick', action='store_true',
                        help='fewer calls (a smoke run, less precise)')
    # A subset of a drawn-device bench (doctor_devices): the full one takes hours on 2 cores.
    parser.add_argument('--devices', type=int, metavar='N',
                        help='devices per kind of a drawn-device bench that takes it '
                             '(doctor_devices; default its own)')
    parser.add_argument('--kinds', metavar='KIND[:COUNT][,...]',
                        help="only these kinds of device ('none' the null devices; "
                             'doctor_devices.KINDS), COUNT devices each (default --devices)')
    parser.add_argument('--workers', type=int, metavar='N',
                        help='worker processes of a bench that takes it (doctor_devices)')
    parser.add_argument('--output', metavar='FILE',
                        help="write the run's record (as --json prints it) to FILE, e.g. "
                             'bench/results/<version>/<benches>.json')
    parser.add_argument('--render', nargs='+', metavar='FILE',
                        help='run nothing: render these records as Markdown, side by side')
    parser.add_argument('--plot', metavar='PNG',
                        help='with --render: also plot each result across the records')


def run(args):
    if args.render:
        return render(args.render, args.plot)
    if args.plot:
        raise BellowsError('--plot draws records: give them with --render FILE...')
    if args.output:
        check_output(args.output)
    started, clock = datetime.datetime.now(datetime.timezone.utc), time.perf_counter()
    commit = bench_records.commit()
    results = []
    options = {name: getattr(args, name, None) for name in ('devices', 'kinds', 'workers')}
    given = {key: value for key, value in options.items() if value is not None}
    # Every bench's options are checked before the first runs: a seeded run of several benches
    # must not stop at the third, an hour in, on an option it does not take.
    modules = {name: importlib.import_module(f'bellows_ros.bench.{name}')
               for name in chosen_modules(args.only)}
    for name, module in modules.items():
        refused = sorted(set(given) - set(inspect.signature(module.run).parameters))
        if refused:
            raise BellowsError(f"bench {name} takes no --{', --'.join(refused)}")
    for name, module in modules.items():
        print(f'bench: {name} ...', file=sys.stderr)
        results.extend(module.run(quick=args.quick, **given))
    record = bench_records.record(results, args.argv, started, time.perf_counter() - clock,
                                  commit)
    text = json.dumps(record, indent=2) + '\n'
    if args.output:
        write_text(args.output, text)
    print(text if args.json else format_table(results), end='' if args.json else '\n')
    return 0


def render(paths, plot=None):
    """Print the records in `paths` as Markdown; with `plot`, write the figure there too."""
    if plot:
        check_output(plot, paths, '--plot')
    records = [(path, bench_records.read(path)) for path in paths]
    print(bench_records.render(records), end='')
    if plot:
        bench_records.plot(records, plot)
    return 0


def chosen_modules(only):
    """
    Return the benchmark modules `--only` selects, in name order: every one if `only` is empty.

    `only`: comma-separated module names or shell patterns (`graph*`). A name is that module
    alone, so `doctor` is not also the hours-long `doctor_devices`. A name or pattern that selects
    no module is an error (a typo would otherwise run nothing of it).
    """
    names = sorted(info.name for info in pkgutil.iter_modules(bench_package.__path__))
    wanted = [text.strip() for text in only.split(',')] if only else []
    for text in wanted:
        if not any(fnmatch.fnmatchcase(name, text) for name in names):
            raise BellowsError(f'--only {only!r}: {text!r} is no benchmark module '
                               f"(modules: {', '.join(names)})")
    return [name for name in names
            if not wanted or any(fnmatch.fnmatchcase(name, text) for text in wanted)]


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
