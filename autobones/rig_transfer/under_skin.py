"""Points under and on the skin carried from the generic rig onto a head.

Orvalho, Zacur & Susin 2008, §3.4: once the generic skin has a dense correspondence on
the head (each generic vertex -> a point of the head's surface), a second thin-plate
spline fitted on a well-spread subsample of that correspondence carries what lies under
the skin (the skeleton, the muscle origins); points on the skin (the muscle insertions)
ride the correspondence itself. Inputs are in the generic rig's frame and units,
outputs in the head's.
"""
from __future__ import annotations

import numpy as np

from ..geometry.closest import closest_points
from ..geometry.tps import ThinPlateSpline


def spread_subsample(P, count):
    """Indices of ``count`` well-spread points of ``P``.

    Parameters
    ----------
    P : (n, 3) float
        Points, any frame.
    count : int
        How many to choose (at most ``n``).

    Returns
    -------
    (min(count, n),) int64
        Greedy farthest-point order from the point nearest the centroid; deterministic.
    """
    count = min(count, len(P))
    chosen = np.empty(count, dtype=np.int64)
    chosen[0] = int(np.argmin(((P - P.mean(axis=0)) ** 2).sum(axis=1)))
    d = ((P - P[chosen[0]]) ** 2).sum(axis=1)
    for i in range(1, count):
        chosen[i] = int(np.argmax(d))
        d = np.minimum(d, ((P - P[chosen[i]]) ** 2).sum(axis=1))
    return chosen


def ride(points, V_src, F_src, P, return_faces=False):
    """Points on the source surface moved with the correspondence.

    Parameters
    ----------
    points : (k, 3) float
        Points on (or near) the source surface, source frame.
    V_src : (n, 3) float
        Source vertices.
    F_src : (m, 3) int
        Source triangles.
    P : (n, 3) float
        Each source vertex's corresponding point, target frame.

    return_faces : bool
        Also return each point's source triangle.

    Returns
    -------
    (k, 3) float
        Each point's barycentric coordinates in its closest source triangle, applied to ``P``;
        with ``return_faces``, also those triangles (k,) int.
    """
    _, face, bary = closest_points(np.asarray(points, dtype=np.float64), V_src, F_src)[:3]
    moved = np.einsum("ki,kij->kj", bary, P[F_src[face]])
    return (moved, face) if return_faces else moved


def under_skin_warp(V_src, P, reliable, control_points, partners=None):
    """The thin-plate spline source -> target fitted on a spread subsample of the correspondence.

    Parameters
    ----------
    V_src : (n, 3) float
        Source (generic) vertices.
    P : (n, 3) float
        Their corresponding points on the target, target frame.
    reliable : (n,) bool
        Trusted correspondences; all are used when fewer than 20 are trusted.
    control_points : int
        Size of the subsample.
    partners : (n,) int or None
        Each source vertex's mirror partner (a symmetric correspondence,
        :mod:`autobones.rig_transfer.symmetry`): the subsample then holds each point's partner too,
        so the warp, and what it carries, is as symmetric as the correspondence.

    Returns
    -------
    ThinPlateSpline
        Regularised (1e-3), source frame -> target frame.
    """
    ok = reliable if partners is None else reliable & reliable[partners]
    good = np.flatnonzero(ok) if ok.sum() >= 20 else np.arange(len(P))
    if partners is None:
        idx = good[spread_subsample(V_src[good], control_points)]
    else:   # half as many, each with its partner: as many points, as spread
        idx = good[spread_subsample(V_src[good], (control_points + 1) // 2)]
        idx = np.unique(np.concatenate([idx, partners[idx]]))
    return ThinPlateSpline(regularization=1e-3).fit(V_src[idx], P[idx])


def carry_muscles(muscles, under, V_src, F_src, P):
    """Muscles of the generic rig on the target: origins by the under-skin warp, insertions riding
    the correspondence.

    Parameters
    ----------
    muscles : list of dict
        Each with ``origin`` and ``insertion`` (3,) in the source frame; other keys copied.
    under : ThinPlateSpline
        :func:`under_skin_warp`.
    V_src, F_src, P
        As in :func:`ride`.

    Returns
    -------
    list of dict
        Copies with ``origin`` and ``insertion`` (3,) float64 arrays in the target frame.
    """
    if not muscles:
        return []
    # every insertion in one closest-point query (one AABB tree, not one a muscle)
    insertions = ride(np.array([m["insertion"] for m in muscles], dtype=np.float64), V_src, F_src, P)
    out = []
    for m, ins in zip(muscles, insertions):
        m = dict(m)
        m["origin"] = under.transform(np.asarray(m["origin"], dtype=np.float64)[None])[0]
        m["insertion"] = ins
        out.append(m)
    return out
