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
   a long way below the pivot on a bust): the shared operation
   :mod:`autobones.geometry.head_share` (also ``transfer``'s), a blend centred on a boundary
   through the head joint (the occiput-C1 pivot, :mod:`.joints`) that passes under the chin, the
   neck base pure neck. The face and ``FACE_HOLD`` times its band keep the whole share wherever
   they hang (a long muzzle below any boundary through the pivot). Above the blend band (the top
   of the skull) nothing is neck; on a head with no neck (a closed head ending at its chin), nothing.

The rows stay non-negative and sum to one (each step moves weight between bones), and are pruned
again as the heat weights were. Everything is computed per vertex in the canonical frame (head
sizes, +Y up), so it is unit- and frame-free and works on the full mesh after a proxy's weights
were carried up; the distance to the mask is one k-d tree query bounded by the hold band.
"""
from __future__ import annotations

import numpy as np

from ..geometry.head_share import apply_head_share, head_share, mask_distance, smooth_share
from ..geometry.smooth import smoothstep
from ..geometry.weights import prune_weights

FACIAL_BAND = 0.08   # head sizes: facial weights fade to 0 this far from the facial mask
FACE_HOLD = 2.0      # of the facial band: the face keeps the head's share this far out
SKULL_BLEND = 0.5    # of the height from the joint to the top: no neck weight above
CHUNK = 65536


def restrict_weights(C, W, facial_mask, joint, neck=0, head=1, facial=None, faces=None, band=FACIAL_BAND,
                     chin=None, face_only=False, prune=0.01, cut=None, no_neck=False, chin_base=False,
                     jaw_angle=None):
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
    chin, face_only, cut, chin_base, jaw_angle
        The boundary's and the neck base's options, see
        :func:`autobones.geometry.head_share.head_share`.
    prune : float
        Weights below this fraction of their row's largest are zeroed afterwards (0: none).
    no_neck : bool
        The head has no neck (a closed head ending at its chin): all of it turns with the head, the
        neck bone weighs nothing.

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
    d = mask_distance(C, facial_mask, FACE_HOLD * band)
    keep = 1.0 - smoothstep(np.minimum(d, band) / band)
    hold = 1.0 - smoothstep(np.minimum(d, FACE_HOLD * band) / (FACE_HOLD * band))
    if (facial.stop > facial.start) if isinstance(facial, slice) else len(facial):
        for s in range(0, n, CHUNK):
            blk = W[s:s + CHUNK, facial]
            k = keep[s:s + CHUNK, None]
            W[s:s + CHUNK, head] += (blk * (1.0 - k)).sum(axis=1)
            W[s:s + CHUNK, facial] = blk * k

    # 2. the head's share (head and facial bones) from the boundary through the pivot, and all of the
    # face and its band (a long muzzle hangs below any plane through the pivot); the rest is neck
    share = np.ones(n) if no_neck else head_share(C, joint, faces=faces, chin=chin, face_only=face_only,
                                                  face=hold, cut=cut, chin_base=chin_base, jaw_angle=jaw_angle,
                                                  angle_estimated=True)
    if faces is not None and not no_neck:
        # the bands are head sizes: on a coarse neck one spans a single long edge, a step of the whole
        # head/neck split across it (as transfer's rigs, :mod:`autobones.rig_transfer.neck`)
        share = smooth_share(share, C, faces)
    apply_head_share(W, share, neck=neck, head=head)

    np.clip(W, 0.0, None, out=W)
    for s in range(0, n, CHUNK):
        blk = W[s:s + CHUNK]
        W[s:s + CHUNK] = prune_weights(blk, prune) if prune > 0 else blk / blk.sum(axis=1, keepdims=True)
    return W
