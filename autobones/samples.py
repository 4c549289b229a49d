"""Sample heads to try every command on: ``autobones samples DIR`` and :func:`path`.

The files come from the package's ``sample_data/`` (built by ``tools/build_samples.py`` from the
test meshes whose licences allow redistribution; ``LICENSES.md`` there is written with them): the
default head, a scan, a bust, a cartoon robot and a goat, each with its landmarks, and a short
face-capture take.

Examples
--------
>>> from autobones import samples
>>> samples.NAMES[:4]
('default_head.obj', 'default_head.landmarks.json', 'scan.obj', 'scan.landmarks.json')
>>> samples.path("goat.obj").name
'goat.obj'
"""
from __future__ import annotations

import atexit
import gzip
import os
import shutil
import tempfile
from importlib import resources
from pathlib import Path

from .errors import AutobonesError

HEADS = ("default_head", "scan", "bust", "robot", "goat")
# every file written, in the order the README lists them
NAMES = tuple(n for h in HEADS for n in (f"{h}.obj", f"{h}.landmarks.json")) + ("goat.pp", "take.csv",
                                                                                 "README.md", "LICENSES.md")
_cache = {}


def _data(name):
    return resources.files("autobones").joinpath("sample_data", name)


def _generic(name):
    from .generic_rig import HERE

    return Path(HERE) / name


def sample_bytes(name):
    """The content of the sample file ``name`` (one of :data:`NAMES`)."""
    if name not in NAMES:
        raise AutobonesError(f"{name!r} is not a sample file; the samples are {', '.join(NAMES)}")
    if name.startswith("default_head."):
        return _generic(name).read_bytes()
    if name.endswith(".obj"):
        return gzip.decompress(_data(name + ".gz").read_bytes())
    if name == "goat.pp":
        return _picked_points("goat.landmarks.json", "goat.obj").encode()
    return _data(name).read_bytes()


def _picked_points(landmarks, mesh):
    """The landmark file as MeshLab picked points (.pp), the format ``--landmarks`` also reads."""
    import json

    from .io.landmarks import picked_points_text

    return picked_points_text(json.loads(_data(landmarks).read_bytes())["landmarks"], mesh)


def write_samples(folder, force=False):
    """Write every sample file into ``folder``; returns their paths (``Path``), in :data:`NAMES` order.

    ``folder`` is created when missing (its parent must exist). An existing folder that holds
    anything is refused unless ``force`` (then the sample files in it are replaced, other files
    kept). The files are written into a temporary folder first (beside a new folder, inside an existing
    one), so a failure leaves nothing half-written.
    """
    shown = os.fspath(folder)  # as the user wrote it, in messages
    folder = Path(shown)
    parent = folder.resolve().parent
    if folder.exists() and not folder.is_dir():
        raise AutobonesError(f"{shown}: exists and is not a folder; choose a new or empty folder")
    if not parent.is_dir():
        raise AutobonesError(f"{shown}: the folder {parent} does not exist; create it first")
    existing = folder.is_dir()
    if existing and any(folder.iterdir()) and not force:
        raise AutobonesError(f"{shown}: the folder is not empty; choose a new or empty folder, or add --force "
                             "to replace the sample files in it")
    # staged beside a new folder, which then appears whole; inside an existing one (the folder the user
    # is in, `samples .`, cannot be removed and replaced), whose files are then moved in one by one
    where = folder if existing else parent
    try:
        staging = Path(tempfile.mkdtemp(prefix=f".{folder.resolve().name}-", dir=where))
    except OSError as exc:
        raise AutobonesError(f"{shown}: cannot write in {where} ({exc.strerror or exc})") from None
    try:
        for name in NAMES:
            (staging / name).write_bytes(sample_bytes(name))
        os.chmod(staging, 0o777 & ~_umask())  # mkdtemp makes its folder owner-only
        if existing:  # empty, or --force with other files: ours replaced one by one, theirs kept
            for name in NAMES:
                os.replace(staging / name, folder / name)
        else:
            os.replace(staging, folder)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return [folder / n for n in NAMES]


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


def path(name):
    """Path of the sample file ``name`` (``"goat.obj"``, ``"take.csv"``...), written with all the
    others into a temporary folder on first use (removed when Python exits): the doctests' inputs."""
    if "folder" not in _cache:
        root = tempfile.mkdtemp(prefix="autobones-samples-")
        atexit.register(shutil.rmtree, root, True)
        write_samples(Path(root) / "samples")
        _cache["folder"] = Path(root) / "samples"
    if name not in NAMES:
        raise AutobonesError(f"{name!r} is not a sample file; the samples are {', '.join(NAMES)}")
    return _cache["folder"] / name
