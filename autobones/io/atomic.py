"""Write a file so that a reader sees the old file or the whole new one, never a part."""
from __future__ import annotations

import os
import tempfile

from ..errors import AutobonesError


# A replaced file is kept under its temporary's name plus this until the group is renamed
# (batch's clean_stale_temps removes any that a kill left behind).
BACKUP_SUFFIX = ".autobones-old"


def _default_mode():
    # a new file's usual mode under the process umask (mkstemp makes its files owner-only)
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def temp_beside(path, suffix=".tmp"):
    """A new empty temporary file in ``path``'s folder, to be renamed onto ``path``.

    Returns ``(fd, tmp)`` like :func:`tempfile.mkstemp`, but the file has the mode a file
    created normally would have (readable by group and others under the usual umask), so
    the renamed output is not owner-only.
    """
    folder = os.path.dirname(os.path.abspath(os.fspath(path)))
    try:  # a folder that takes no new files (/proc, read-only, full): one line naming the output
        fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(os.fspath(path)) + "-", suffix=suffix, dir=folder)
    except OSError as exc:
        raise AutobonesError(f"{os.fspath(path)}: cannot write in {folder} ({exc.strerror or exc})") from None
    os.fchmod(fd, _default_mode())
    return fd, tmp


def output_folder(path):
    """The folder ``path`` will be written in; AutobonesError when it does not exist."""
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise AutobonesError(f"{path}: the folder {folder} does not exist; create it first")
    return folder


def check_destination(path, what="file"):
    """AutobonesError naming ``path`` when a file cannot be renamed onto it: a folder (or
    anything but a regular file) stands there, or its folder is missing. Checked for every
    output of a group before any is written, so the message names the file at fault."""
    path = os.fspath(path)
    output_folder(path)
    if os.path.isdir(path):
        raise AutobonesError(f"{path}: a folder of that name is in the way of {what}; move it or choose another output")
    if os.path.lexists(path) and not os.path.isfile(path):
        raise AutobonesError(f"{path}: exists and is not a regular file; {what} cannot replace it")
    return path


def replace_all(staged, what="outputs"):
    """Rename each complete temporary file onto its target, in the given order, all or nothing.

    Parameters
    ----------
    staged : sequence of (tmp, target)
        Temporary files (beside their targets, :func:`temp_beside`) and where they go.
    what : str
        What the group is, for the error message.

    Every target is checked first (:func:`check_destination`). A target that exists is kept
    under a hard link while the group is renamed, so when a rename fails the new files already
    renamed are removed and the old ones put back: a reader never finds a glb beside sidecars of
    another rig. The temporaries are removed in every case. AutobonesError names the file that
    could not be written.
    """
    staged = [(os.fspath(t), os.fspath(p)) for t, p in staged]
    try:
        for _, target in staged:
            check_destination(target, what)
    except AutobonesError:
        _remove(t for t, _ in staged)
        raise
    done, backups = [], []
    current = None
    try:
        for tmp, target in staged:
            current = target
            backup = None
            if os.path.isfile(target):
                backup = tmp + BACKUP_SUFFIX  # hidden and unique, like the temporary itself
                try:
                    os.link(target, backup)
                except OSError:  # no hard links here (FAT, some network file systems): no way back
                    backup = None
            backups.append(backup)
            os.replace(tmp, target)
            done.append(target)
    except OSError as exc:
        for target, backup in zip(done, backups):
            try:
                if backup is not None:
                    os.replace(backup, target)
                else:
                    os.unlink(target)
            except OSError:
                pass
        _remove(t for t, _ in staged)
        _remove(b for b in backups if b is not None)
        raise AutobonesError(f"{current}: cannot write {what} ({exc.strerror or exc}); "
                             "nothing was written") from None
    _remove(b for b in backups if b is not None)
    return [target for _, target in staged]


def _remove(paths):
    for p in paths:
        try:
            os.unlink(p)
        except OSError:
            pass


def same_file(a, b):
    """True when paths ``a`` and ``b`` name the same file (hard links and symbolic links
    included); a path that does not exist is compared by its resolved name."""
    a, b = os.fspath(a), os.fspath(b)
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.realpath(a) == os.path.realpath(b)


def refuse_overwriting_inputs(outputs, inputs):
    """AutobonesError when any output path is one of the inputs: an output is never the input.

    ``outputs`` and ``inputs`` are paths (None entries ignored); checked before any work, so a
    command such as ``place a.glb -o a.glb`` stops at once instead of replacing its own input.
    """
    for out in outputs:
        if out is None:
            continue
        for inp in inputs:
            if inp is not None and os.path.exists(os.fspath(inp)) and same_file(out, inp):
                raise AutobonesError(f"{os.fspath(out)}: is the input file {os.fspath(inp)}; an output never "
                                     "replaces its input, choose another output name")


def check_outputs(outputs, inputs=(), what="the output"):
    """Every check a group of outputs can fail before any work is done: none is an input
    (:func:`refuse_overwriting_inputs`), each one's folder exists and takes a new file (one is made
    and removed), and no folder or special file stands where one goes (:func:`check_destination`).

    ``outputs`` and ``inputs`` are paths (None entries ignored). A command calls it first, so a
    mistyped ``-o`` costs nothing instead of the minutes a large head takes to rig.
    """
    refuse_overwriting_inputs(outputs, inputs)
    for out in outputs:
        if out is None:
            continue
        check_destination(out, what)
        fd, tmp = temp_beside(out, suffix=".probe")   # a read-only folder or /proc: refused here
        os.close(fd)
        os.unlink(tmp)


def probe_folder(folder, what="the output folder"):
    """Create ``folder`` (and its parents) if needed and check that a file can be written in it,
    with a temporary file removed at once; AutobonesError naming the folder otherwise."""
    folder = os.fspath(folder)
    try:
        os.makedirs(folder, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=".autobones-probe-", dir=folder)
        os.close(fd)
        os.unlink(tmp)
    except OSError as exc:
        raise AutobonesError(f"{folder}: cannot write in {what} ({exc.strerror or exc})") from None
    return folder


def write_bytes_atomic(path, data, what="file"):
    """Write ``data`` to a temporary file beside ``path``, then rename it into place.

    Parameters
    ----------
    path : str or os.PathLike
        Target file; its folder must exist.
    data : bytes
        Content.
    what : str
        What the file is, for the error message (e.g. ``"the batch report"``).
    """
    path = os.fspath(path)
    check_destination(path, what)
    tmp = None
    try:
        fd, tmp = temp_beside(path)  # inside the try: an unwritable folder fails here
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.replace(tmp, path)
    except OSError as exc:
        if tmp is not None:
            _remove([tmp])
        raise AutobonesError(f"{path}: cannot write {what} ({exc.strerror or exc})") from None
    return path


def write_text_atomic(path, text, what="file"):
    """:func:`write_bytes_atomic` of ``text`` encoded as UTF-8."""
    return write_bytes_atomic(path, text.encode("utf-8"), what)
