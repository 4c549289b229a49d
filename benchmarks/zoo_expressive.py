"""Expressive heads for the zoo: ICT identity000 wearing real ICT-FaceKit expressions, with its landmarks.

ICT-FaceKit is linear: identity k with expression E at weight w is ``neutral + identity_k + w E``
(``../shared/data/README.md``), and every shape shares one vertex list, so the identity's hand-checked
landmarks ride on the expression by their barycentric coordinates on the neutral identity's triangles.
The heads are written once into a cache folder (OBJ + contract landmark JSON) so the zoo reads them as
it reads any head: the checks need no ground truth beyond those landmarks.
"""
from __future__ import annotations

import json
import tempfile
import zlib
from pathlib import Path

import numpy as np

from autobones.geometry.closest import closest_points
from autobones.io.atomic import write_text_atomic
from autobones.io.landmarks import read_landmarks
from autobones.io.mesh import load_mesh

# name -> {ICT expression: weight}; strong, whole-face expressions a scan may be taken in
EXPRESSIONS = {
    "jawopen": {"jawOpen": 1.0},
    "smile": {"mouthSmile_L": 1.0, "mouthSmile_R": 1.0, "cheekSquint_L": 0.5, "cheekSquint_R": 0.5},
    "surprise": {"browInnerUp_L": 1.0, "browInnerUp_R": 1.0, "browOuterUp_L": 1.0, "browOuterUp_R": 1.0,
                 "eyeWide_L": 1.0, "eyeWide_R": 1.0, "jawOpen": 0.6},
    "pucker": {"mouthPucker": 1.0, "mouthFunnel": 0.5},
    "blink": {"eyeBlink_L": 1.0, "eyeBlink_R": 1.0},
}
IDENTITY = "identity000"


def expressive_heads(data):
    """name -> (mesh path, landmark path) of ``IDENTITY`` in each of :data:`EXPRESSIONS`, written under
    the system's temporary folder; {} when ``data`` has no ICT shape set."""
    shapes, mesh, marks = (data / "ict" / n for n in ("ict_facekit_shapes.npz", f"{IDENTITY}.obj",
                                                      f"{IDENTITY}.landmarks.json"))
    if not (shapes.is_file() and mesh.is_file() and marks.is_file()):
        return {}
    # named by what is in it: a changed expression list is written afresh
    folder = Path(tempfile.gettempdir()) / f"autobones_zoo_expressive_{zlib.crc32(repr(EXPRESSIONS).encode()):08x}"
    out = {f"{IDENTITY}_{e}": (folder / f"{IDENTITY}_{e}.obj", folder / f"{IDENTITY}_{e}.landmarks.json")
           for e in EXPRESSIONS}
    if all(m.is_file() and lm.is_file() for m, lm in out.values()):
        return out
    folder.mkdir(exist_ok=True)
    V, F = load_mesh(mesh)
    lm = read_landmarks(marks)
    names = list(lm)
    _, face, bary = closest_points(np.array([lm[n] for n in names], dtype=np.float64), V, F)[:3]
    with np.load(shapes) as z:
        for e, weights in EXPRESSIONS.items():
            Ve = V + sum(w * z[f"expression/{k}"].astype(np.float64) for k, w in weights.items())
            P = np.einsum("ij,ijk->ik", bary, Ve[F[face]])
            m, lmp = out[f"{IDENTITY}_{e}"]
            text = "".join(f"v {x:.9g} {y:.9g} {w:.9g}\n" for x, y, w in Ve)
            text += "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F)
            write_text_atomic(m, text)   # whole or not at all: a half file would pass for written next run
            write_text_atomic(lmp, json.dumps({"format": "autobones-landmarks/1",
                                               "landmarks": {n: p.tolist() for n, p in zip(names, P)}}, indent=1))
    return out
