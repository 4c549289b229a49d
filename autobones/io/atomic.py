"""Write a text file so that a reader sees the old file or the whole new one, never a part."""
from __future__ import annotations

import os
import tempfile

from ..errors import AutobonesError


def write_text_atomic(path, text, what="file"):
    """Write ``text`` to a temporary file beside ``path``, then rename it into place.

    Parameters
    ----------
    path : str or os.PathLike
        Target file; its folder must exist.
    text : str
        Content (UTF-8).
    what : str
        What the file is, for the error message (e.g. ``"the batch report"``).
    """
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise AutobonesError(f"{path}: the folder {folder} does not exist; create it first")
    fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(path) + "-", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except OSError as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise AutobonesError(f"{path}: cannot write {what} ({exc.strerror or exc})") from None
