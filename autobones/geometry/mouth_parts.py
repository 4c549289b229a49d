"""The mouth's separate inner parts (teeth, gums, tongue): which ride the jaw, which the skull.

One rule for the expression model's jaw (:mod:`autobones.expressions.model`) and ``transfer``'s exported
weights (:mod:`autobones.rig_transfer.mouth_parts`), so the two agree; its lengths (:data:`MOUTH_PARTS`)
are the model's defaults, which ``generic_rig/expressions.json`` may override for the model.

They are carried by the mandible below the occlusal plane and by the skull above it (taken level
through the stomion): a small part (a tooth) rides one bone by its centre; a large one (gums with
the tongue) splits vertex by vertex over a narrow band at the crowns of the lower teeth, when
there are any (the lower gums and the tongue lie within the lower dental arch, up to its crowns),
and behind the jaw joint stays with the skull (the pharynx).

Canonical frame (+Y up, +Z front), head sizes; ``fu`` is the face unit in head sizes; the
definitions' lengths are in fu.
"""
from __future__ import annotations

import numpy as np

from .smooth import ramp

# fu: a part centred within ``reach`` of the stomion (and not in front of it) is inside the mouth; up to
# ``rigid_size`` across it goes whole; larger ones split over +-``band`` at the lower crowns; the pharynx is
# held from ``pharynx`` behind the jaw joint
MOUTH_PARTS = {"reach": 0.9, "band": 0.03, "rigid_size": 0.5, "pharynx": 0.1}


def inner_mouth_parts(V, part, candidates, stomion, fu, reach, rigid_size):
    """The separate parts inside the mouth.

    ``V`` (n, 3); ``part`` (n,) int connected part per vertex; ``candidates`` (n,) bool the
    vertices that may belong to one (not skin, not eyes, not lid attachments); ``stomion`` (3,);
    ``reach`` and ``rigid_size`` in fu. A part is inside the mouth when its centre lies within
    ``reach`` of the stomion and not in front of it.

    Returns a list of ``(rows (p,) int64, centre (3,) float, small bool)``: small parts (up to
    ``rigid_size`` across) move whole.
    """
    found = []
    for p_ in np.unique(part[candidates]):
        rows = np.flatnonzero((part == p_) & candidates)
        cen = V[rows].mean(axis=0)
        if np.linalg.norm(cen - stomion) <= float(reach) * fu and cen[2] <= stomion[2]:
            found.append((rows, cen, np.ptp(V[rows], axis=0).max() <= float(rigid_size) * fu))
    return found


def mouth_part_weights(W, j, head, V, found, stomion, jaw_pivot, fu, band, pharynx):
    """Skin weights (n, b) with the inner mouth parts split between jaw and skull (a new array).

    Parameters
    ----------
    W : (n, b) float
        Skin weights (the jaw column already sharpened).
    j, head : int, int or None
        Columns of the jaw and the head bone.
    V : (n, 3) float
        Vertices.
    found : list
        :func:`inner_mouth_parts`.
    stomion, jaw_pivot : (3,) float
        The stomion and the jaw joint.
    fu : float
        Face unit.
    band, pharynx : float
        fu: half width of the split at the lower crowns; the pharynx is held fully from
        ``pharynx`` behind the jaw joint and free from twice that in front (a sharper step turns
        the tongue's triangles over at the joint as the jaw opens).

    Returns
    -------
    W : (n, b) float
    rows : (p,) int64
        The vertices of the inner mouth parts, sorted.
    """
    W = W.copy()
    st = stomion
    # (a lower crown stands at most a little above the lips' line: a small part reaching
    # higher is not a lower tooth)
    tops = [V[rows, 1].max() - st[1] for rows, cen, sm in found if sm and cen[1] < st[1]]
    level = st[1] + max([t_ for t_ in tops if t_ <= 0.1 * fu], default=0.0)
    band = float(band) * fu
    ph = float(pharynx) * fu
    front = ramp(V[:, 2] - jaw_pivot[2], -ph, 2.0 * ph)
    inner = np.zeros(0, dtype=np.int64)
    for rows, cen, sm in found:
        y = np.full(len(rows), cen[1] - st[1]) if sm else V[rows, 1] - level
        jw = ramp(y, band, -band) * front[rows]
        W[rows] = 0.0
        W[rows, j] = jw
        if head is not None:
            W[rows, head] = 1.0 - jw
        inner = np.union1d(inner, rows)
    return W, inner
