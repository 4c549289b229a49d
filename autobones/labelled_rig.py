"""The labelled generic rig: skin, landmarks, skeleton, skin weights, attribute fields, muscles.

Orvalho, Zacur & Susin 2008, §2: the generic rig R is a skin surface R_S with landmarks (lambda),
a skeleton R_B, muscles R_M and per-layer attributes ("weight, texture,
muscle stress, etc."). :class:`LabelledRig` holds those layers as plain arrays
so that the transfer (their §3) can carry every field to another head, and users
can add their own (``rig.fields["my_field"] = array``, one row per vertex).

On disk a rig is a folder:

``rig.json``
    everything small and readable: format, units and frame notes, landmarks,
    skeleton (names, parents, heads, tails), muscles, label class names, the
    list of fields with their shapes and dtypes, free-form ``info``.
``mesh.obj``
    ``v`` and ``f`` lines only (1-based), vertex order kept, coordinates written
    with the shortest round-trip repr (exact float64).
``fields.npz``
    ``weights`` and every field, float32 for floating fields (integer label
    fields keep their integer type).

:meth:`LabelledRig.save` writes into a temporary folder next to the target and
renames it into place, so a reader never sees a half-written rig.
"""
from __future__ import annotations

import json
import os
import shutil
import tempfile
from dataclasses import dataclass, field

import numpy as np

from .errors import AutobonesError
from .io.files import read_json
from .io.jsonable import jsonable, strict_dumps
from .io.obj import read_obj, write_obj
from .skeleton import Skeleton

FORMAT = "autobones-labelled-rig/1"
FILES = ("rig.json", "mesh.obj", "fields.npz")


def check_rig_folder(folder):
    """``(folder, parent)`` absolute, when :meth:`LabelledRig.save` can write ``folder``: its parent
    exists and nothing but a folder stands there; AutobonesError naming it otherwise."""
    folder = os.path.abspath(os.fspath(folder))
    parent = os.path.dirname(folder)
    if not os.path.isdir(parent):
        raise AutobonesError(f"{folder}: the parent folder {parent} does not exist; create it first")
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise AutobonesError(f"{folder}: exists and is not a folder")
    return folder, parent


@dataclass
class LabelledRig:
    """A head with its rig layers; all coordinates in the same frame and units.

    Attributes
    ----------
    vertices : (n, 3) float
        Skin vertices in the head's own (input) frame and units.
    faces : (m, 3) int
        Triangles.
    landmarks : dict str -> (3,) float
        Contract landmarks (``spec/landmarks.md``), same frame.
    skeleton : Skeleton
        Bones (``neck``, ``head``, ``jaw``, ``eye_l``, ``eye_r`` for a built rig).
    weights : (n, b) float
        Skin weights for ``skeleton`` bones; rows sum to 1.
    fields : dict str -> (n,) or (n, k) array
        Per-vertex attribute fields (floats in [0, 1], or integer labels).
    labels : dict str -> list of str
        Class names of integer label fields: ``fields[name] == i`` means ``labels[name][i]``.
    muscles : list of dict
        Each with at least ``name``, ``type``, ``side``, ``origin`` (3,), ``insertion`` (3,),
        ``width`` and ``falloff`` (widths in the same units as the vertices).
    units : str
        Free text, e.g. ``"metres"`` or ``"input mesh units"``.
    frame : str
        Free text describing the axes, e.g. ``"+Y up, +Z front, +X subject's left"``.
    info : dict
        Anything else JSON-serialisable (canonical frame, build parameters, rules).
    """

    vertices: np.ndarray
    faces: np.ndarray
    landmarks: dict
    skeleton: Skeleton
    weights: np.ndarray
    fields: dict = field(default_factory=dict)
    labels: dict = field(default_factory=dict)
    muscles: list = field(default_factory=list)
    units: str = "input mesh units"
    frame: str = "input mesh frame"
    info: dict = field(default_factory=dict)

    def __post_init__(self):
        self.vertices = np.asarray(self.vertices, dtype=np.float64)
        self.faces = np.asarray(self.faces, dtype=np.int64)
        self.weights = np.asarray(self.weights)
        self.landmarks = {k: np.asarray(v, dtype=np.float64).reshape(3) for k, v in self.landmarks.items()}
        n = len(self.vertices)
        if self.vertices.ndim != 2 or self.vertices.shape[1] != 3:
            raise AutobonesError(f"LabelledRig: vertices must be (n, 3), got {self.vertices.shape}")
        if self.faces.ndim != 2 or self.faces.shape[1] != 3:
            raise AutobonesError(f"LabelledRig: faces must be (m, 3), got {self.faces.shape}")
        if self.weights.shape != (n, len(self.skeleton)):
            raise AutobonesError(f"LabelledRig: weights must be ({n}, {len(self.skeleton)}) "
                                 f"(vertices x bones), got {self.weights.shape}")

    @property
    def bone_names(self):
        return list(self.skeleton.names)

    def check_fields(self):
        """Raise AutobonesError if a field does not have one row per vertex."""
        n = len(self.vertices)
        for name, value in self.fields.items():
            a = np.asarray(value)
            if a.ndim not in (1, 2) or a.shape[0] != n:
                raise AutobonesError(f"LabelledRig field {name!r}: expected ({n},) or ({n}, k), got {a.shape}")
        for name in self.labels:
            if name not in self.fields:
                raise AutobonesError(f"LabelledRig: labels given for {name!r} but there is no such field")

    # -----------------------------------------------------------------------------------------
    # saving

    def to_json(self):
        """The small, readable part of the rig as a JSON-ready dict."""
        fields = {}
        for name, value in self.fields.items():
            a = np.asarray(value)
            fields[name] = {"shape": list(a.shape), "dtype": str(_stored(a).dtype)}
        return {
            "format": FORMAT,
            "units": self.units,
            "frame": self.frame,
            "vertex_count": int(len(self.vertices)),
            "face_count": int(len(self.faces)),
            "landmarks": {k: [float(c) for c in v] for k, v in self.landmarks.items()},
            "skeleton": self.skeleton.to_list(),
            "muscles": [jsonable(m) for m in self.muscles],
            "labels": {k: list(v) for k, v in self.labels.items()},
            "fields": fields,
            "info": jsonable(self.info),
        }

    def save(self, folder):
        """Write ``rig.json``, ``mesh.obj`` and ``fields.npz`` into ``folder`` atomically.

        The files are written into a temporary folder beside ``folder`` which then
        replaces it (an existing rig folder is replaced as a whole).
        """
        self.check_fields()
        folder, parent = check_rig_folder(folder)
        tmp = tempfile.mkdtemp(prefix="." + os.path.basename(folder) + "-", dir=parent)
        try:
            os.chmod(tmp, 0o755)
            with open(os.path.join(tmp, "rig.json"), "w", encoding="utf-8") as fh:
                fh.write(strict_dumps(self.to_json(), indent=1))
                fh.write("\n")
            write_obj(os.path.join(tmp, "mesh.obj"), self.vertices, self.faces, comment="autobones labelled rig skin")
            arrays = {"weights": _stored(self.weights)}
            for name, value in self.fields.items():
                arrays["field:" + name] = _stored(np.asarray(value))
            np.savez_compressed(os.path.join(tmp, "fields.npz"), **arrays)
            old = None
            if os.path.isdir(folder):
                old = tempfile.mkdtemp(prefix="." + os.path.basename(folder) + "-old-", dir=parent)
                os.rmdir(old)
                os.rename(folder, old)
            os.rename(tmp, folder)
            if old is not None:
                shutil.rmtree(old, ignore_errors=True)
        except OSError as exc:
            shutil.rmtree(tmp, ignore_errors=True)
            raise AutobonesError(f"{folder}: cannot write the rig ({exc.strerror or exc})") from None
        return folder

    # -----------------------------------------------------------------------------------------
    # loading

    @classmethod
    def load(cls, folder):
        """Read a rig folder written by :meth:`save`; AutobonesError naming what is wrong."""
        from .arguments import path_argument

        folder = path_argument(folder, "folder")
        if not os.path.isdir(folder):
            raise AutobonesError(f"{folder}: no such rig folder (expected a folder with {', '.join(FILES)})")
        missing = [f for f in FILES if not os.path.isfile(os.path.join(folder, f))]
        if missing:
            raise AutobonesError(f"{folder}: not a complete rig folder, missing {', '.join(missing)}")
        path = os.path.join(folder, "rig.json")
        try:
            meta = read_json(path, "rig", "rig folder's rig.json", "not readable rig JSON")  # bounded, depth checked
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise AutobonesError(f"{path}: not readable rig JSON ({exc})") from None
        if not isinstance(meta, dict) or meta.get("format") != FORMAT:
            got = meta.get("format") if isinstance(meta, dict) else type(meta).__name__
            raise AutobonesError(f"{path}: format {got!r} is not {FORMAT!r}; not a labelled rig")
        try:
            V, F = _read_skin(os.path.join(folder, "mesh.obj"))
            with np.load(os.path.join(folder, "fields.npz"), allow_pickle=False) as z:
                arrays = {k: z[k] for k in z.files}
        except AutobonesError:
            raise
        except Exception as exc:  # noqa: BLE001 - any parser failure is the file's fault
            raise AutobonesError(f"{folder}: corrupt mesh.obj or fields.npz ({exc.__class__.__name__}: {exc})") from None
        try:
            sk = meta["skeleton"]
            names = [b["name"] for b in sk]
            parents = [names.index(b["parent"]) if b["parent"] is not None else -1 for b in sk]
            skeleton = Skeleton(names, parents, [b["head"] for b in sk], [b["tail"] for b in sk])
            if "weights" not in arrays:
                raise KeyError("weights (in fields.npz)")
            fields = {}
            for name in meta.get("fields", {}):
                key = "field:" + name
                if key not in arrays:
                    raise KeyError(f"field {name!r} (in fields.npz)")
                fields[name] = arrays[key]
            muscles = []
            for m in meta.get("muscles", []):
                m = dict(m)
                for k in ("origin", "insertion"):
                    if k in m:
                        m[k] = np.asarray(m[k], dtype=np.float64)
                muscles.append(m)
            if meta.get("vertex_count") not in (None, len(V)) or meta.get("face_count") not in (None, len(F)):
                raise ValueError(f"mesh.obj has {len(V)} vertices / {len(F)} faces, rig.json says "
                                 f"{meta.get('vertex_count')} / {meta.get('face_count')}")
            rig = cls(vertices=V, faces=F, landmarks=meta.get("landmarks", {}), skeleton=skeleton,
                      weights=arrays["weights"], fields=fields, labels=meta.get("labels", {}),
                      muscles=muscles, units=meta.get("units", ""), frame=meta.get("frame", ""),
                      info=meta.get("info", {}))
            rig.check_fields()
        except AutobonesError as exc:
            raise AutobonesError(f"{folder}: corrupt rig: {exc}") from None
        except (KeyError, ValueError, TypeError, AssertionError, IndexError) as exc:
            raise AutobonesError(f"{folder}: corrupt rig ({exc.__class__.__name__}: {exc})") from None
        return rig


def _stored(a):
    a = np.asarray(a)
    if np.issubdtype(a.dtype, np.floating):
        return a.astype(np.float32)
    if a.dtype == bool:
        return a.astype(np.uint8)
    return a


def _read_skin(path):
    """mesh.obj of a rig folder: (V (n, 3) float64, F (m, 3) int64), both non-empty and consistent."""
    V, F = read_obj(path)
    if len(F) == 0:
        raise AutobonesError(f"{path}: no vertices or faces")
    if F.min() < 0 or F.max() >= len(V):
        raise AutobonesError(f"{path}: face index out of range")
    return V, F


def load_labelled_rig(folder):
    """Shorthand for :meth:`LabelledRig.load`."""
    return LabelledRig.load(folder)
