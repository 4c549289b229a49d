"""The data terms of the dense fit (:mod:`autobones.rig_transfer.correspondence`): which target point
each source vertex is pulled to, and back.

- :class:`PartTrees`: nearest target vertex, restricted to a part;
- :func:`reverse_matches`, :func:`target_samples`: target -> source matches (the reverse term), a dense
  target binned into grid cells first;
- :func:`boundary_neighbours`, :func:`onto_rim`: closest points on the target's rim;
- :class:`Matcher`: all of them folded into the targets ``C`` of one least-squares solve.

Arrays in, arrays out; the figures behind each choice are in benchmarks/README.md (correspondence).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..geometry.closest import closest_points
from ..geometry.normals import triangle_normals


class PartTrees:
    """Nearest target vertex per source vertex, restricted to a part when one is assigned.

    One 4-d tree: the part label, times more than the point cloud's diameter,
    is the fourth coordinate, so the nearest neighbour of a labelled query is in
    its part; unlabelled queries use a plain 3-d tree.
    """

    def __init__(self, V, mask, part):
        self.idx = np.flatnonzero(mask)
        P = V[self.idx]
        self.big = 10.0 * (np.ptp(P, axis=0).max() + 1.0) if len(P) else 1.0
        self.parts = np.unique(part[self.idx])
        self.tree3 = cKDTree(P) if len(P) else None
        self.tree4 = cKDTree(np.c_[P, self.big * part[self.idx]]) if len(P) else None

    def query(self, X, labels):
        labels = np.asarray(labels)
        out = np.empty(len(X), dtype=np.int64)
        lab = np.isin(labels, self.parts)
        if lab.any():
            out[lab] = self.idx[self.tree4.query(np.c_[X[lab], self.big * labels[lab]], workers=-1)[1]]
        if not lab.all():
            out[~lab] = self.idx[self.tree3.query(X[~lab], workers=-1)[1]]
        return out


def reverse_matches(X, N, labels, sidx, T, N_t, part_t, area_t, big, cos_max):
    """Target -> source matches: every target sample ``T`` (k, 3) (normals ``N_t``, parts ``part_t``,
    areas ``area_t``: :func:`target_samples`) goes to its nearest source vertex ``sidx``.

    Same part only (part label times ``big`` as a fourth coordinate), dropped
    when the normals differ by more than ``acos(cos_max)`` or the distance is
    an outlier (> 5 x median). Returns ``has`` (n,) bool, a source vertex
    received matches; ``M`` (n, 3) the area-weighted mean of its
    matched target samples (the centroid of the target surface closest to
    it); ``a`` (n,) the target area it received.
    """
    d, i = cKDTree(np.c_[X[sidx], big * labels[sidx]]).query(np.c_[T, big * part_t], workers=-1)
    i = sidx[i]
    ok = (np.einsum("ij,ij->i", N[i], N_t) >= cos_max) & (d <= 5.0 * np.median(d) + 1e-12)
    i, k = i[ok], np.flatnonzero(ok)
    a = np.bincount(i, area_t[k], minlength=len(X))
    has = a > 0
    M = np.stack([np.bincount(i, area_t[k] * T[k, c], minlength=len(X)) for c in range(3)], axis=1)
    M[has] /= a[has, None]
    return has, M, a


# a target denser than SAMPLE_RATIO x the source is matched back through grid cells of half the source's
# median edge: the centroid of a source vertex's target area is the same, at a fraction of the queries
SAMPLE_RATIO = 4


def target_samples(V_tgt, N_tgt, part, area, tq, cell, turn):
    """The target vertices ``tq`` as reverse-match samples: themselves, or where ``cell`` > 0 (target
    units) their area-weighted centroids per grid cell of that size and part. The grid's axes are the
    source's, turned into the target by ``turn`` (3, 3) (:func:`autobones.rig_transfer.correspondence.rigid_turn`, rows ``x_src @ turn``):
    a grid along the target file's axes would bin a turned head differently. Returns points (k, 3),
    unit normals (k, 3), parts (k,) and areas (k,)."""
    if cell <= 0:
        return V_tgt[tq], N_tgt[tq], part[tq], area[tq]
    P = V_tgt[tq]
    G = P @ turn.T
    key = np.c_[np.floor((G - G.min(axis=0)) / cell).astype(np.int64), part[tq]]
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inv = inv.ravel()
    w = area[tq] + 1e-12 * (area[tq].mean() + 1e-300)   # a cell of zero-area vertices keeps its place
    m = len(first)
    sw = np.bincount(inv, w, minlength=m)
    T = np.stack([np.bincount(inv, w * P[:, c], minlength=m) for c in range(3)], axis=1) / sw[:, None]
    Nt = np.stack([np.bincount(inv, w * N_tgt[tq, c], minlength=m) for c in range(3)], axis=1)
    Nt /= np.maximum(np.linalg.norm(Nt, axis=1, keepdims=True), 1e-300)
    return T, Nt, part[tq][first], np.bincount(inv, area[tq], minlength=m)


def boundary_neighbours(n, F):
    """(n, 2) int64: each boundary vertex's neighbours along the boundary (-1 where none; a vertex
    where more than two boundary edges meet keeps two of them)."""
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    E.sort(axis=1)
    u, count = np.unique(E[:, 0] * n + E[:, 1], return_counts=True)
    b = u[count == 1]
    ends, other = np.r_[b // n, b % n], np.r_[b % n, b // n]
    order = np.argsort(ends, kind="stable")
    ends, other = ends[order], other[order]
    first = np.r_[True, ends[1:] != ends[:-1]]
    second = ~first & np.r_[False, first[:-1]]
    nb = np.full((n, 2), -1, dtype=np.int64)
    nb[ends[first], 0] = other[first]
    nb[ends[second], 1] = other[second]
    return nb


def onto_rim(X, j, V, nb):
    """Closest points (k, 3) to ``X`` (k, 3) on the boundary edges at each one's nearest boundary vertex ``j``."""
    best = V[j].copy()
    d2 = ((X - best) ** 2).sum(axis=1)
    for c in range(2):
        ok = np.flatnonzero(nb[j, c] >= 0)
        a = V[j[ok]]
        e = V[nb[j[ok], c]] - a
        t = np.clip(((X[ok] - a) * e).sum(axis=1) / np.maximum((e * e).sum(axis=1), 1e-300), 0.0, 1.0)
        P = a + t[:, None] * e
        d = ((X[ok] - P) ** 2).sum(axis=1)
        better = d < d2[ok]
        best[ok[better]], d2[ok[better]] = P[better], d[better]
    return best


class Matcher:
    """The data term's targets ``C`` (n, 3) for the current fit ``X`` (n, 3) with normals ``N``:
    closest target points (point-to-plane at the nearest vertex, or exact), rejected matches
    held in place, boundary vertices pulled to the target boundary, and the reverse term
    folded in (see the module doc)."""

    def __init__(self, V_tgt, F_tgt, tgt, labels, in_face, bidx, btrees, cos_max, exact, symmetric_weight, reverse):
        self.V_tgt, self.F_tgt, self.tgt, self.labels, self.in_face = V_tgt, F_tgt, tgt, labels, in_face
        self.bidx, self.btrees, self.cos_max, self.exact = bidx, btrees, cos_max, exact
        self.symmetric_weight, self.reverse = symmetric_weight, reverse
        if exact:  # only the exact closest points land on faces
            self.face_labels = tgt["part"][F_tgt[:, 0]]
            FN = triangle_normals(V_tgt, F_tgt)
            self.FN_tgt = FN / np.maximum(np.linalg.norm(FN, axis=1, keepdims=True), 1e-300)

    def __call__(self, X, N):
        V_tgt, labels, in_face, bidx, tgt = self.V_tgt, self.labels, self.in_face, self.bidx, self.tgt
        if self.exact:
            C, fc, _, _ = closest_points(X, V_tgt, self.F_tgt, labels, self.face_labels)
            nj = self.FN_tgt[fc]
        else:
            j = tgt["trees"].query(X, labels)
            nj = tgt["N"][j]
            C = X - np.einsum("ij,ij->i", X - V_tgt[j], nj)[:, None] * nj      # point-to-plane
        dist = np.linalg.norm(C - X, axis=1)
        bad = (np.einsum("ij,ij->i", N, nj) < self.cos_max) | (dist > 5.0 * np.median(dist[in_face]) + 1e-12)
        C[bad] = X[bad]
        if len(bidx):
            # the closest point of the target's rim (its two rim edges at the nearest rim vertex):
            # snapping to rim vertices bunched the source rim on a coarse target's long rim edges
            C[bidx] = onto_rim(X[bidx], self.btrees.query(X[bidx], labels[bidx]), V_tgt, tgt["bnb"])
        C[~in_face] = X[~in_face]
        if self.reverse is not None:
            area_s, sidx, samples = self.reverse
            has, M, a = reverse_matches(X, N, labels, sidx, *samples,
                                         tgt["trees"].big, self.cos_max)
            has[bidx] = False
            r = self.symmetric_weight * np.minimum(a[has] / area_s[has], 4.0)[:, None]
            C[has] = (C[has] + r * M[has]) / (1.0 + r)
        return C
