"""Stick (STK): project a warped source mesh onto the target surface.

Orvalho, Zacur & Susin 2008, §3.3, equation 4: every vertex of the (TPS-warped) source goes to the
closest point of the target surface, which gives a dense correspondence
``source vertex i -> (target face, barycentric coordinates)``.

Orvalho et al. note that sticking "can present undesirable folds in areas with high
curvature or if the distance between origin and target points is large" and
leaves them undetected; here each vertex also gets a reliability flag, false
where

- the source normal and the normal of the target face it lands on disagree by
  more than ``max_angle`` (it was stuck onto a surface facing another way:
  the other side of a lip, the eyeball behind a lid), or
- a source triangle around it is flipped (its normal reverses) or collapsed
  (its area shrinks below ``min_area_ratio`` of the warped area) by sticking.

Optional part labels restrict which target faces a vertex may land on (used by
:mod:`autobones.rig_transfer.correspondence` to keep eyeballs on eyeballs). Closest points come from
libigl's AABB tree; nothing is ``O(n^2)``.
"""
from __future__ import annotations

import numpy as np

from ..errors import AutobonesError, counted
from ..geometry.closest import closest_points
from ..geometry.normals import triangle_normals, vertex_normals
from ..geometry.validate import mesh_arrays


def stick(V_src, F_src, V_tgt, F_tgt, max_angle=60.0, min_area_ratio=0.01, labels=None, face_labels=None):
    """Project every source vertex to the closest point of the target surface.

    Parameters
    ----------
    V_src : (n, 3) float
        Source vertices already warped into the target's frame and units
        (e.g. by :class:`autobones.geometry.tps.ThinPlateSpline`).
    F_src : (m_s, 3) int
        Source triangles (for normals and fold detection).
    V_tgt : (n_t, 3) float
        Target vertices.
    F_tgt : (m_t, 3) int
        Target triangles.
    max_angle : float, default 60
        Degrees; a vertex whose normal differs from the normal of the target
        face it lands on by more is unreliable.
    min_area_ratio : float, default 0.01
        A source triangle whose stuck area is below this fraction of its
        warped area counts as collapsed.
    labels : (n,) int, optional
        Part of each source vertex, see :func:`closest_points`.
    face_labels : (m_t,) int, optional
        Part of each target face.

    Returns
    -------
    P : (n, 3) float64
        Stuck positions, on the target surface (target units).
    face : (n,) int64
        Target face each vertex landed on.
    bary : (n, 3) float64
        Barycentric coordinates in that face: ``P = sum_k bary[:, k] * V_tgt[F_tgt[face, k]]``.
    reliable : (n,) bool
        False at detected folds: normal disagreement, or a vertex of a flipped
        or collapsed stuck triangle.

    Raises
    ------
    AutobonesError
        Arrays of the wrong shape, face indices out of range, NaN coordinates.

    Examples
    --------
    >>> import trimesh
    >>> s = trimesh.creation.icosphere(3)
    >>> P, face, bary, ok = stick(1.1 * s.vertices, s.faces, s.vertices, s.faces)
    >>> bool(ok.all())
    True
    """
    V_src, F_src = mesh_arrays(V_src, F_src, "source mesh")
    V_tgt, F_tgt = mesh_arrays(V_tgt, F_tgt, "target mesh")
    if labels is not None and len(labels) != len(V_src):
        raise AutobonesError(f"labels: {counted(len(labels), 'value')} for {counted(len(V_src), 'source vertex', 'source vertices')}")
    if face_labels is not None and len(face_labels) != len(F_tgt):
        raise AutobonesError(f"face_labels: {counted(len(face_labels), 'value')} for {counted(len(F_tgt), 'target face')}")
    P, face, bary, _ = closest_points(V_src, V_tgt, F_tgt, labels, face_labels)
    face, bary = facing_face(P, face, bary, V_tgt, F_tgt, vertex_normals(V_src, F_src), face_labels)
    reliable = fold_free(V_src, F_src, P, V_tgt, F_tgt, face, max_angle, min_area_ratio)
    return P, face, bary, reliable


# a closest point whose barycentric coordinate is below ON_EDGE lies on the face's edge or corner
# (dimensionless: the same in any unit and frame)
ON_EDGE = 1e-9


def facing_face(P, face, bary, V, F, normals, face_labels=None):
    """Settle a closest point on an edge or a corner of the mesh: of the faces sharing it, the one
    whose normal is nearest the query's.

    Such a point belongs to every face around that edge or corner, and which one a closest-point
    search reports is decided by rounding (a copy of the head at x1000, or turned, picks another);
    on a fold the faces there face opposite ways, so the normal checks downstream (the stick's fold
    test, the field copy's reliability) flipped with the units. Ties among equally facing faces go
    to the lowest face index.

    Parameters
    ----------
    P : (k, 3) float
        The closest points, on the mesh (its units).
    face : (k,) int
        Face reported for each.
    bary : (k, 3) float
        Barycentric coordinates of ``P`` in ``face``.
    V, F : (n, 3) float, (m, 3) int
        The mesh.
    normals : (k, 3) float
        Unit normal of each query.
    face_labels : (m,) int, optional
        Part of each face: the face stays in the part it was found in.

    Returns
    -------
    face : (k,) int64
    bary : (k, 3) float64
        Coordinates of the same points in the faces kept.
    """
    from ..geometry.closest import barycentric

    face, bary = np.asarray(face, dtype=np.int64).copy(), np.asarray(bary, dtype=np.float64).copy()
    F = np.asarray(F, dtype=np.int64)
    support = bary > ON_EDGE
    q = np.flatnonzero(support.sum(axis=1) < 3)
    if not len(q):
        return face, bary
    # candidates: the faces around each point's strongest corner that also hold its other support corner
    lead = F[face[q], np.argmax(bary[q], axis=1)]
    other = np.where(support[q].sum(axis=1) == 2, F[face[q], np.argsort(bary[q], axis=1)[:, 1]], lead)
    order = np.argsort(F.ravel(), kind="stable")
    start = np.searchsorted(F.ravel()[order], np.arange(len(V) + 1))
    count = start[lead + 1] - start[lead]
    row = np.repeat(np.arange(len(q)), count)
    at = np.arange(len(row)) - np.repeat(np.cumsum(count) - count, count)
    cand = order[start[lead][row] + at] // 3
    keep = (F[cand] == other[row, None]).any(axis=1)
    if face_labels is not None:
        keep &= np.asarray(face_labels)[cand] == np.asarray(face_labels)[face[q]][row]
    row, cand = row[keep], cand[keep]
    FN = triangle_normals(V, F[cand])
    FN /= np.maximum(np.linalg.norm(FN, axis=1, keepdims=True), 1e-300)
    score = np.einsum("ij,ij->i", np.asarray(normals, dtype=np.float64)[q[row]], FN)
    best = np.lexsort((cand, -score, row))          # per query: best score, then lowest index
    first = best[np.r_[True, row[best][1:] != row[best][:-1]]]
    hit = q[row[first]]
    face[hit] = cand[first]
    T = np.asarray(V, dtype=np.float64)[F[face[hit]]]
    bary[hit] = barycentric(np.asarray(P, dtype=np.float64)[hit], T[:, 0], T[:, 1], T[:, 2])
    return face, bary


def fold_free(V_before, F_src, V_after, V_tgt, F_tgt, face, max_angle=60.0, min_area_ratio=0.01):
    """Per-vertex flag: sticking ``V_before`` to ``V_after`` made no fold there.

    Parameters
    ----------
    V_before : (n, 3) float
        Source vertices before sticking (warped into the target frame).
    F_src : (m_s, 3) int
        Source triangles.
    V_after : (n, 3) float
        Stuck positions.
    V_tgt, F_tgt : target mesh; ``face`` (n,) the target face of each stuck vertex.
    max_angle, min_area_ratio : see :func:`stick`.

    Returns
    -------
    reliable : (n,) bool
    """
    n = len(V_before)
    N_src = vertex_normals(V_before, F_src)
    FN_tgt = triangle_normals(V_tgt, F_tgt)
    FN_tgt /= np.maximum(np.linalg.norm(FN_tgt, axis=1, keepdims=True), 1e-300)
    used = np.zeros(n, dtype=bool)
    used[F_src.ravel()] = True
    agree = np.einsum("ij,ij->i", N_src, FN_tgt[face]) >= np.cos(np.radians(max_angle))
    reliable = agree | ~used
    before = triangle_normals(V_before, F_src)
    after = triangle_normals(V_after, F_src)
    a0 = np.linalg.norm(before, axis=1)
    a1 = np.linalg.norm(after, axis=1)
    flipped = np.einsum("ij,ij->i", before, after) < 0
    collapsed = (a1 < min_area_ratio * a0) & (a0 > 0)
    bad = flipped | collapsed
    reliable[F_src[bad].ravel()] = False
    return reliable
