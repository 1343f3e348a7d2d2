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
- An output is a regular file or a new path. A rename replaces whatever has the name: a device
  node, a FIFO, a socket, `/dev/stdout` would become a regular file (as root, for the whole
  machine), so anything else that exists there is refused (`check_output`, and again just before
  the rename). A link to a regular file is followed: the file it names is replaced, the link
  stays.
- A report directory is built beside the old one and swapped in whole (`report_directory`): never
  a new report.json beside old plots. An existing directory is replaced only when every entry in
  it is one the package wrote, as the report's manifest (`MANIFEST`: each file's name and
  SHA-256) records; a file a user put there, or a report file a user edited, makes it refused,
  because the package never deletes what it did not create. A report directory given as a link
  is resolved (the link stays, the directory it names is replaced).
- Before any work (a fit, a diagnosis), `check_output` refuses an output that is one of the
  inputs (the same path or the same file through a link), and one that cannot be written (no such
  directory, a read-only file system, a directory where a file should go), so a mistake costs a
  second, not minutes of fitting.
Temporary files are named `.<name>.<random>.tmp` and removed on every way out the process has: an
error, Ctrl-C, and SIGTERM or SIGHUP (`signals_as_exceptions`, which the `bellows` command turns
on, makes those run the clean-up; one that comes between the file's creation and the start of
its clean-up is held until then, `_SignalsHeld`). Only SIGKILL leaves one behind: while a
temporary file (or a report directory being built) is written its writer holds a lock on it, and
the next write of the same output removes the ones no process holds (`_remove_orphans`,
`_remove_orphan_directories`).
Nothing else is ever removed.
"""
import contextlib
import ctypes
import ctypes.util
import fcntl
import hashlib
import json
import os
from pathlib import Path
import shutil
import signal
import stat
import tempfile
import threading

from bellows_ros.errors import BellowsError


def _same_file(a, b):
    try:
        return os.path.samefile(a, b)
    except OSError:  # one does not exist: the same only by name
        return os.path.abspath(a) == os.path.abspath(b)


def _writable_directory(directory, what):
    if not directory.is_dir():
        raise BellowsError(f'{what}: no such directory: {directory}')
    try:  # the one test that holds for root, ACLs and read-only mounts alike: try it
        _probe(directory)
    except OSError as exc:
        raise BellowsError(f'{what}: cannot write in {directory} ({exc.strerror})') from None


def _probe(directory):
    """
    Create a file in `directory` and let it go; OSError if it cannot be written in.

    The file has no name (O_TMPFILE), so a signal in between leaves nothing behind: a named probe
    stayed in the user's directory once when SIGHUP came between its creation and its removal.
    Where that fails (a directory not writable, a file system or kernel without unnamed files),
    a named probe, removed at once, decides and its error is the one reported.
    """
    unnamed = getattr(os, 'O_TMPFILE', None)
    if unnamed is not None:
        try:
            os.close(os.open(directory, unnamed | os.O_WRONLY, 0o600))
            return
        except OSError:
            pass
    with tempfile.NamedTemporaryFile(dir=directory, prefix='.bellows-probe-'):
        pass


_KINDS = ((stat.S_ISCHR, 'a character device'), (stat.S_ISBLK, 'a block device'),
          (stat.S_ISFIFO, 'a FIFO (named pipe)'), (stat.S_ISSOCK, 'a socket'),
          (stat.S_ISDIR, 'a directory'))


def _kind(mode):
    return next((name for test, name in _KINDS if test(mode)), 'not a regular file')


def _target(path, what):
    """
    Return the path an output named `path` is written to; BellowsError if no regular file.

    A new path is itself; a regular file is itself; a link to a regular file (or to a new path in
    an existing directory) is the path it names, so the link stays a link. Anything else would be
    replaced by the rename: refused.
    """
    text = os.fspath(path)
    path = Path(path)
    if text.endswith(os.sep) or text.endswith(os.sep + '.') or path.name in ('', '.', '..'):
        raise BellowsError(f'{what} {text}: names a directory; give a file name')
    if not os.path.lexists(path):
        return path
    resolved = Path(os.path.realpath(path))
    try:
        mode = os.stat(resolved).st_mode
    except FileNotFoundError:
        if not resolved.parent.is_dir():
            raise BellowsError(f'{what} {text}: a link to {resolved}, in no existing '
                               'directory') from None
        return resolved
    except OSError as exc:
        raise BellowsError(f'{what} {text}: cannot look at it ({exc.strerror})') from None
    if stat.S_ISDIR(mode):
        raise BellowsError(f'{what} {text}: is a directory; give a file name')
    if not stat.S_ISREG(mode):
        through = f' (through a link to {resolved})' if resolved != path.absolute() else ''
        raise BellowsError(f'{what} {text}: is {_kind(mode)}{through}, not a regular file; the '
                           'package writes an output as a new file and would replace it: give '
                           'a file name')
    return resolved


def check_output(path, inputs=(), what='--output'):
    """
    Check, before any work, that `path` can be written and is none of `inputs`; return a Path.

    `inputs` are the paths the command reads (None entries are skipped). An existing output must
    be a regular file (or a link to one). BellowsError otherwise.
    """
    target = _target(path, what)
    path = Path(path)
    for source in inputs:
        if source is not None and _same_file(path, source):
            raise BellowsError(f'{what} {path}: that is an input of this command ({source}); '
                               'write the result to another file')
    _writable_directory(target.parent if str(target.parent) else Path('.'), f'{what} {path}')
    return path


def _locked(path):
    """Tell whether a process holds the writer's lock on the temporary file `path`."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError:
        return True  # gone, or not ours to judge: leave it
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            return True
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return False
    except OSError:
        return True
    finally:
        os.close(fd)


def _remove_orphans(path):
    """Remove temporary files of `path` that no writer holds (left by a SIGKILL)."""
    prefix = f'.{path.name}.'
    try:
        names = [entry.name for entry in os.scandir(path.parent)
                 if entry.name.startswith(prefix) and entry.name.endswith('.tmp')
                 and entry.is_file(follow_symlinks=False)]
    except OSError:
        return
    for name in names:
        orphan = path.parent / name
        if not _locked(orphan):
            with contextlib.suppress(OSError):
                os.unlink(orphan)


@contextlib.contextmanager
def atomic_file(path, mode='w', check=None, **open_args):
    """
    Open a temporary file beside `path` for writing; rename it over `path` on success.

    `check(temporary_path)`, when given, reads the finished file before it replaces anything; an
    exception from it leaves `path` as it was (a writer never leaves a file its reader refuses).
    An existing `path` that is not a regular file (a device, a FIFO, a socket) is refused before
    and again just before the rename; a link to a regular file has its file replaced.
    """
    path = _target(path, 'output')
    _remove_orphans(path)
    with _SignalsHeld() as held:
        fd, temporary = tempfile.mkstemp(dir=path.parent, prefix=f'.{path.name}.', suffix='.tmp')
        try:
            with os.fdopen(fd, mode, **open_args) as stream:
                held.release()  # a signal that came since the file was made raises here
                fcntl.flock(fd, fcntl.LOCK_EX)  # ours while we write: never taken for an orphan
                yield stream
                stream.flush()
                os.fsync(stream.fileno())
                if check is not None:
                    check(temporary)
                _target(path, 'output')  # it may have changed while we wrote
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


class Signalled(BaseException):
    """SIGTERM or SIGHUP arrived (`signals_as_exceptions`): unwind, cleaning up, then exit."""

    def __init__(self, signum):
        self.signum = signum
        super().__init__(signal.Signals(signum).name)


def _raise_signalled(signum, frame):
    if _SignalsHeld.depth:
        _SignalsHeld.pending = signum
        return
    raise Signalled(signum)


class _SignalsHeld:
    """
    Hold a `Signalled` from a temporary file's creation until its clean-up is armed.

    `with _SignalsHeld() as held:` create the file, enter the `try` that removes it, and there
    call `held.release()`: a SIGTERM or SIGHUP that came in between raises then, inside the
    `try`, instead of between the two, where nothing would remove the file. Leaving the block
    releases too. Signal handlers run in the main thread only, so only there is anything held.
    """

    depth = 0       # holds open in the main thread
    pending = None  # the signal that came while held

    def __enter__(self):
        self.held = threading.current_thread() is threading.main_thread()
        _SignalsHeld.depth += self.held
        return self

    def release(self):
        if not self.held:
            return
        self.held = False
        _SignalsHeld.depth -= 1
        if not _SignalsHeld.depth and _SignalsHeld.pending is not None:
            signum, _SignalsHeld.pending = _SignalsHeld.pending, None
            raise Signalled(signum)

    def __exit__(self, *exc_info):
        self.release()


@contextlib.contextmanager
def signals_as_exceptions(signums=(signal.SIGTERM, signal.SIGHUP)):
    """
    While the block runs, SIGTERM and SIGHUP raise `Signalled` in the main thread.

    Their default action ends the process at once, so no `finally` runs and a temporary file or
    an unfinished report directory stays behind; as an exception they unwind like Ctrl-C. Outside
    the main thread (where Python cannot set handlers) it does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {}
    try:
        for signum in signums:
            if signal.getsignal(signum) in (signal.SIG_DFL, None):
                previous[signum] = signal.signal(signum, _raise_signalled)
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


# The report's own record of what it wrote: each file's name and SHA-256 (`report_directory`).
MANIFEST = '.bellows-report.json'
# A manifest lists a report's handful of files; a larger one is not ours.
MANIFEST_BYTES = 1 << 20


def _sha256(path):
    digest = hashlib.sha256()
    with open(path, 'rb') as stream:
        for block in iter(lambda: stream.read(1 << 20), b''):
            digest.update(block)
    return digest.hexdigest()


def write_manifest(directory):
    """Record every file of the report built in `directory` (called last, before the swap)."""
    directory = Path(directory)
    names = sorted(entry.name for entry in os.scandir(directory) if entry.name != MANIFEST)
    files = {name: _sha256(directory / name) for name in names}
    (directory / MANIFEST).write_text(json.dumps({'bellows_report': 1, 'files': files},
                                                 indent=1) + '\n')


def _foreign(directory):
    """Return the first entry of `directory` the package did not write as it is, or None."""
    directory = Path(directory)
    names = sorted(entry.name for entry in os.scandir(directory))
    manifest = directory / MANIFEST
    written = {}
    try:
        if manifest.is_symlink() or manifest.stat().st_size > MANIFEST_BYTES:
            return MANIFEST
        document = json.loads(manifest.read_text())
        written = document['files'] if isinstance(document, dict) else {}
    except FileNotFoundError:
        return next((name for name in names), None)
    except (OSError, ValueError, KeyError, TypeError):
        return MANIFEST
    if not isinstance(written, dict):
        return MANIFEST
    for name in names:
        if name == MANIFEST:
            continue
        entry = directory / name
        try:
            ours = (name in written and not entry.is_symlink() and entry.is_file()
                    and _sha256(entry) == written[name])
        except OSError:
            ours = False
        if not ours:
            return name
    return None


def is_report(directory):
    """Tell whether every entry of `directory` is a report file the package wrote, unchanged."""
    return _foreign(directory) is None


def _report_path(path, what):
    """`path`, or the directory it links to (resolved before any work); BellowsError if neither."""
    path = Path(path)
    if os.path.islink(path):
        resolved = Path(os.path.realpath(path))
        if os.path.lexists(resolved) and not resolved.is_dir():
            raise BellowsError(f'{what} {path}: a link to {resolved}, which is not a directory')
        if not resolved.parent.is_dir():
            raise BellowsError(f'{what} {path}: a link to {resolved}, in no existing directory')
        return resolved
    return path


def check_report_directory(path, inputs=(), what='--report'):
    """
    Check, before any work, that the report directory `path` can be written or replaced.

    Returns the directory the report goes to: `path`, or where it links to.
    """
    given = Path(path)
    path = _report_path(given, what)
    for source in inputs:
        if source is not None and (_same_file(path, source)
                                   or Path(os.path.realpath(source)).is_relative_to(
                                       os.path.realpath(path))):
            raise BellowsError(f'{what} {given}: holds an input of this command ({source})')
    if os.path.lexists(path):
        if not path.is_dir():
            raise BellowsError(f'{what} {given}: is a file, not a directory')
        foreign = _foreign(path)
        if foreign is not None:
            why = ('it has no bellows report manifest' if foreign != MANIFEST
                   and not (path / MANIFEST).exists() else
                   'its manifest is damaged' if foreign == MANIFEST else
                   'the report did not write it, or it changed since')
            raise BellowsError(f'{what} {given}: holds files that are not a bellows report '
                               f'({foreign!r}: {why}); give a new or empty directory (nothing '
                               'is deleted that the package did not write)')
    _writable_directory(path.parent if str(path.parent) else Path('.'), f'{what} {given}')
    return path


@contextlib.contextmanager
def report_directory(path):
    """
    Yield a new directory beside `path` to write the report into; swap it in whole on success.

    The old report (checked by `check_report_directory`) goes only once the new one is complete
    and only if it is still all the package's: the two are exchanged in one step where the kernel
    can (renameat2 RENAME_EXCHANGE), else the old one is renamed aside first. The manifest is
    written last. On failure the new directory is removed and the old one stays.
    """
    path = check_report_directory(path)
    _remove_orphan_directories(path)
    with _SignalsHeld() as held:
        building = Path(tempfile.mkdtemp(dir=path.parent, prefix=f'.{path.name}.',
                                         suffix='.new'))
        holder = None
        try:
            holder = _hold_directory(building)
            held.release()  # a signal that came since the directory was made raises here
            yield building
            write_manifest(building)
            os.chmod(building, 0o777 & ~_umask())
            if not os.path.lexists(path):
                os.rename(building, path)
                return
            check_report_directory(path)  # a file put there while the report was built stays
            if not _exchange(building, path):
                with _SignalsHeld():  # until `building` names the directory made aside
                    aside = Path(tempfile.mkdtemp(dir=path.parent, prefix=f'.{path.name}.',
                                                  suffix='.old'))
                    os.close(holder)
                    holder = _hold_directory(aside)
                    os.rename(path, aside / 'report')
                    os.rename(building, path)
                    building = aside
            # `building` now holds the old report, which this package wrote: only that goes.
            shutil.rmtree(building)
        except BaseException:
            shutil.rmtree(building, ignore_errors=True)  # our own unfinished directory
            raise
        finally:
            if holder is not None:
                os.close(holder)


def _hold_directory(directory):
    """Lock a directory this process builds (flock), so no other run takes it for an orphan."""
    fd = os.open(directory, os.O_RDONLY | os.O_DIRECTORY)
    fcntl.flock(fd, fcntl.LOCK_EX)
    return fd


def _remove_orphan_directories(path):
    """Remove the unfinished or set-aside report directories of `path` a SIGKILL left behind."""
    prefix = f'.{path.name}.'
    try:
        names = [entry.name for entry in os.scandir(path.parent)
                 if entry.name.startswith(prefix) and entry.name[-4:] in ('.new', '.old')
                 and entry.is_dir(follow_symlinks=False)]
    except OSError:
        return
    for name in names:
        orphan = path.parent / name
        try:
            fd = os.open(orphan, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            continue  # a run building it now
        else:
            shutil.rmtree(orphan, ignore_errors=True)
        finally:
            os.close(fd)


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
