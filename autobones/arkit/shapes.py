"""The packaged ARKit source shapes: ICT-FaceKit's neutral skin and its 51 displacement fields.

Goes beyond the seeds (issue #15). Built by ``generic_rig/build_arkit_shapes.py`` from
ICT-FaceKit (MIT, ``generic_rig/arkit/LICENSE``); see that script for the file layout.
"""
from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..errors import AutobonesError
from ..io.files import read_json
from .folds import folded_each
from .names import ABSENT, ARKIT_NAMES

# landmarks a set and a head must share: the correspondence's TPS needs a few non-coplanar points
# (the robot shares 7 with ICT)
MIN_LANDMARKS = 6
NPZ, JSON = "ict_arkit.npz", "ict_arkit.json"  # the set's two files (the packaged set's names, kept for any set)
IDENTITY_NPZ = "ict_identity.npz"  # optional: identity modes of the set's skin


def shapes_folder():
    """Folder of the packaged shape set (``generic_rig/arkit``)."""
    from ..generic_rig import HERE

    return os.path.join(HERE, "arkit")


@dataclass(frozen=True)
class ShapeSet:
    """A base head and named displacement fields of it.

    vertices : (n, 3) float64
        The base skin, in its own frame and units (ICT: cm, +X subject's left, +Y up, +Z front).
    faces : (m, 3) int64
    landmarks : dict str -> (3,) float64
        Contract landmarks of the base, same frame.
    deltas : dict str -> (n, 3) float64
        Displacement of every base vertex at weight 1, per ARKit name (absent names left out).
    meta : dict
        The sidecar JSON (source, licence, units, ...).
    identity : (j, n, 3) float64 or None
        Identity modes of the base skin (one standard deviation each, its units), when the folder has
        ``ict_identity.npz`` (the packaged set: ICT's 20): the expression fit solves them with the
        expression (:mod:`autobones.rig_transfer.expression_prior`).
    """

    vertices: np.ndarray
    faces: np.ndarray
    landmarks: dict
    deltas: dict
    meta: dict
    identity: Optional[np.ndarray] = None

    @property
    def names(self):
        """The names with data, in :data:`ARKIT_NAMES` order."""
        return [n for n in ARKIT_NAMES if n in self.deltas]


def load_shapes(folder=None):
    """The :class:`ShapeSet` in ``folder`` (None: the packaged ICT-FaceKit set; a rig folder's
    ``arkit/`` from ``build-rig --shapes`` has the same files). Cached: do not modify it."""
    folder = shapes_folder() if folder is None else os.fspath(folder)
    try:  # the file's time in the key: a rig folder rebuilt in place is read again
        stamp = os.stat(os.path.join(folder, NPZ)).st_mtime_ns
    except OSError:
        stamp = None
    return _load(folder, stamp)


@functools.lru_cache(maxsize=4)
def _load(folder, stamp):
    npz, js = os.path.join(folder, NPZ), os.path.join(folder, JSON)
    try:
        meta = read_json(js, "rig", "ARKit shape set's JSON")
        with np.load(npz, allow_pickle=False) as z:
            V = z["vertices"].astype(np.float64)
            F = z["faces"].astype(np.int64)
            deltas = {}
            for name in ARKIT_NAMES:
                if f"shape/{name}/index" not in z.files:
                    continue
                D = np.zeros_like(V)
                D[z[f"shape/{name}/index"].astype(np.int64)] = z[f"shape/{name}/delta"].astype(np.float64)
                deltas[name] = D
    except (OSError, KeyError, ValueError) as exc:
        raise AutobonesError(f"{folder}: not a readable ARKit shape set ({type(exc).__name__}: {exc}); "
                             "build it with generic_rig/build_arkit_shapes.py") from None
    # a set may leave names out when its sidecar lists them as absent (a studio's own set)
    missing = [n for n in ARKIT_NAMES if n not in deltas and n not in ABSENT and n not in meta.get("absent", ())]
    if missing:
        raise AutobonesError(f"{folder}: the shape set lacks {', '.join(missing)}")
    landmarks = {k: np.asarray(v, dtype=np.float64) for k, v in meta["landmarks"].items()}
    identity = None
    if os.path.isfile(os.path.join(folder, IDENTITY_NPZ)):
        with np.load(os.path.join(folder, IDENTITY_NPZ), allow_pickle=False) as z:
            identity = z["modes"].astype(np.float64)
        if identity.shape[1:] != V.shape:
            raise AutobonesError(f"{folder}: {IDENTITY_NPZ} is not for this skin ({identity.shape[1:]} vs {V.shape})")
    return ShapeSet(V, F, landmarks, deltas, meta, identity)


def flipped_triangles(V, F, deltas):
    """Triangles whose normal turns over (dot < 0) between ``V`` (n, 3) and ``V + D`` for each
    displacement ``D`` (n, 3) of ``deltas`` (dict name -> D): dict name -> count
    (:func:`autobones.arkit.folds.folded_each`, all shapes at once)."""
    if not deltas:
        return {}
    counts = folded_each(V, F, np.stack(list(deltas.values()))).sum(axis=1)
    return {n: int(c) for n, c in zip(deltas, counts)}
