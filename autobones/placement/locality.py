"""Keep ``place``'s bone-heat weights local: facial bones on the face, a still neck base, a neck-free skull.

Bone heat (:mod:`.skin_weights`) gives every vertex some weight of every nearby bone, and the
facial bones, lying just under the skin of the face, are the nearest bones of much of the head's
sides: left alone, a head turn drags the base of the neck and a chin bone tugs at the neck and
the temples. A rigger expects the neck base to stay put and facial bones to stay on the face.
:func:`restrict_weights` restricts the heat weights along the bone hierarchy (neck -> head ->
facial bones), each step a smooth (C1) factor, so no seam appears:

1. facial bones: each facial weight is multiplied by a falloff of the distance to the facial
   mask, 1 on the mask and 0 beyond a blend band (``FACIAL_BAND`` head sizes), a smooth step
   between; the removed weight goes to the head bone (their parent);
2. neck base: the share of the head and its children is multiplied by a smooth step of height,
   0 on the lowest ``NECK_BASE`` of the neck (from the lowest vertex to the head/neck joint) and 1
   from ``NECK_RISE`` of it up, so the neck base is pure neck and a head turn leaves it still;
3. skull: the neck weight is multiplied by a smooth step falling from 1 at the joint's height to
   0 at ``SKULL_BLEND`` of the way to the top of the head; the removed weight goes to the head bone.

The rows stay non-negative and sum to one (each step moves weight between bones), and are pruned
again as the heat weights were. Everything is computed per vertex in the canonical frame (head
sizes, +Y up), so it is unit- and frame-free and works on the full mesh after a proxy's weights
were carried up; the distance to the mask is one k-d tree query bounded by the band.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..geometry.smooth import smoothstep
from ..geometry.topology import used_vertices
from ..geometry.weights import prune_weights

FACIAL_BAND = 0.08   # head sizes: facial weights fade to 0 this far from the facial mask
NECK_BASE = 0.05     # of the neck's height (lowest vertex to the joint): pure neck below
NECK_RISE = 0.30     # of the neck's height: the head's share is the heat's own from here up
SKULL_BLEND = 0.5    # of the height from the joint to the top: no neck weight above
CHUNK = 65536


def restrict_weights(C, W, facial_mask, joint, neck=0, head=1, facial=None, faces=None, band=FACIAL_BAND,
                     neck_base=NECK_BASE, neck_rise=NECK_RISE, skull_blend=SKULL_BLEND, prune=0.01):
    """Restrict bone-heat weights to stay local (module docstring); in place, and returned.

    Parameters
    ----------
    C : (n, 3) float
        Canonical vertices (head sizes, +Y up).
    W : (n, b) float
        Weights >= 0, rows summing to one; changed in place.
    facial_mask : (n,) bool
        Vertices of the face.
    joint : (3,) float
        Canonical head/neck joint (the neck bone's tail, the head bone's head).
    neck, head : int
        Columns of the neck bone and of the head bone (the facial bones' parent).
    facial : sequence of int, optional
        Columns of the facial bones; default every column but ``neck`` and ``head``.
    faces : (m, 3) int, optional
        Triangles: the lowest and highest vertices are taken among the vertices they use (a
        stray loose vertex does not move the neck base).
    band : float
        Blend band around the facial mask, head sizes.
    neck_base, neck_rise, skull_blend : float
        Fractions of the neck's and the skull's height; see the module docstring.
    prune : float
        Weights below this fraction of their row's largest are zeroed afterwards (0: none).

    Returns
    -------
    W : (n, b) float
        The same array.
    """
    C = np.asarray(C, dtype=np.float64)
    n, b = W.shape
    if facial is None:
        facial = [j for j in range(b) if j not in (neck, head)]
    facial = np.asarray(facial, dtype=np.int64)
    if len(facial) and np.array_equal(facial, np.arange(facial[0], facial[0] + len(facial))):
        facial = slice(int(facial[0]), int(facial[0]) + len(facial))  # a view, not a copy per block
    facial_mask = np.asarray(facial_mask, dtype=bool)
    y = C[:, 1]
    used = y if faces is None or len(faces) == 0 else y[used_vertices(np.asarray(faces), n)]
    bottom, top, yj = float(used.min()), float(used.max()), float(joint[1])
    neck_h, skull_h = max(yj - bottom, 1e-12), max(top - yj, 1e-12)

    # 1. facial bones fade out beyond the mask's blend band (distances bounded by it: inf beyond)
    if (facial.stop > facial.start) if isinstance(facial, slice) else len(facial):
        if facial_mask.any():
            d, _ = cKDTree(C[facial_mask]).query(C, distance_upper_bound=band)
            keep = 1.0 - smoothstep(np.minimum(d, band) / band)
            keep[facial_mask] = 1.0
        else:
            keep = np.zeros(n)
        for s in range(0, n, CHUNK):
            blk = W[s:s + CHUNK, facial]
            k = keep[s:s + CHUNK, None]
            W[s:s + CHUNK, head] += (blk * (1.0 - k)).sum(axis=1)
            W[s:s + CHUNK, facial] = blk * k

    # 2. the head's share (head and facial bones) fades to 0 at the neck base
    rise = smoothstep((y - (bottom + neck_base * neck_h)) / max((neck_rise - neck_base) * neck_h, 1e-12))
    low = np.flatnonzero(rise < 1.0)
    if len(low):
        others = np.array([j for j in range(b) if j != neck], dtype=np.int64)
        sub = W[np.ix_(low, others)]
        r = rise[low, None]
        W[low, neck] += (sub * (1.0 - r)).sum(axis=1)
        W[np.ix_(low, others)] = sub * r

    # 3. the neck's weight fades to 0 above the joint
    fade = smoothstep((y - yj) / max(skull_blend * skull_h, 1e-12))
    moved = W[:, neck] * fade
    W[:, neck] -= moved
    W[:, head] += moved

    np.clip(W, 0.0, None, out=W)
    for s in range(0, n, CHUNK):
        blk = W[s:s + CHUNK]
        W[s:s + CHUNK] = prune_weights(blk, prune) if prune > 0 else blk / blk.sum(axis=1, keepdims=True)
    return W
