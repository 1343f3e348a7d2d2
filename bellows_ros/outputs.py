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
Every file the package writes, written so that nothing is lost.

- An output is written to a temporary file in its own directory (so on the same file system),
  flushed to disk, then renamed over the old one: a reader, a crash or a signal sees the whole
  old file or the whole new one, never a shorter one (`atomic_file`, `write_text`).
- A report directory is built beside the old one and swapped in whole (`report_directory`): never
  a new report.json beside old plots. An existing directory is replaced only when it is a report
  this package wrote (it holds report.json and nothing a report does not hold); anything else is
  refused, because the package never deletes what it did not create.
- Before any work (a fit, a diagnosis), `check_output` refuses an output that is one of the
  inputs (the same path or the same file through a link), and one that cannot be written (no such
  directory, a read-only file system, a directory where a file should go), so a mistake costs a
  second, not minutes of fitting.
Temporary files are named `.<name>.<random>.tmp` and removed when the write fails; nothing else is
ever removed.
"""
import contextlib
import ctypes
import ctypes.util
import os
from pathlib import Path
import shutil
import tempfile

from bellows_ros.errors import BellowsError


def _same_file(a, b):
    try:
        return os.path.samefile(a, b)
    except OSError:  # one does not exist: the same only by name
        return os.path.abspath(a) == os.path.abspath(b)


def _writable_directory(directory, what):
    if not directory.is_dir():
        raise BellowsError(f'{what}: no such directory: {directory}')
    probe = None
    try:  # the one test that holds for root, ACLs and read-only mounts alike: try it
        probe = tempfile.NamedTemporaryFile(dir=directory, prefix='.bellows-probe-', delete=True)
    except OSError as exc:
        raise BellowsError(f'{what}: cannot write in {directory} ({exc.strerror})') from None
    finally:
        if probe is not None:
            probe.close()


def check_output(path, inputs=(), what='--output'):
    """
    Check, before any work, that `path` can be written and is none of `inputs`; return a Path.

    `inputs` are the paths the command reads (None entries are skipped). BellowsError otherwise.
    """
    path = Path(path)
    for source in inputs:
        if source is not None and _same_file(path, source):
            raise BellowsError(f'{what} {path}: that is an input of this command ({source}); '
                               'write the result to another file')
    if path.is_dir():
        raise BellowsError(f'{what} {path}: is a directory; give a file name')
    _writable_directory(path.parent if str(path.parent) else Path('.'), f'{what} {path}')
    return path


@contextlib.contextmanager
def atomic_file(path, mode='w', check=None, **open_args):
    """
    Open a temporary file beside `path` for writing; rename it over `path` on success.

    `check(temporary_path)`, when given, reads the finished file before it replaces anything; an
    exception from it leaves `path` as it was (a writer never leaves a file its reader refuses).
    """
    path = Path(path)
    fd, temporary = tempfile.mkstemp(dir=path.parent, prefix=f'.{path.name}.', suffix='.tmp')
    try:
        with os.fdopen(fd, mode, **open_args) as stream:
            yield stream
            stream.flush()
            os.fsync(stream.fileno())
        if check is not None:
            check(temporary)
        if path.exists():  # keep the old file's permissions
            os.chmod(temporary, path.stat().st_mode & 0o7777)
        else:
            os.chmod(temporary, 0o666 & ~_umask())
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temporary)  # our own temporary file, never the output
        raise


def write_text(path, text):
    """Write `text` to `path` atomically."""
    with atomic_file(path) as stream:
        stream.write(text)


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


# What a report directory may hold: the files `bellows diagnose` writes.
REPORT_FILES = ('report.json', 'details.json', 'report.md', 'extended.yaml')


def is_report(directory):
    """Tell whether `directory` is a report this package wrote (report.json, report files only)."""
    names = [p.name for p in Path(directory).iterdir()]
    return 'report.json' in names and all(
        name in REPORT_FILES or name.endswith('.png') for name in names)


def check_report_directory(path, inputs=(), what='--report'):
    """Check, before any work, that the report directory `path` can be written or replaced."""
    path = Path(path)
    for source in inputs:
        if source is not None and (_same_file(path, source)
                                   or Path(os.path.abspath(source)).is_relative_to(
                                       os.path.abspath(path))):
            raise BellowsError(f'{what} {path}: holds an input of this command ({source})')
    if path.exists():
        if not path.is_dir():
            raise BellowsError(f'{what} {path}: is a file, not a directory')
        if any(path.iterdir()) and not is_report(path):
            raise BellowsError(f'{what} {path}: holds files that are not a bellows report; '
                               'give a new or empty directory (nothing is deleted that the '
                               'package did not write)')
    _writable_directory(path.parent if str(path.parent) else Path('.'), f'{what} {path}')
    return path


@contextlib.contextmanager
def report_directory(path):
    """
    Yield a new directory beside `path` to write the report into; swap it in whole on success.

    The old report (checked by `check_report_directory`) goes only once the new one is complete:
    the two are exchanged in one step where the kernel can (renameat2 RENAME_EXCHANGE), else the
    old one is renamed aside first. On failure the new directory is removed and the old one stays.
    """
    path = Path(path)
    check_report_directory(path)
    building = Path(tempfile.mkdtemp(dir=path.parent, prefix=f'.{path.name}.', suffix='.new'))
    try:
        yield building
        os.chmod(building, 0o777 & ~_umask())
        if not path.exists():
            os.rename(building, path)
            return
        if not _exchange(building, path):
            aside = Path(tempfile.mkdtemp(dir=path.parent, prefix=f'.{path.name}.', suffix='.old'))
            os.rename(path, aside / 'report')
            os.rename(building, path)
            building = aside
        # `building` now holds the old report, which this package wrote: only that goes.
        shutil.rmtree(building)
    except BaseException:
        shutil.rmtree(building, ignore_errors=True)  # our own unfinished directory
        raise


_RENAME_EXCHANGE = 2


def _exchange(a, b):
    """Swap two paths atomically (Linux renameat2); False where the system cannot."""
    libc = ctypes.CDLL(ctypes.util.find_library('c') or 'libc.so.6', use_errno=True)
    renameat2 = getattr(libc, 'renameat2', None)
    if renameat2 is None:
        return False
    at_fdcwd = -100
    result = renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), _RENAME_EXCHANGE)
    return result == 0
