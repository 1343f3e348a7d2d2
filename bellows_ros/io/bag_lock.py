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
A recording has one writer: the lock protocol of a rosbag2 directory.

The writer (`bellows record`, `bellows reindex`) holds an exclusive `fcntl.flock` on
`<bag>/.bellows-writer.lock` for as long as it writes (`hold`). Readers (`export`, `identify`,
`diagnose`, `stiffness` through `bag.read_bag_table`) and a second writer ask without waiting
(`check_not_written`): a bag being written is refused in one line naming it, since a reader would
see a part of it (and `reindex` would cut it short and write a metadata.yaml that claims less or
more than the bag ends up holding). The lock is the kernel's: it goes when the writer's process
ends, however it ends (SIGKILL too), so a killed recorder never leaves a bag locked.

The lock file is created inside the bag directory, so the writer takes it just after the storage
library created the directory (rosbag2 writers refuse an existing one); `hold` removes it on
release. A directory without the file, or with a file nobody holds, is not being written by a
writer that follows this protocol. A writer that does not (`ros2 bag record`, a recorder of an
older version) is not seen here; `bellows reindex` also refuses a storage file that is still
growing (`bag_repair`).
"""
import contextlib
import errno
import fcntl
import os
from pathlib import Path

from bellows_ros.errors import BellowsError

LOCK_NAME = '.bellows-writer.lock'
# What the lock file may hold: the writer's pid and what it does, one short line.
_NOTE_BYTES = 200


class BagBeingWritten(BellowsError):
    """The bag is being written by another process (its lock is held)."""


def _note(fd):
    """Return the writer's own line in the lock file ('pid 123, bellows record'), or ''."""
    try:
        text = os.pread(fd, _NOTE_BYTES, 0).decode(errors='replace')
    except OSError:
        return ''
    line = text.splitlines()[0] if text.strip() else ''
    return ''.join(c for c in line if c.isprintable())


def _busy(bag, fd, what):
    note = _note(fd)
    by = f' (by {note})' if note else ''
    return BagBeingWritten(f'{bag}: the recording is being written{by}; {what} waits for the '
                           'recorder to end (Ctrl-C or its --duration), or read a copy')


@contextlib.contextmanager
def hold(bag_dir, who='bellows record'):
    """
    Hold the writer's lock of the existing bag directory `bag_dir` for the block.

    `who` is written into the lock file for the refusal a reader prints. Raises
    `BagBeingWritten` when another process holds it; the lock file is removed on release.
    """
    bag = Path(bag_dir)
    path = bag / LOCK_NAME
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o644)
    except OSError as exc:
        raise BellowsError(f'{bag}: cannot create its writer lock {LOCK_NAME} '
                           f'({exc.strerror})') from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise _busy(bag, fd, who) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f'pid {os.getpid()}, {who}\n'.encode(), 0)
        try:
            yield path
        finally:
            with contextlib.suppress(OSError):  # still held: no reader can take it for ours
                os.unlink(path)
    finally:
        os.close(fd)


def check_not_written(bag_dir, what='reading'):
    """
    Raise `BagBeingWritten` (one line naming the bag) if a writer holds `bag_dir`'s lock.

    Non-blocking: a bag nobody writes is answered at once. `what` names the refused action.
    """
    bag = Path(bag_dir)
    try:
        fd = os.open(bag / LOCK_NAME, os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC | os.O_NONBLOCK)
    except OSError as exc:
        if exc.errno in (errno.ENOENT, errno.ENOTDIR):
            return  # no writer follows the protocol here
        if exc.errno == errno.ELOOP:
            raise BellowsError(f'{bag}: {LOCK_NAME} is a link, not a bellows writer lock; '
                               'remove it') from None
        return  # unreadable (permissions): no lock we can judge; the reader reports the rest
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            raise _busy(bag, fd, what) from None
    finally:
        os.close(fd)
