"""Write a file so that a reader sees the old file or the whole new one, never a part."""
from __future__ import annotations

import os
import tempfile

from ..errors import AutobonesError


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
    fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(os.fspath(path)) + "-", suffix=suffix, dir=folder)
    os.fchmod(fd, _default_mode())
    return fd, tmp


def output_folder(path):
    """The folder ``path`` will be written in; AutobonesError when it does not exist."""
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise AutobonesError(f"{path}: the folder {folder} does not exist; create it first")
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
    output_folder(path)
    fd, tmp = temp_beside(path)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.replace(tmp, path)
    except OSError as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise AutobonesError(f"{path}: cannot write {what} ({exc.strerror or exc})") from None
    return path


def write_text_atomic(path, text, what="file"):
    """:func:`write_bytes_atomic` of ``text`` encoded as UTF-8."""
    return write_bytes_atomic(path, text.encode("utf-8"), what)
