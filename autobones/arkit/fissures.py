"""The openings of a one-surface head that a carried shape must be free to part: the triangles inside
each eye's opening and across the lip line, and how a displacement moves the lips (all in the
head's own frame and units; the canonical frame from ``frame``)."""
from __future__ import annotations

import numpy as np

from ..geometry.normals import triangle_normals
from .lids import eye_sides, margin_points

# the eye opening of a one-surface head: the landmarks' quadrilateral grown about its centre
FISSURE_GROWTH = 1.3
# the lip line (:func:`mouth_fissure`): its two ends and middle, then the lips' middles
MOUTH = ("cheilion_r", "stomion", "cheilion_l", "labiale_superius", "labiale_inferius")


def eye_fissures(V, F, landmarks, frame, growth=None):
    """Triangles of a one-surface head inside each eye's opening: (m,) bool.

    The opening is the outline of the two lid margins (:func:`autobones.arkit.lids.margin_points`,
    the curves through ``endocanthion``, ``palpebrale_superius|inferius`` and ``exocanthion``)
    seen from the front in the head's canonical frame, grown by ``growth`` about its centre
    (None: :data:`FISSURE_GROWTH`); a triangle is in it when its centroid is, its normal faces
    forward and it lies within a fissure length of the landmarks in depth. On a scan the eye
    surface there is one with the lids: held rigid it would keep the lids apart in a blink.
    """
    growth = FISSURE_GROWTH if growth is None else growth
    C = frame.to_canonical(np.asarray(V, dtype=np.float64)[F].mean(axis=1))
    n = triangle_normals(V, F) @ np.asarray(frame.rotation, dtype=np.float64).T
    out = np.zeros(len(F), dtype=bool)
    for side in eye_sides(landmarks):
        ends = [np.asarray(landmarks[f"{k}_{side}"], dtype=np.float64) for k in ("endocanthion", "exocanthion")]
        up, lo = margin_points(landmarks, side, np.linspace(0.0, 1.0, 18)[1:-1])
        Q = frame.to_canonical(np.vstack([ends[0], up, ends[1], lo[::-1]]))
        fissure = np.linalg.norm(ends[1] - ends[0]) / frame.size
        mid = Q[:, :2].mean(axis=0)
        inside = _in_polygon(C[:, :2], mid + growth * (Q[:, :2] - mid))
        out |= inside & (n[:, 2] > 0.3) & (np.abs(C[:, 2] - Q[:, 2].mean()) < fissure)
    return out


def mouth_fissure(V, F, landmarks, frame, names=MOUTH):
    """Triangles across a head's lip line: (m,) bool (all False without the landmarks or where the mouth is open).

    The lip line is the curve through ``cheilion_r``, ``stomion`` and ``cheilion_l`` (a quadratic
    in the canonical left-right coordinate, for height and depth); a triangle is across it when
    its corners lie on both sides in height, between the mouth corners, and within a lip's
    height (``labiale_superius`` to ``labiale_inferius``) of it in depth. On a closed-mouth scan
    these are the only triangles joining the upper lip to the lower one: held as they are they
    tie the lips together, and jawOpen moved the menpo3d james scan's upper lip about as far as
    its lower one (0.29 and 0.37 mouth widths; ICT's own 0.05 and 0.80); set free, 0.09 and 0.60
    (``benchmarks/arkit.py --lips``).
    """
    if not all(n in landmarks for n in names):
        return np.zeros(len(F), dtype=bool)
    r, st, l, up, lo = (frame.to_canonical(np.asarray(landmarks[n], dtype=np.float64)[None])[0] for n in names)
    if abs(l[0] - r[0]) <= 0 or up[1] <= lo[1]:
        return np.zeros(len(F), dtype=bool)
    C = frame.to_canonical(np.asarray(V, dtype=np.float64))
    xs = np.array([r[0], st[0], l[0]])
    deg = 2 if len(np.unique(xs)) == 3 else 1  # the quadratic through the three (a line if two share x)
    x = C[:, 0]
    height = C[:, 1] - np.polyval(np.polyfit(xs, [r[1], st[1], l[1]], deg), x)
    depth = C[:, 2] - np.polyval(np.polyfit(xs, [r[2], st[2], l[2]], deg), x)
    inside = (x > min(r[0], l[0])) & (x < max(r[0], l[0])) & (np.abs(depth) < up[1] - lo[1])
    h = height[F]
    return inside[F].all(axis=1) & (h.min(axis=1) < 0) & (h.max(axis=1) > 0)


def lip_motion(V, landmarks, D, up):
    """How a displacement ``D`` (n, 3) moves a head's lips, in mouth widths (cheilion to cheilion).

    The upper lip is sampled at the vertices nearest 10 points from ``stomion`` to
    ``labiale_superius`` (5 % to 95 %), the lower to ``labiale_inferius``. Returns the upper's and the
    lower's mean displacement length and the opening: the lower's mean displacement minus the
    upper's along ``-up`` (``up`` (3,) the head's up, input frame), all divided by the mouth width.
    ``V``, ``landmarks`` (name -> (3,)) and ``D`` in the same frame and units.
    """
    from scipy.spatial import cKDTree

    st, ls, li, cl, cr = (np.asarray(landmarks[k], dtype=np.float64) for k in
                          ("stomion", "labiale_superius", "labiale_inferius", "cheilion_l", "cheilion_r"))
    width = max(float(np.linalg.norm(cl - cr)), 1e-300)
    f = np.linspace(0.05, 0.95, 10)[:, None]
    tree = cKDTree(np.asarray(V, dtype=np.float64))
    du = D[tree.query(st + f * (ls - st))[1]]
    dl = D[tree.query(st + f * (li - st))[1]]
    return (float(np.linalg.norm(du, axis=1).mean() / width), float(np.linalg.norm(dl, axis=1).mean() / width),
            float((dl.mean(axis=0) - du.mean(axis=0)) @ -np.asarray(up, dtype=np.float64)) / width)


def _in_polygon(X, poly):
    """Points ``X`` (k, 2) inside the closed polygon ``poly`` (p, 2): even-odd ray casting, (k,) bool."""
    inside = np.zeros(len(X), dtype=bool)
    for a, b in zip(poly, np.roll(poly, -1, axis=0)):
        crosses = (a[1] > X[:, 1]) != (b[1] > X[:, 1])
        with np.errstate(divide="ignore", invalid="ignore"):
            x_at = a[0] + (X[:, 1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
        inside ^= crosses & (X[:, 0] < x_at)
    return inside
