"""``transfer_teeth_jaw_open.png``: a transferred head's teeth and mouth bag with the jaw opened (issue #31
check 2, ``autobones/rig_transfer/mouth_parts.py``).

    python gallery/make_gallery.py --only transfer_teeth_jaw_open

ICT identity001 transferred with its landmark file, its jaw bone turned 23 degrees open (what ICT's own
jawOpen does to its lower teeth) by linear blend skinning with the rig's own weights, what a glTF player
does; only the separate parts inside the mouth are drawn (32 teeth and the mouth bag; the skin, eyes and
lashes hidden), tinted green by their jaw weight. Top row: the jaw repair's field alone (before
``mouth_parts``): the lower teeth pale (jaw 0-0.5), the molars stretched between the arches. Bottom row: now, each
tooth whole on the jaw or the skull, the bag split between them.
"""
from __future__ import annotations

from pathlib import Path
from unittest import mock

import numpy as np

import autobones
from autobones import render
from autobones.geometry.topology import mesh_parts
from autobones.io.landmarks import read_landmarks
from autobones.io.mesh import load_mesh
from autobones.rig_transfer import pipeline

HERE = Path(__file__).resolve().parent
ICT = HERE.parent.parent / "shared" / "data" / "ict"


def opened_jaw(rig, degrees):
    """(canonical vertices, opened canonical vertices, jaw weight (n, 1), canonical jaw joint (3,)) of
    ``rig`` with its jaw bone turned ``degrees`` open about the left-right axis (chin down) by linear
    blend skinning, what a glTF player does (``jaw_open_goat_robot`` uses it too)."""
    j = rig.skeleton.names.index("jaw")
    jaw = rig.weights[:, j][:, None]
    C = rig.frame.to_canonical(rig.vertices)
    pivot = rig.frame.to_canonical(rig.skeleton.heads[[j]])[0]
    t = np.radians(degrees)
    R = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(t), -np.sin(t)], [0.0, np.sin(t), np.cos(t)]])
    return C, C + jaw * ((C - pivot) @ R.T + pivot - C), jaw, pivot


def teeth_picture(out, degrees=23.0, size=420):
    """``transfer_teeth_jaw_open.png`` in the folder ``out``."""
    V, F = load_mesh(ICT / "identity001.obj")[:2]
    lm = read_landmarks(ICT / "identity001.landmarks.json")
    part = mesh_parts(len(V), F)
    inner = F[np.isin(part[F[:, 0]], np.arange(1, 34))]   # ICT's mouth bag (1) and its 32 teeth (2-33)
    off = lambda V, F, W, *a, **k: (np.array(W), None)  # noqa: E731
    with mock.patch.object(pipeline, "carried_mouth_parts", off), mock.patch.object(pipeline, "rigid_mouth_parts", off):
        before = autobones.transfer((V, F), lm)
    after = autobones.transfer((V, F), lm)
    rows = []
    for rig in (before, after):
        C, opened, jaw, _ = opened_jaw(rig, degrees)
        colours = np.array([0.85, 0.85, 0.85]) * (1 - jaw) + np.array([0.15, 0.75, 0.2]) * jaw
        keep = np.unique(inner)   # framed on the mouth's parts alone
        remap = np.zeros(len(V), dtype=np.int64)
        remap[keep] = np.arange(len(keep))
        rows.append(render.render_views(opened[keep], remap[inner], vertex_colors=colours[keep],
                                        views=("front", "three_quarter", "side"), size=(size, size)))
    path = Path(out) / "transfer_teeth_jaw_open.png"
    render.save_png(path, np.concatenate(rows, axis=0))
    print(f"{path}: ICT identity001's teeth and mouth bag, jaw opened {degrees:g} degrees; before, after")
