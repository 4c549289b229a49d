"""The batch lock: one ``autobones batch`` at a time writes into an output folder (issue #33).

Two batches into one folder at once both planned the same files as to do, wrote the same
``.NAME.glb.partial`` folders and temporaries under each other, and each wrote its own report
over the other's: 2 of 8 rigs missing, both exit 1. The second batch now refuses at once (one
line, exit 2, naming the pid that holds the folder) rather than waiting: a wait would only end
with every file skipped as up to date, and a script that started two runs into one folder is
more likely a mistake worth a message than a queue.

The lock is ``fcntl.flock`` on ``OUT_DIR/.batch.lock``. The kernel drops a flock when the last
descriptor of its open file goes, so a batch killed with ``kill -9`` (or by the OOM killer) never
leaves a stale lock behind: the file may stay, with its dead pid in it, but the next run takes it.
The workers never hold it (it is opened ``O_CLOEXEC``; spawned workers do not inherit it).
"""
from __future__ import annotations

import errno
import os
from contextlib import contextmanager

from ..errors import AutobonesError

LOCK_NAME = ".batch.lock"


@contextmanager
def batch_lock(out):
    """Hold the batch lock of the output folder ``out`` (which exists) for the ``with`` block.

    AutobonesError when another process holds it (naming its pid) or when the lock file
    cannot be made (a link or a folder at its name: it is opened ``O_NOFOLLOW``, so a link
    placed there never makes us create or truncate a file elsewhere). The file is removed
    on the way out, so a finished run leaves nothing of it.
    """
    import fcntl

    path = os.path.join(os.fspath(out), LOCK_NAME)
    while True:
        fd = _open(path)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            holder = _holder(fd)
            os.close(fd)
            if exc.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise AutobonesError(f"{out}: cannot lock the output folder ({exc.strerror or exc})") from None
            raise AutobonesError(f"{out}: another autobones batch (pid {holder}) is writing into this folder; "
                                 "wait for it to end or choose another output folder") from None
        # the holder before us may have removed the file between our open and our lock: then we
        # hold a lock on a name no one sees, and a third run could lock a new file; take the name again
        try:
            same = os.path.samestat(os.fstat(fd), os.lstat(path))
        except OSError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        yield path
    finally:
        try:
            os.unlink(path)  # while still locked: a run that opened it meanwhile sees the name gone and retries
        except OSError:
            pass
        os.close(fd)


def _open(path):
    flags = os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        return os.open(path, flags, 0o644)
    except OSError as exc:
        raise AutobonesError(f"{path}: cannot make the batch lock file ({exc.strerror or exc}); "
                             "remove what stands at that name") from None


def _holder(fd, tries=20):
    """The pid written in the lock file, or "unknown". The holder writes it just after locking, so
    an empty file is read again a few times (0.2 s at most) before giving up."""
    import time

    for _ in range(tries):
        try:
            text = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
        except OSError:
            return "unknown"
        if text.isdigit():
            return text
        time.sleep(0.01)
    return "unknown"
