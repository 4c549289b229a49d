"""Read a rig back from the files ``Rig.save`` writes: ``x.glb``, ``x.rig.json``, ``x.weights.npz``.

Beyond Orvalho, Zacur & Susin 2008: the saved rig is the hand-off between rigging and animation, so
``autobones.load_rig("head.glb").pose(au={12: 0.8})`` must give what the in-memory rig
gave. The glb supplies the triangles (and, for files saved before the sidecar kept them,
the float32 positions); the sidecar the frame, bones, labels, muscles, landmarks and
expression definitions; the npz the full weight matrix, every field and the exact float64
vertices.
"""
from __future__ import annotations

import os
import zipfile

import numpy as np

from ..arguments import path_argument
from ..errors import AutobonesError, counted
from ..expressions.definitions import MODEL_DEFAULTS
from .files import check_regular, read_json, shown
from .rig_schema import SchemaError, check_sidecar, finite_float, no_constants
from .gltf import read_accessor, read_glb
from ..orient import Frame
from ..rig import SIDECAR_FORMAT, Rig, sidecar_attributes, sidecar_paths
from ..skeleton import Skeleton

# sidecar keys the Rig rebuilds itself; every other key goes to its typed attributes (rig.sidecar_attributes)
_OWN_KEYS = ("format", "autobones_version", "options", "frame", "vertex_count", "bones", "label_names", "labels",
             "facial_mask", "depth_merge_distances")


def load_rig(path):
    """The :class:`autobones.rig.Rig` saved as ``path`` (a ``.glb`` written by autobones) and its sidecars.

    Parameters
    ----------
    path : str or os.PathLike
        ``x.glb`` (or ``x.rig.glb``); ``x.rig.json`` and ``x.weights.npz`` must sit beside it.

    Returns
    -------
    Rig
        ``vertices`` (n, 3) float64 in the input frame and units: the exact input vertices
        kept in the npz (rigs saved before it kept them: the glb's float32 positions),
        ``faces`` (m, 3) int64 from the glb, ``skeleton``, ``weights`` (n, b) float64 (saved
        as float32), ``labels``, ``facial_mask``, ``frame``, ``options``, ``fields`` and the
        sidecar's typed attributes (``muscles``, ``landmarks``, ``field_labels``, ``expressions``
        with its definitions...; see :class:`autobones.rig.Rig`). ``rig.pose(...)`` works
        when the rig has muscles (``transfer``); the model is fitted again on first use
        with the definitions the sidecar kept
        (``rig.expression_model(other)`` to use others). The sidecar pins the numbers, not
        the code: a newer autobones poses with its own model code and the saved numbers
        (a parameter they lack takes the code's default).
        ``segmentation`` and ``timings`` are not saved (None, {}).

    Raises
    ------
    AutobonesError
        The glb is missing, unreadable or not written by autobones, a sidecar is missing or
        corrupt, or the three files do not belong together (vertex or bone counts differ).

    Examples
    --------
    >>> import os, tempfile
    >>> import autobones
    >>> from autobones import samples
    >>> path = os.path.join(tempfile.mkdtemp(), "robot.glb")
    >>> saved = autobones.transfer(samples.path("robot.obj"), samples.path("robot.landmarks.json")).save(path)
    >>> rig = autobones.load_rig(path)
    >>> rig.skeleton.names, len(rig.muscles)
    (['neck', 'head', 'jaw', 'eye_l', 'eye_r'], 40)
    >>> rig.pose(au={12: 0.8, 6: 0.4}, jaw_deg=10).shape == rig.vertices.shape
    True
    """
    path = path_argument(path, "path")  # load_rig(None): one line naming the argument, not a TypeError
    doc, body = _read_autobones_glb(path)
    json_path, npz_path = sidecar_paths(path)
    for side in (json_path, npz_path):
        if not os.path.isfile(side):
            raise AutobonesError(f"{path}: its sidecar {side} is missing (autobones writes the glb, "
                                 f"{os.path.basename(json_path)} and {os.path.basename(npz_path)} together; "
                                 "keep them beside each other)")
    meta, skeleton, frame, labels, mask = _read_sidecar(json_path)
    names = skeleton.names
    try:
        with np.load(npz_path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        W = arrays["weights"].astype(np.float64)
        saved_names = [str(s) for s in arrays.get("bone_names", names)]
    except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError) as exc:
        raise AutobonesError(f"{npz_path}: not a readable autobones weights file ({type(exc).__name__}: {exc})") from None
    try:
        prim = doc["meshes"][0]["primitives"][0]
        F = read_accessor(doc, body, prim["indices"]).astype(np.int64).reshape(-1, 3)
        P = read_accessor(doc, body, prim["attributes"]["POSITION"])
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        raise AutobonesError(f"{path}: its mesh cannot be read ({type(exc).__name__}: {exc})") from None
    V = arrays.get("vertices")
    V = P.astype(np.float64) if V is None else np.asarray(V, dtype=np.float64)
    _check_together(path, len(mask), P, V, F, W, labels, names, saved_names)
    fields = {k[len("field/"):]: v for k, v in arrays.items() if k.startswith("field/")}
    arkit = _arkit_targets(path, doc, body, meta.get("arkit"), len(P))
    return Rig(vertices=V, faces=F, skeleton=skeleton, weights=W, labels=labels, facial_mask=mask, frame=frame,
               options=dict(meta.get("options") or {}), fields=fields, arkit_targets=arkit,
               **sidecar_attributes({k: v for k, v in meta.items() if k not in _OWN_KEYS}))


def _arkit_targets(path, doc, body, record, n):
    """The ARKit morph targets the sidecar's ``arkit`` record names, read from the glb: dict name ->
    (n, 3) float64 (the float32 the file stores), or None when the rig has none."""
    if not record:
        return None
    try:
        mesh = doc["meshes"][0]
        names = list(mesh.get("extras", {}).get("targetNames", []))
        targets = mesh["primitives"][0].get("targets", [])
        out = {}
        for name in record["names"]:
            D = read_accessor(doc, body, targets[names.index(name)]["POSITION"]).astype(np.float64)
            if D.shape != (n, 3):
                raise ValueError(f"target {name} has {len(D)} rows for {n} vertices")
            out[name] = D
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        raise AutobonesError(f"{path}: its ARKit morph targets cannot be read ({type(exc).__name__}: {exc}); "
                             "save the rig again") from None
    return out


def _read_autobones_glb(path):
    """(glTF JSON dict, binary chunk bytes) of a glb written by autobones; AutobonesError otherwise."""
    check_regular(path, "rig", "a folder, not a rig .glb")
    try:
        doc, body = read_glb(path)
    except (OSError, ValueError) as exc:
        raise AutobonesError(f"{path}: cannot read it as a glb ({exc})") from None
    except RecursionError:  # read_glb's json.loads on a JSON chunk nested 100k deep
        raise AutobonesError(f"{path}: cannot read it as a glb (its JSON chunk is nested too deeply: a damaged "
                             "file)") from None
    asset = doc.get("asset") or {}
    if asset.get("generator") != "autobones":
        raise AutobonesError(f"{path}: not a rig written by autobones (generator {asset.get('generator')!r}); "
                             "rig the mesh first: autobones transfer HEAD -o OUT.glb")
    return doc, body


def _read_sidecar(json_path):
    """The ``.rig.json`` sidecar: (its dict, Skeleton, Frame, labels (n,) int8, facial mask (n,) bool).
    Every value is checked by :mod:`autobones.io.rig_schema` before it is used: a tampered sidecar is
    one line naming its key, never a traceback or an allocation of what it claims."""
    meta = read_json(json_path, "sidecar", invalid="not a readable autobones sidecar",  # bounded, depth checked
                     parse_constant=no_constants, parse_float=finite_float)
    try:
        if not isinstance(meta, dict) or meta.get("format") != SIDECAR_FORMAT:
            raise SchemaError(f"format {meta.get('format') if isinstance(meta, dict) else None!r}, "
                              f"expected {SIDECAR_FORMAT!r}")
        n = check_sidecar(meta, MODEL_DEFAULTS)
    except SchemaError as exc:
        raise AutobonesError(f"{shown(json_path)}: not a readable autobones sidecar ({exc})") from None
    bones = meta["bones"]
    names = [b["name"] for b in bones]
    skeleton = Skeleton(names, [names.index(b["parent"]) if b["parent"] is not None else -1 for b in bones],
                        [b["head"] for b in bones], [b["tail"] for b in bones])
    frame = Frame.from_dict(meta["frame"])
    labels = np.asarray(meta["labels"], dtype=np.int8)  # within label_names: checked
    mask = np.zeros(n, dtype=bool)
    mask[np.asarray(meta.get("facial_mask", []), dtype=np.int64)] = True
    return meta, skeleton, frame, labels, mask


def _check_together(path, n, P, V, F, W, labels, names, saved_names):
    """AutobonesError unless the glb positions ``P``, npz vertices ``V`` and weights ``W`` and the
    sidecar's ``n`` vertices, ``labels`` and bone ``names`` describe one rig."""
    problems = []
    if len(P) != n or V.shape != (n, 3) or labels.shape != (n,):
        problems.append(f"vertex counts differ (glb {len(P)}, sidecar {n}, npz {len(V)})")
    elif np.abs(V.astype(np.float32) - P).max(initial=0.0) > 0:
        problems.append("the npz vertices are not the glb's")
    if W.shape != (n, len(names)) or saved_names != names:
        problems.append(f"the weights ({W.shape[0]} x {W.shape[1] if W.ndim == 2 else '?'}, bones "
                        f"{', '.join(saved_names[:3])}...) do not match the sidecar's {len(names)} bones")
    if len(F) and (F.min() < 0 or F.max() >= len(P)):
        problems.append("triangle indices out of range")
    for what, a in (("glb positions", P), ("npz vertices", V), ("npz weights", W)):
        if not np.isfinite(a).all():
            problems.append(f"the {what} hold {counted(int((~np.isfinite(a)).sum()), 'NaN or infinite value')}")
    if problems:
        raise AutobonesError(f"{path}: the glb and its sidecars do not belong together: {'; '.join(problems)} "
                             "(save the rig again)")
