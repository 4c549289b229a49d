"""Regenerate the gallery pictures from real autobones results.

    python gallery/make_gallery.py            # all pictures into gallery/
    python gallery/make_gallery.py --only ict_neutral

Each picture is a rig made by ``autobones.place`` right now (no cached data),
rendered by ``autobones.render`` from the front, three-quarter and side views in
the head's detected canonical frame: skin coloured by the skin weights (each
bone a colour, blended by weight), bones drawn as segments with their heads as
dots; a second row shows the face / middle / back depth groups and the facial
mask (seed 003 fig. 1).
"""
from __future__ import annotations

import argparse
import colorsys
from pathlib import Path

import numpy as np

import autobones
from autobones import render

HERE = Path(__file__).resolve().parent
DATA = HERE.parent.parent / "shared" / "data"

HEADS = {
    "default_head": (None, "dense"),
    "ict_neutral": ("ict/generic_neutral_mesh.obj", "dense"),
    "lee_perry_smith": ("misc/LeePerrySmith.obj", "medium"),
    "demosthenes": ("misc/demosthenes-low-res.obj", "medium"),
    "goat": ("misc/goathead.obj", "sparse"),
    "robot": ("misc/robot_head_neutral.obj", "sparse"),
}


def bone_colours(n):
    """(n, 3) distinct colours in [0, 1], golden-ratio hues."""
    return np.array([colorsys.hsv_to_rgb((0.13 + i * 0.618034) % 1.0, 0.65, 0.95) for i in range(n)])


def rig_picture(rig, size=420):
    C = rig.frame.to_canonical(rig.vertices)
    H = rig.frame.to_canonical(rig.skeleton.heads)
    T = rig.frame.to_canonical(rig.skeleton.tails)
    views = ("front", "three_quarter", "side")
    skin = rig.weights @ bone_colours(len(rig.skeleton))
    top = render.render_views(C, rig.faces, vertex_colors=skin, views=views, size=(size, size),
                              points=H, segments=np.stack([H, T], axis=1), point_color=(20, 20, 20),
                              segment_color=(20, 20, 20))
    groups = np.array([[0.9, 0.3, 0.3], [0.35, 0.75, 0.35], [0.35, 0.45, 0.9]])[rig.labels]
    groups[~rig.facial_mask & (rig.labels == 0)] = [0.85, 0.6, 0.85]  # face group below the chin (neck)
    bottom = render.render_views(C, rig.faces, vertex_colors=groups, views=views, size=(size, size))
    return np.concatenate([top, bottom], axis=0)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", nargs="*", choices=sorted(HEADS))
    ap.add_argument("--out", default=str(HERE))
    args = ap.parse_args(argv)
    for name in args.only or HEADS:
        rel, density = HEADS[name]
        rig = autobones.place(None if rel is None else DATA / rel, density=density)
        path = Path(args.out) / f"place_{name}.png"
        render.save_png(path, rig_picture(rig))
        print(f"{path}: {len(rig.skeleton)} bones, up {rig.frame.up}, front {rig.frame.front}")


if __name__ == "__main__":
    main()
