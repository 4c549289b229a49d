"""``place_head_turn.png`` and ``transfer_head_turn.png``: a rig's head bone turned (issues #31, #32).

    python gallery/make_gallery.py --only place_head_turn transfer_head_turn

Each head rigged (``place --density dense``; ``transfer`` with its landmark file), its head bone and the
bones under it turned about the up axis through the head joint by linear blend skinning with the rig's
own weights; front, three-quarter and side views of the turned head, tinted orange by how far each vertex
moved (relative to the largest motion), each row labelled with the largest motion of the neck base (its
lowest 5 % of the height; for ``transfer`` in its landmarks' anatomical frame) relative to the peak. The
face, jaw and skull should turn as one, the neck twist, its base stay. ``transfer`` is turned further
(30 degrees) so the jaw's lower border shows: before the boundary passed under the jaw's angle
(``autobones/geometry/head_share.py``), the jaw folded along it.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

import autobones
from autobones import render
from autobones.rig_transfer.neck import anatomical_axes

HERE = Path(__file__).resolve().parent
DATA = HERE.parent.parent / "shared" / "data"

# label -> mesh under ../shared/data (None: the built-in head). ICT's face is far denser than its neck (its
# lowest 5% of vertices reach above the chin) and the SMPL woman's neck is cut close under her chin: both left
# their chins behind before the face's share rose to the chin (geometry/head_share.py)
PLACE_HEADS = {"default head": None, "Lee Perry-Smith": "misc/LeePerrySmith.obj",
               "ICT identity000": "ict/identity000.obj", "SMPL woman": "zoo/human_woman.obj"}
# label -> (mesh, landmark file: under tests/ in the project, else under ../shared/data)
TRANSFER_HEADS = {"ICT identity000": ("ict/identity000.obj", "ict/identity000.landmarks.json"),
                  "SMPL woman": ("zoo/human_woman.obj", "zoo/human_woman.landmarks.json"),
                  "Lee Perry-Smith": ("misc/LeePerrySmith.obj", "tests/landmarks/LeePerrySmith.landmarks.json"),
                  "cow": ("zoo/cowHead.obj", "tests/landmarks/cowHead.landmarks.json")}


def _rigs(command):
    """(label, rig) of each head the picture shows."""
    if command == "place":
        for label, rel in PLACE_HEADS.items():
            yield label, autobones.place(None if rel is None else DATA / rel, density="dense")
        return
    for label, (mesh, marks) in TRANSFER_HEADS.items():
        marks = HERE.parent / marks if marks.startswith("tests/") else DATA / marks
        yield label, autobones.transfer(DATA / mesh, marks)


def _axes(rig):
    """(3, 3) rows left, up, front of the head's frame: the rig's own, or for a rig with landmarks
    (``transfer``'s) their anatomical frame, which ``transfer``'s neck step works in (the cow's rig frame
    leans 39 degrees with its snout: its "lowest" vertices are its chin)."""
    if not rig.landmarks:
        return rig.frame.rotation
    return anatomical_axes(rig.vertices, rig.faces, rig.landmarks, rig.frame.rotation)


def _row(label, rig, degrees, size):
    """One head's three views, turned (``Rig.turn_bones``); and its neck base's motion over the peak."""
    axes = _axes(rig)
    canonical = lambda P: (np.asarray(P, dtype=np.float64) - rig.frame.origin) @ axes.T / rig.frame.size  # noqa: E731
    C = canonical(rig.vertices)
    pivot = canonical(rig.skeleton.heads[[rig.skeleton.names.index("head")]])[0]
    turned = canonical(rig.turn_bones(head_deg=(0.0, degrees, 0.0), axes=axes))
    motion = np.linalg.norm(turned - C, axis=1)
    a = (motion / motion.max())[:, None] ** 0.7
    colours = (1 - a) * np.array([0.85, 0.85, 0.85]) + a * np.array([1.0, 0.45, 0.1])
    bottom = C[:, 1].min()
    base = motion[C[:, 1] <= bottom + 0.05 * (pivot[1] - bottom)].max() / motion.max()
    note = f"{label}: neck base {base:.1%} of peak"
    mark = np.array([[C[:, 0].min(), bottom - 0.04, C[:, 2].max()]])
    img = np.concatenate([
        render.render_views(turned, rig.faces, vertex_colors=colours, views=(view,), size=(size, size),
                            points=np.vstack([pivot[None], mark]) if k == 0 else pivot[None],
                            point_labels=["joint", note] if k == 0 else ["joint"], point_color=(40, 40, 40))
        for k, view in enumerate(("front", "three_quarter", "side"))], axis=1)
    print(f"{label}: peak {motion.max():.3g} head sizes, neck base {base:.2%} of it")
    return img


def head_turn_picture(out, command="place", degrees=None, size=360):
    """``{command}_head_turn.png`` in the folder ``out``: every head of the command's table, one row each,
    its head turned ``degrees`` (default 15 for ``place``, 30 for ``transfer``)."""
    degrees = (15.0 if command == "place" else 30.0) if degrees is None else degrees
    rows = [_row(label, rig, degrees, size) for label, rig in _rigs(command)]
    path = Path(out) / f"{command}_head_turn.png"
    render.save_png(path, np.concatenate(rows, axis=0))
    heads = PLACE_HEADS if command == "place" else TRANSFER_HEADS
    print(f"{path}: {', '.join(heads)}, head turned {degrees:g} degrees")
