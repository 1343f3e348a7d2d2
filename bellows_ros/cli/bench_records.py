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
Bench results as data: the record `bellows bench --json` prints, and what renders records.

A record is one run of `bellows bench`: which package and commit, when, on what host, with what
command, and the results (`bench.Result` as dicts). The records of a release are kept under
bench/results/<version>/ and rendered by `bellows bench --render FILE...` (tables, and with
`--plot` a figure of each result across the records). Nothing here runs a benchmark.
"""
import datetime
import json
import os
from pathlib import Path
import platform
import subprocess

from bellows_ros.errors import BellowsError
from bellows_ros.io.outputs import atomic_file

FORMAT = 'bellows_ros bench record 1'
KEYS = ('format', 'bellows_ros', 'commit', 'started', 'seconds', 'command', 'host', 'results')
RESULT_KEYS = ('name', 'value', 'unit')


def record(results, command, started, seconds, commit):
    """
    Return the record of one run: `results` (Result), `command` (argv), `started` (datetime).

    `commit`: `commit()` when the run started (a commit made during a long run is not what ran).
    """
    return {'format': FORMAT, 'bellows_ros': _version(), 'commit': commit,
            'started': started.astimezone(datetime.timezone.utc).isoformat(timespec='seconds'),
            'seconds': round(seconds, 3), 'command': ['bellows', *command],
            'host': {'machine': platform.machine(), 'system': platform.platform(),
                     'python': platform.python_version(), 'cpus': os.cpu_count()},
            'results': [r.as_dict() for r in results]}


def _version():
    from importlib import metadata
    try:
        return metadata.version('bellows_ros')
    except metadata.PackageNotFoundError:
        return None


def commit():
    """Return the git commit the package runs from ('+' if its code has changes), or None."""
    here = Path(__file__).resolve().parents[1]   # bellows_ros: the code that runs
    try:
        head = subprocess.run(['git', '-C', str(here), 'rev-parse', 'HEAD'], capture_output=True,
                              text=True, timeout=5, check=True).stdout.strip()
        changed = subprocess.run(['git', '-C', str(here), 'status', '--porcelain', '--', '.'],
                                 capture_output=True, text=True, timeout=5, check=True).stdout
    except (OSError, subprocess.SubprocessError):
        return None   # an installed package, or no git: the version says what ran
    return head + ('+' if changed.strip() else '')


def read(path):
    """Return the record in file `path`; BellowsError naming the file if it is not one."""
    try:
        data = json.loads(Path(path).read_text())
    except OSError as exc:
        raise BellowsError(f'{path}: cannot read: {exc.strerror}') from None
    except json.JSONDecodeError as exc:
        raise BellowsError(f'{path}: line {exc.lineno} column {exc.colno}: not JSON '
                           f'({exc.msg})') from None
    except UnicodeDecodeError:
        raise BellowsError(f'{path}: not text (a bench record is JSON)') from None
    if not isinstance(data, dict) or data.get('format') != FORMAT:
        raise BellowsError(f"{path}: not a bench record ('format' is not {FORMAT!r}; write one "
                           'with bellows bench --output FILE)')
    missing = [key for key in KEYS if key not in data]
    if missing:
        raise BellowsError(f"{path}: bench record without '{missing[0]}'")
    for index, result in enumerate(data['results']):
        if not isinstance(result, dict) or any(key not in result for key in RESULT_KEYS):
            raise BellowsError(f'{path}: result {index + 1} is not a result (needs '
                               f"{', '.join(RESULT_KEYS)})")
    return data


def _by_name(records):
    """Return each record's results by name, and every name in the order first met."""
    by_name = [{r['name']: r for r in data['results']} for _, data in records]
    return by_name, list(dict.fromkeys(name for results in by_name for name in results))


def _label(data):
    return f"{data['bellows_ros'] or '?'} {data['started'][:10]}"


def _show(value, unit):
    if value is None:
        return ''
    if unit == 's':
        return f'{value * 1e6:.2f} µs' if value < 1e-2 else f'{value:.3f} s'
    return f'{value:.4g} {unit}'.rstrip()


def render(records):
    """Return Markdown of `records` [(path, record)]: each run, then the results side by side."""
    lines = ['# Bench records', '']
    for path, data in records:
        host = data['host']
        lines += [f"- `{path}`: bellows_ros {data['bellows_ros']}, commit "
                  f"{(data['commit'] or 'unknown')[:12]}, {data['started']}, "
                  f"{data['seconds']:.0f} s, {host.get('cpus')} CPUs, {host.get('machine')}: "
                  f"`{' '.join(data['command'])}`"]
    by_name, names = _by_name(records)
    lines += ['', '| result | ' + ' | '.join(_label(d) for _, d in records) + ' | target |',
              '|---|' + '---|' * (len(records) + 1)]
    for name in names:
        cells, target = [], ''
        for results in by_name:
            r = results.get(name)
            if r is None:
                cells.append('')
                continue
            ratio = f" ({r['ratio']:.2f}× {r['reference']})" if r.get('ratio') is not None else ''
            cells.append(_show(r['value'], r['unit']) + ratio)
            target = _show(r.get('target'), r['unit']) or target
        lines.append(f'| {name} | ' + ' | '.join(cells) + f' | {target} |')
    return '\n'.join(lines) + '\n'


def plot(records, path):
    """Write a PNG: each result's value over its value in the first record that has it."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    by_name, names = _by_name(records)
    names = [n for n in names if sum(n in results for results in by_name) > 1]
    first = {n: next(results[n]['value'] for results in by_name if n in results) for n in names}
    figure, axes = plt.subplots(figsize=(8.0, 0.3 * len(names) + 1.5))
    for (_, data), results in zip(records, by_name):
        xs, ys = [], []
        for row, name in enumerate(names):
            if name in results and first[name]:
                xs.append(results[name]['value'] / first[name])
                ys.append(row)
        axes.plot(xs, ys, 'o', label=_label(data))
    axes.axvline(1.0, color='0.6', linewidth=0.8)
    axes.set_yticks(range(len(names)), names, fontsize=7)
    axes.set_xscale('log')
    axes.set_xlabel('value over the first record that has it')
    axes.invert_yaxis()
    axes.legend(fontsize=7)
    figure.tight_layout()
    with atomic_file(path, 'wb') as stream:
        figure.savefig(stream, format='png', dpi=110)
    plt.close(figure)
