"""A studio's own ARKit shape set: a folder of posed meshes, read and stored as the packaged set is.

Goes beyond the seeds (issue #15). ``autobones build-rig BASE --landmarks FILE -o DIR --shapes FOLDER``
reads FOLDER (:func:`read_studio_shapes`) and writes it into ``DIR/arkit/`` in the packaged
format (:func:`write_shape_set`; :mod:`.shapes` reads it back), so ``transfer --rig DIR --arkit``
carries the studio's shapes instead of ICT-FaceKit's (:func:`rig_shapes_folder`).

The folder (the simplest thing a modelling tool exports)::

    neutral.obj                 the studio's neutral head (any frame and unit)
    neutral.landmarks.json      its contract landmarks (any format --landmarks reads; also neutral.pp
                                or neutral.pts), at least 6 names the heads' landmark files share
    jawOpen.obj, eyeBlinkLeft.obj, ...
                                one posed mesh per ARKit name (Left = the subject's left), the
                                neutral's vertices in the same order, moved as the shape at weight 1

Other files are ignored; ARKit names without a mesh are recorded as absent (their targets are
written all zero). Only the neutral's largest connected part (the skin) is kept, as for the
packaged set: separate eyeballs, teeth or lashes would be stuck onto the head's skin by the
correspondence.
"""
from __future__ import annotations

import difflib
import json
import os

import numpy as np

from ..errors import AutobonesError, counted
from ..geometry.topology import largest_part
from .names import ARKIT_NAMES
from .shapes import JSON, MIN_LANDMARKS, NPZ, ShapeSet, flipped_triangles

NEUTRAL = "neutral.obj"
LANDMARK_FILES = ("neutral.landmarks.json", "neutral.pp", "neutral.pts")
SUBFOLDER = "arkit"  # inside a rig folder
MOVES = 1e-7         # of the neutral's bounding-box diagonal: below it a vertex is stored as not moving


def read_studio_shapes(folder):
    """The :class:`ShapeSet` of a studio's shapes folder (module doc); AutobonesError, one line, when bad.

    Returns vertices (n, 3) and faces (m, 3) of the neutral's skin part, its landmarks, and per
    ARKit name given the displacement (n, 3) = posed - neutral, in the neutral's frame and units.
    """
    from ..io.landmarks import read_landmarks
    from ..io.obj import read_obj

    folder = os.fspath(folder)
    if not os.path.isdir(folder):
        raise AutobonesError(f"{folder}: no such shapes folder")
    files = sorted(f for f in os.listdir(folder) if f.lower().endswith(".obj") and f != NEUTRAL)
    if not os.path.isfile(os.path.join(folder, NEUTRAL)):
        raise AutobonesError(f"{folder}: no {NEUTRAL} (the neutral head the shapes are posed from)")
    unknown = [f[:-4] for f in files if f[:-4] not in ARKIT_NAMES]
    if unknown:
        hints = [f"{u} (did you mean {m[0]}?)" if (m := difflib.get_close_matches(u, ARKIT_NAMES, 1)) else u
                 for u in unknown]
        raise AutobonesError(f"{folder}: unknown ARKit shape name(s): {', '.join(hints)}; each posed mesh is "
                             "named <arkitName>.obj, e.g. jawOpen.obj, eyeBlinkLeft.obj")
    if not files:
        raise AutobonesError(f"{folder}: no posed meshes beside {NEUTRAL} (one <arkitName>.obj per shape)")
    marks = [f for f in LANDMARK_FILES if os.path.isfile(os.path.join(folder, f))]
    if len(marks) != 1:
        raise AutobonesError(f"{folder}: {'no' if not marks else 'more than one'} landmark file for the neutral "
                             f"(exactly one of {', '.join(LANDMARK_FILES)})")
    V, F = read_obj(os.path.join(folder, NEUTRAL))
    landmarks = read_landmarks(os.path.join(folder, marks[0]))
    if len(landmarks) < MIN_LANDMARKS:
        raise AutobonesError(f"{os.path.join(folder, marks[0])}: {counted(len(landmarks), 'landmark')}; the shapes need at "
                             f"least {MIN_LANDMARKS} contract names shared with the heads")
    posed, bad = {}, []
    for f in files:
        P, _ = read_obj(os.path.join(folder, f))
        if P.shape != V.shape:
            bad.append(f"{f} has {len(P)}")
        posed[f[:-4]] = P
    if bad:
        raise AutobonesError(f"{folder}: vertex count differs from {NEUTRAL}'s {len(V)}: {', '.join(bad)} "
                             "(posed meshes keep the neutral's vertices, in order)")
    Vs, Fs, skin = largest_part(V, F)
    deltas = {n: (posed[n] - V)[skin].astype(np.float32).astype(np.float64) for n in ARKIT_NAMES if n in posed}
    given = [n for n in ARKIT_NAMES if n in deltas]
    meta = {
        "format": "autobones-arkit-shapes/1",
        "source": f"a studio's own shape set ({os.path.abspath(folder)}; autobones build-rig --shapes)",
        "license": "the studio's own",
        "units": "the neutral's own", "frame": "the neutral's own",
        "left_right": "ARKit's Left is the subject's own left",
        "names": list(ARKIT_NAMES), "absent": [n for n in ARKIT_NAMES if n not in deltas],
        "given": given, "skin_index_of": NEUTRAL,
        "storage": f"float32 displacements of vertices moving more than {MOVES:g} of the neutral's size",
        "source_flipped_triangles": flipped_triangles(Vs, Fs, {n: deltas[n] for n in given}),
        "landmarks": {k: [float(x) for x in v] for k, v in landmarks.items()},
        "vertex_count": int(len(Vs)), "triangle_count": int(len(Fs)),
    }
    return ShapeSet(Vs, Fs, {k: np.asarray(v, dtype=np.float64) for k, v in landmarks.items()}, deltas, meta)


def write_shape_set(shapes, rig_folder):
    """Write ``shapes`` into ``rig_folder/arkit/`` in the packaged format (:mod:`.shapes`), atomically.

    ``ict_arkit.npz``: ``vertices`` (n, 3) float32, ``faces`` (m, 3) int32, and per given name
    ``shape/<name>/index`` (k,) uint32 and ``shape/<name>/delta`` (k, 3) float32; ``ict_arkit.json``:
    the set's ``meta``. Returns the folder written.
    """
    from ..io.atomic import replace_all, temp_beside

    out = os.path.join(os.fspath(rig_folder), SUBFOLDER)
    os.makedirs(out, exist_ok=True)
    V = np.asarray(shapes.vertices, dtype=np.float64)
    tol = MOVES * float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    arrays = {"vertices": V.astype(np.float32), "faces": np.asarray(shapes.faces, dtype=np.int32)}
    moving = {}
    for name in ARKIT_NAMES:
        if name in shapes.deltas:
            D = np.asarray(shapes.deltas[name], dtype=np.float64)
            idx = np.flatnonzero(np.linalg.norm(D, axis=1) > tol)
            arrays[f"shape/{name}/index"] = idx.astype(np.uint32)
            arrays[f"shape/{name}/delta"] = D[idx].astype(np.float32)
            moving[name] = int(len(idx))
    meta = dict(shapes.meta, moving_vertices=moving)
    staged = []
    try:
        fd, tmp = temp_beside(os.path.join(out, NPZ), suffix=".npz")
        staged.append((tmp, os.path.join(out, NPZ)))
        with os.fdopen(fd, "wb") as fh:
            np.savez_compressed(fh, **arrays)
        fd, tmp = temp_beside(os.path.join(out, JSON))
        staged.append((tmp, os.path.join(out, JSON)))
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            json.dump(meta, fh, indent=1)
    except OSError as exc:
        for tmp, _ in staged:
            if os.path.exists(tmp):
                os.remove(tmp)
        raise AutobonesError(f"{out}: cannot write the shape set ({exc.strerror or exc})") from None
    replace_all(staged, "the ARKit shape set")
    return out


def rig_shapes_folder(rig_option):
    """``DIR/arkit`` when ``rig_option`` (a transfer's ``--rig``, ``rig.options['rig']``) is a rig folder
    holding a shape set written by :func:`write_shape_set`, else None (the packaged ICT-FaceKit set)."""
    if not isinstance(rig_option, (str, os.PathLike)) or not os.path.isdir(rig_option):
        return None
    folder = os.path.join(os.fspath(rig_option), SUBFOLDER)
    return folder if os.path.isfile(os.path.join(folder, NPZ)) else None
