"""Pack the Blender add-on (:mod:`autobones.blender_addon`) into a zip Blender installs.

Beyond the papers (issue #37): ``autobones blender-addon -o autobones_blender.zip`` writes the
add-on's source under the folder ``autobones_blender/`` (Blender's module name for it) with the
landmark contract's names (:data:`autobones.io.landmark_names.NAMES`) as ``landmark_names.json``,
so the add-on names landmark empties exactly as autobones reads them without importing autobones.
Entries are sorted and dated 1980-01-01: the same autobones writes the same bytes.
"""
from __future__ import annotations

import io
import json
import os
import re
import zipfile

from .errors import AutobonesError
from .io.atomic import check_destination, replace_all, temp_beside
from .io.landmark_names import NAMES

MODULE = "autobones_blender"  # the add-on's module name in Blender (its folder in the zip)
SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "blender_addon")
NAMES_FILE = "landmark_names.json"
_BL_VERSION = re.compile(rb'"version": \([0-9, ]*\),')


def _version_tuple():
    """autobones' version as bl_info's tuple of whole numbers (``0.1.0`` -> ``(0, 1, 0)``)."""
    from .version import __version__

    return tuple(int(p) for p in re.findall(r"\d+", __version__)[:3])


def addon_files():
    """[(name in the zip, bytes)] of the add-on: its ``.py`` files and the landmark names, sorted."""
    files = []
    for name in sorted(os.listdir(SOURCE)):
        if name.endswith(".py"):
            with open(os.path.join(SOURCE, name), "rb") as fh:
                data = fh.read()
            if name == "__init__.py":  # Blender shows bl_info's version: autobones' own
                data = _BL_VERSION.sub(f'"version": {_version_tuple()},'.encode(), data, count=1)
            files.append((f"{MODULE}/{name}", data))
    names = json.dumps({"format": "autobones-landmarks/1", "names": list(NAMES)}, indent=1) + "\n"
    files.append((f"{MODULE}/{NAMES_FILE}", names.encode()))
    return sorted(files)


def addon_zip_bytes():
    """The add-on zip's bytes (deterministic)."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in addon_files():
            info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, data)
    return buf.getvalue()


def write_addon_zip(out_path):
    """Write the add-on zip to ``out_path``.

    Parameters
    ----------
    out_path : str or os.PathLike
        A ``.zip`` path. An existing zip is replaced (an older add-on zip); any other existing file,
        a folder in the way or a missing folder is refused before anything is written.

    Returns
    -------
    dict
        ``path``, ``module`` (the add-on's name in Blender), ``files`` (count), ``bytes``.

    Raises AutobonesError (one line) for a bad destination.
    """
    out_path = os.fspath(out_path)
    if not out_path.lower().endswith(".zip"):
        raise AutobonesError(f"{out_path}: the add-on is written as a .zip (Blender installs zips)")
    check_destination(out_path, "the add-on zip")
    if os.path.isfile(out_path) and not zipfile.is_zipfile(out_path):
        raise AutobonesError(f"{out_path}: exists and is not a zip file; not replacing it")
    data = addon_zip_bytes()
    fd, tmp = temp_beside(out_path, suffix=".zip")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        replace_all([(tmp, out_path)], "the add-on zip")
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    return {"path": out_path, "module": MODULE, "files": len(addon_files()), "bytes": len(data)}
