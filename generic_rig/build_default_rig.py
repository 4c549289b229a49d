"""Build the generic rig on the default head: ``generic_rig/default/`` and ``gallery/generic_rig.png``.

The generic rig's layers of Orvalho, Zacur & Susin 2008 (§2). Everything is regenerated from the
committed ``default_head.obj`` and ``default_head.landmarks.json`` (run
``place_default_landmarks.py`` first when the head changed) with
:func:`autobones.rig_building.build.build_rig` and ``muscles.json``.

Run ``python generic_rig/build_default_rig.py``.
"""
from __future__ import annotations

import argparse
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

from autobones.rig_building.build import REGIONS, build_rig  # noqa: E402
from autobones.io.landmarks import read_landmarks  # noqa: E402
from autobones.io.mesh import load_mesh  # noqa: E402

MESH = os.path.join(HERE, "default_head.obj")
LANDMARKS = os.path.join(HERE, "default_head.landmarks.json")
OUT = os.path.join(HERE, "default")
PICTURE = os.path.join(ROOT, "gallery", "generic_rig.png")

REGION_COLORS = np.array([
    (0.80, 0.80, 0.80),  # scalp
    (0.95, 0.85, 0.55),  # forehead
    (0.55, 0.35, 0.20),  # brow
    (0.30, 0.55, 0.95),  # eyelids
    (0.95, 0.55, 0.20),  # nose
    (0.95, 0.65, 0.70),  # cheeks
    (0.85, 0.10, 0.20),  # lips
    (0.45, 0.80, 0.35),  # chin
    (0.20, 0.60, 0.50),  # jaw
    (0.70, 0.45, 0.85),  # ears
    (0.60, 0.70, 0.90),  # neck
])
BONE_COLOR = (20, 20, 230)
MUSCLE_COLOR = (200, 0, 0)


def jaw_colors(w):
    w = np.clip(np.asarray(w, dtype=float), 0, 1)[:, None]
    return (1 - w) * np.array([0.85, 0.85, 0.85]) + w * np.array([0.1, 0.75, 0.2])


def render(rig, path):
    from autobones.render import muscle_segments, render_views, save_png

    V, F = rig.vertices, rig.faces
    segs = [rig.skeleton.segments]
    cols = [np.tile(BONE_COLOR, (len(rig.skeleton), 1))]
    M = muscle_segments(rig.muscles)            # the default head's own frame is canonical
    segs.append(M)
    cols.append(np.tile(MUSCLE_COLOR, (len(M), 1)))
    S = np.concatenate(segs)
    C = np.concatenate(cols)
    joints = np.concatenate([rig.skeleton.heads])
    top = render_views(V, F, jaw_colors(rig.fields["jaw_weight"]), views=("front", "side"), size=(640, 640),
                       segments=S, segment_color=C, points=joints, point_labels=rig.skeleton.names,
                       point_color=BONE_COLOR)
    reg = rig.fields["region"]
    # one label per region at the vertex nearest the region's (front-most half) centroid
    pts, names = [], []
    for i, name in enumerate(REGIONS):
        idx = np.flatnonzero(reg == i)
        if len(idx) == 0:
            continue
        sub = idx[V[idx, 0] >= -1e-9] if (V[idx, 0] >= -1e-9).any() else idx
        c = V[sub].mean(axis=0)
        pts.append(V[sub[np.argmin(np.linalg.norm(V[sub] - c, axis=1))]])
        names.append(name)
    bottom = render_views(V, F, REGION_COLORS[reg], views=("front", "side"), size=(640, 640),
                          points=np.array(pts), point_labels=names, point_color=(0, 0, 0))
    save_png(path, np.concatenate([top, bottom], axis=0))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=OUT)
    ap.add_argument("--picture", default=PICTURE)
    args = ap.parse_args(argv)
    V, F = load_mesh(MESH)
    lm = read_landmarks(LANDMARKS)
    rig = build_rig(V, F, lm)
    rig.units = "metres"
    rig.frame = "+Y up, +Z front (the head looks along +Z), +X subject's left; origin: x=0 midline, y=0 menton height"
    rig.save(args.out)
    if args.picture:
        render(rig, args.picture)
    return 0


if __name__ == "__main__":
    sys.exit(main())
