"""Small closed parts of a mesh (eyeballs, teeth, a button nose) and skin weights that move each whole.

Bone heat (:mod:`autobones.placement.skin_weights`) solves every separate part from its own nearest
bones, so an eyeball under the lids' facial bones took one weight on its front and another on its
back, and a facial bone's turn squashed it: on ICT identity001 rigged by ``place --density dense`` an
eyeball's weights spread over 0.70-0.74 (largest difference from the part's mean), a tooth's up to
0.54. A closed surface that is small against the head is a rigid body the modeller made apart (an
eyeball, a tooth, a horn's cap): the same weights on all its vertices move it as one piece (exactly
under one bone, as the blend of its bones' motions otherwise). Open parts are left alone: lashes, a
lid's shell, a mouth bag follow the skin they line.

Arrays in, arrays out; any frame and unit.
"""
from __future__ import annotations

import numpy as np

from .areas import triangle_areas, vertex_areas
from .topology import mesh_parts, weld
from .weights import prune_weights

SMALL = 0.2   # of the mesh's extent: a closed part at most this large is rigid


def closed_small_parts(V, F, small=SMALL, weld_tol=1e-6):
    """The separate closed parts of a mesh smaller than ``small`` of its extent.

    Parameters
    ----------
    V : (n, 3) float
        Vertices, any frame and unit.
    F : (m, 3) int
        Triangles; vertices closer than ``weld_tol`` of the bounding-box diagonal are welded first
        (an unwelded export splits every face apart).
    small : float
        Largest extent of a part (bounding-box side), as a share of the mesh's largest side.
    weld_tol : float
        Welding tolerance, share of the bounding-box diagonal.

    Returns
    -------
    list of (p,) int64
        The vertices of each part, in part order; the largest part by area (the skin) is never one.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    if len(F) == 0:
        return []
    diag = float(np.linalg.norm(np.ptp(V, axis=0))) or 1.0
    Vw, Fw, index = weld(V, F, weld_tol * diag)
    part_w = mesh_parts(len(Vw), Fw)
    face_part = part_w[Fw[:, 0]]
    area = np.bincount(face_part, weights=triangle_areas(Vw, Fw), minlength=len(Vw))
    # closed: every edge of the part's triangles shared by exactly two of them
    E = np.sort(np.concatenate([Fw[:, [0, 1]], Fw[:, [1, 2]], Fw[:, [2, 0]]]), axis=1)
    key = E[:, 0] * len(Vw) + E[:, 1]
    uniq, inverse, count = np.unique(key, return_inverse=True, return_counts=True)
    open_part = np.zeros(len(Vw), dtype=bool)
    open_part[np.tile(face_part, 3)[count[inverse] != 2]] = True
    part = part_w[index]
    used = np.zeros(len(V), dtype=bool)
    used[F.ravel()] = True
    extent = float(np.ptp(V[used], axis=0).max())
    skin = int(np.argmax(area))
    out = []
    for p in np.unique(face_part):
        if p == skin or open_part[p]:
            continue
        rows = np.flatnonzero(part == p)
        if np.ptp(V[rows], axis=0).max() <= small * extent:
            out.append(rows)
    return out


def rigid_weights(W, V, F, parts, prune=0.01):
    """Skin weights with each part's rows set to its area-weighted mean row, pruned.

    Parameters
    ----------
    W : (n, b) float
        Skin weights, rows summing to 1.
    V, F : (n, 3) float, (m, 3) int
        The mesh (the vertex areas weigh the mean).
    parts : list of (p,) int
        Vertex rows of each part (:func:`closed_small_parts`).
    prune : float
        A part's weights below this share of its largest are zeroed, the rest rescaled
        (:func:`autobones.geometry.weights.prune_weights`; the mean of pruned rows has new small ones).

    Returns
    -------
    (n, b) float64
        A new array, rows still summing to 1; ``W`` itself (as float64) when there are no parts: a
        head without teeth or eyeballs pays no copy (272 MB at a million vertices and 34 bones).
    """
    if not parts:
        return np.asarray(W, dtype=np.float64)
    W = np.array(W, dtype=np.float64)
    a = vertex_areas(np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64))
    for rows in parts:
        w = a[rows] if a[rows].sum() > 0 else np.ones(len(rows))
        mean = (w[:, None] * W[rows]).sum(axis=0, keepdims=True) / w.sum()
        W[rows] = prune_weights(mean, prune) if prune > 0 else mean
    return W
