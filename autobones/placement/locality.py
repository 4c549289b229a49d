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
2. head and neck: the share of the head and its children is set by where a vertex lies, not by
   the heat (which splits the neck from the head wherever the two bones' segments are equidistant,
   a long way below the pivot on a bust): :func:`head_share` is 0 below a boundary through the
   head joint (the occiput-C1 pivot, :mod:`.joints`) and 1 above it, a smooth step across a band
   centred on the boundary. Behind the pivot the boundary is level with it (the suboccipital
   region: the skull above turns, the nape below stays); in front it descends to pass under the
   chin, so the jaw, chin and lips turn with the head and the throat stays with the neck. The
   neck base is pure neck: the share is 0 up to the higher of the lowest ``NECK_BASE`` of the
   vertices and ``NECK_BASE`` of the mesh's height, rising over the next ``NECK_RISE`` of the way
   to the joint, so a head turn leaves it still. The face and ``FACE_HOLD`` times its band keep
   the whole share wherever they hang (a long muzzle below any boundary through the pivot). The
   neck gets the rest of each row; the head and facial bones keep their heat weights where these
   sum to less than the share (the head bone takes the rest) and are scaled down alike where
   more. Above the blend band (the top of the skull) nothing is neck.

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
from .joints import NECK_BASE, neck_base_height

FACIAL_BAND = 0.08   # head sizes: facial weights fade to 0 this far from the facial mask
FACE_HOLD = 2.0      # of the facial band: the face keeps the head's share this far out
NECK_RISE = 0.30     # of the way from the neck base to the joint: the head's share rises over it
HEAD_BAND = 0.10     # head sizes: half-width of the neck/head blend across the boundary
BAND_SHARE = 0.4     # ... and at most this share of the height from the neck base to the joint
SKULL_BLEND = 0.5    # of the height from the joint to the top: no neck weight above
CHIN_MARGIN = 0.05   # head sizes: the boundary passes this far under the chin
ROUND = 0.05         # head sizes: the boundary's bend at the pivot is rounded over this depth
CHUNK = 65536


def restrict_weights(C, W, facial_mask, joint, neck=0, head=1, facial=None, faces=None, band=FACIAL_BAND,
                     chin=None, face_only=False, prune=0.01, cut=None):
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
    chin, face_only, cut
        The boundary's and the neck base's options, see :func:`head_share`.
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
    # 1. facial bones fade out beyond the mask's blend band (distances bounded by it: inf beyond)
    # the face holds the head's share over twice the facial band: the head/neck split is a larger
    # move of weight than the facial bones' fade, and as steep a step would be a seam under the chin
    keep, hold = np.zeros(n), np.zeros(n)
    if facial_mask.any():
        d, _ = cKDTree(C[facial_mask]).query(C, distance_upper_bound=FACE_HOLD * band)
        keep = 1.0 - smoothstep(np.minimum(d, band) / band)
        hold = 1.0 - smoothstep(np.minimum(d, FACE_HOLD * band) / (FACE_HOLD * band))
        keep[facial_mask] = hold[facial_mask] = 1.0
    if (facial.stop > facial.start) if isinstance(facial, slice) else len(facial):
        for s in range(0, n, CHUNK):
            blk = W[s:s + CHUNK, facial]
            k = keep[s:s + CHUNK, None]
            W[s:s + CHUNK, head] += (blk * (1.0 - k)).sum(axis=1)
            W[s:s + CHUNK, facial] = blk * k

    # 2. the head's share (head and facial bones) from the boundary through the pivot, and all of the
    # face and its band (a long muzzle hangs below any plane through the pivot); the rest is neck
    share = head_share(C, joint, faces=faces, chin=chin, face_only=face_only, face=hold, cut=cut)
    others = np.array([j for j in range(b) if j != neck], dtype=np.int64)
    head_col = int(np.flatnonzero(others == head)[0])
    for s in range(0, n, CHUNK):
        blk, h = W[s:s + CHUNK][:, others], share[s:s + CHUNK]
        total = blk.sum(axis=1)
        # too much heat above the share: all scaled down alike; too little: the head bone takes the
        # rest (scaling the facial bones up would steepen their own steps beyond the heat's)
        over = total > h
        blk[over] *= (h[over] / total[over])[:, None]
        blk[~over, head_col] += (h - total)[~over]
        W[s:s + CHUNK, others] = blk
        W[s:s + CHUNK, neck] = 1.0 - h

    np.clip(W, 0.0, None, out=W)
    for s in range(0, n, CHUNK):
        blk = W[s:s + CHUNK]
        W[s:s + CHUNK] = prune_weights(blk, prune) if prune > 0 else blk / blk.sum(axis=1, keepdims=True)
    return W


def head_share(C, joint, faces=None, chin=None, face_only=False, face=None, band=HEAD_BAND,
               neck_base=NECK_BASE, neck_rise=NECK_RISE, cut=None):
    """The head's share of each vertex (step 2 of the module docstring): (n,) in [0, 1].

    Parameters
    ----------
    C : (n, 3) float
        Canonical vertices (head sizes, +Y up, +Z front).
    joint : (3,) float
        The head joint (the pivot); the boundary runs through it.
    faces : (m, 3) int, optional
        Triangles: the neck base is measured on the vertices they use.
    chin : (float, float), optional
        The menton's height and the chin's front depth: in front of the pivot the boundary descends
        to ``CHIN_MARGIN`` under that point (its slope kept between 0.3 and 2); default slope 1.
    face_only : bool
        A face-only mesh: its face turns with the head down to its lowest vertices (the chin of a
        mask); a neck below the face still keeps its base still.
    face : (n,) float, optional
        1 on the facial mask falling to 0 across its band: the face turns with the head wherever
        it hangs (a long muzzle below any boundary through the pivot).
    band : float
        Half-width of the blend across the boundary, head sizes (at most ``BAND_SHARE`` of the
        height from the neck base to the joint).
    neck_base, neck_rise : float
        See the module docstring.
    cut : ((3,) float, (3,) float), optional
        A planar neck cut's centre and unit normal (pointing out of the mesh, canonical frame;
        :func:`autobones.cut_cues.cut_cues`): the vertices within ``neck_base`` of the height from it
        are neck base too, the head's share rising over the next ``neck_rise`` of the way to the
        joint. A cut slanted to the head's up (an animal's neck leaves its skull backwards: the
        cow's by 39 degrees) puts some of its edge above the lowest heights, which a head turn then
        dragged.
    """
    C = np.asarray(C, dtype=np.float64)
    y, z = C[:, 1], C[:, 2]
    used = y if faces is None or len(faces) == 0 else y[used_vertices(np.asarray(faces), len(C))]
    yj, zj = float(joint[1]), float(joint[2])
    base = min(neck_base_height(used, neck_base), yj - 1e-6)
    slope = 1.0
    if chin is not None:
        slope = float(np.clip((yj - (chin[0] - CHIN_MARGIN)) / max(chin[1] - zj, ROUND), 0.3, 2.0))
    # level behind the pivot, descending in front, the bend rounded (softplus) so the share is smooth
    boundary = yj - slope * ROUND * np.logaddexp(0.0, (z - zj) / ROUND)
    half = max(min(band, BAND_SHARE * (yj - base)), 1e-6)
    rise = smoothstep((y - base) / max(neck_rise * (yj - base), 1e-12))
    if cut is not None and not face_only:
        centre, normal = np.asarray(cut[0], dtype=np.float64), np.asarray(cut[1], dtype=np.float64)
        above = (C - centre) @ -normal
        top = float((np.asarray(joint, dtype=np.float64) - centre) @ -normal)
        low = neck_base * float(np.ptp(used))
        if top > low:
            rise = rise * smoothstep((above - low) / max(neck_rise * (top - low), 1e-12))
    share = smoothstep((y - boundary + half) / (2.0 * half)) * rise
    if face is not None:
        # a face-only mesh's lowest vertices are its chin, which turns with the head; a neck's base
        # is still even where the face's band reaches it
        share = np.maximum(share, face if face_only else face * rise)
    return share
