"""Build generic_rig/arkit/ (the ARKit source shapes) from ICT-FaceKit in ../shared/data/ict.

Run from the project root: ``python generic_rig/build_arkit_shapes.py [ICT_FOLDER]``.

Writes, beside ICT-FaceKit's MIT LICENSE:

- ``ict_arkit.npz``: ICT's neutral skin (its largest connected part: face, scalp, neck,
  lids and lips; ICT's own vertex order kept through ``skin_index``) as ``vertices``
  (n, 3) float32 in ICT's centimetres, +Y up, +Z front, +X the subject's left, and
  ``faces`` (m, 3) int32; for each of the 51 ARKit shapes ICT has, ``shape/<name>/index``
  (k,) uint16 (the skin vertices that move by more than ``MOVES`` cm) and
  ``shape/<name>/delta`` (k, 3) float16 displacements (cm). ``browInnerUp`` and
  ``cheekPuff`` are the sums of ICT's L and R halves. ICT's eyeLook* shapes move the lids
  and the eye-surface shells but not the eyeballs (those turn by ICT's eye joints), so
  no eyeball turn is taken from them (see autobones/arkit/targets.py).
- ``ict_identity.npz``: ICT's 20 identity modes (principal components of its identities, each
  scaled to one standard deviation) on the same skin vertices, ``modes`` (20, n, 3) float16 cm: the
  expression fit solves them with the expression so a head's own shape is not taken for one
  (:mod:`autobones.rig_transfer.expression_prior`).
- ``ict_arkit.json``: the names, the 27 contract landmarks of the neutral head, the
  storage error, the source and licence.
"""
from __future__ import annotations

import json
import os
import shutil
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from autobones.arkit.names import ABSENT, ARKIT_NAMES, ict_names  # noqa: E402
from autobones.arkit.shapes import flipped_triangles  # noqa: E402
from autobones.geometry.topology import largest_part  # noqa: E402
from autobones.io.obj import read_obj  # noqa: E402

OUT = os.path.join(ROOT, "generic_rig", "arkit")
MOVES = 1e-4  # cm: 1 micrometre; below it a vertex is stored as not moving


def main(ict=os.path.join(ROOT, "..", "shared", "data", "ict")):
    V, F = read_obj(os.path.join(ict, "generic_neutral_mesh.obj"))
    _, Fs, skin = largest_part(V, F)
    with np.load(os.path.join(ict, "ict_facekit_shapes.npz")) as z:
        neutral = z["neutral"]
        expr = {k[len("expression/"):]: z[k].astype(np.float64) for k in z.files if k.startswith("expression/")}
    assert np.allclose(neutral, V, atol=1e-5), "the npz neutral is not generic_neutral_mesh.obj"
    with open(os.path.join(ict, "generic_neutral_mesh.landmarks.json")) as fh:
        landmarks = json.load(fh)["landmarks"]

    arrays = {"vertices": V[skin].astype(np.float32), "faces": Fs.astype(np.int32),
              "skin_index": skin.astype(np.int32)}
    worst, counts, folds = 0.0, {}, {}
    for name in ARKIT_NAMES:
        if name in ABSENT:
            continue
        D = sum(expr[i] for i in ict_names(name))
        Ds = D[skin]
        idx = np.flatnonzero(np.linalg.norm(Ds, axis=1) > MOVES)
        d16 = Ds[idx].astype(np.float16)
        arrays[f"shape/{name}/index"] = idx.astype(np.uint16)
        arrays[f"shape/{name}/delta"] = d16
        counts[name] = int(len(idx))
        stored = np.zeros_like(Ds)
        stored[idx] = d16
        # ICT's own shapes fold some triangles at weight 1 (mouthClose is meant on top of jawOpen)
        folds.update(flipped_triangles(V[skin], Fs, {name: stored}))
        worst = max(worst, float(np.abs(d16.astype(np.float64) - Ds[idx]).max()))
    assert len(Fs) < 2 ** 31 and len(skin) < 2 ** 16
    os.makedirs(OUT, exist_ok=True)
    np.savez_compressed(os.path.join(OUT, "ict_arkit.npz"), **arrays)
    meta = {
        "format": "autobones-arkit-shapes/1",
        "source": "ICT-FaceKit (USC Institute for Creative Technologies), generic_neutral_mesh and its "
                  "expression shapes; https://github.com/ICT-VGL/ICT-FaceKit",
        "license": "MIT (LICENSE beside this file)",
        "units": "cm", "frame": "+X subject's left, +Y up, +Z front",
        "left_right": "ARKit's Left and ICT's _L are the subject's own left (+X)",
        "names": list(ARKIT_NAMES), "absent": list(ABSENT),
        "combined": {"browInnerUp": ["browInnerUp_L", "browInnerUp_R"], "cheekPuff": ["cheekPuff_L", "cheekPuff_R"]},
        "moving_vertices": counts, "storage": "float16 displacements of vertices moving more than 1e-4 cm",
        "storage_max_error_cm": worst, "source_flipped_triangles": folds, "landmarks": landmarks,
        "vertex_count": int(len(skin)), "triangle_count": int(len(Fs)),
    }
    with open(os.path.join(OUT, "ict_arkit.json"), "w") as fh:
        json.dump(meta, fh, indent=1)
    shutil.copyfile(os.path.join(ict, "LICENSE"), os.path.join(OUT, "LICENSE"))
    size = sum(os.path.getsize(os.path.join(OUT, f)) for f in os.listdir(OUT))
    write_identity(ict)
    print(f"{OUT}: {len(skin)} skin vertices, {len(Fs)} triangles, {len(counts)} shapes "
          f"(+ {', '.join(ABSENT)} absent), float16 error <= {worst:.2e} cm, {size / 1e6:.2f} MB")


def write_identity(ict=os.path.join(ROOT, "..", "shared", "data", "ict")):
    """``ict_identity.npz`` (module doc) beside the shapes; returns its path."""
    with np.load(os.path.join(OUT, "ict_arkit.npz")) as z:
        skin = z["skin_index"].astype(np.int64)
    with np.load(os.path.join(ict, "ict_facekit_shapes.npz")) as z:
        names = sorted(k for k in z.files if k.startswith("identity/"))
        modes = np.stack([z[k][skin] for k in names]).astype(np.float16)
    path = os.path.join(OUT, "ict_identity.npz")
    np.savez_compressed(path, modes=modes)
    return path


if __name__ == "__main__":
    main(*sys.argv[1:])
