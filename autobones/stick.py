"""Stick (STK): project a warped source mesh onto the target surface.

Seed 004 §3.3, equation 4: every vertex of the (TPS-warped) source goes to the
closest point of the target surface, which gives a dense correspondence
``source vertex i -> (target face, barycentric coordinates)``.

Seed 004 notes that sticking "can present undesirable folds in areas with high
curvature or if the distance between origin and target points is large" and
leaves them undetected; here each vertex also gets a reliability flag, false
where

- the source normal and the normal of the target face it lands on disagree by
  more than ``max_angle`` (it was stuck onto a surface facing another way:
  the other side of a lip, the eyeball behind a lid), or
- a source triangle around it is flipped (its normal reverses) or collapsed
  (its area shrinks below ``min_area_ratio`` of the warped area) by sticking.

Optional part labels restrict which target faces a vertex may land on (used by
:mod:`autobones.fit` to keep eyeballs on eyeballs). Closest points come from
libigl's AABB tree; nothing is ``O(n^2)``.
"""
from __future__ import annotations

import numpy as np
import igl

from .errors import AutobonesError


def _check(V, F, name):
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    if V.ndim != 2 or V.shape[1] != 3 or len(V) == 0:
        raise AutobonesError(f"{name}: vertices must have shape (n, 3), got {V.shape}")
    if F.ndim != 2 or F.shape[1] != 3 or len(F) == 0:
        raise AutobonesError(f"{name}: faces must have shape (m, 3), got {F.shape}")
    if F.min() < 0 or F.max() >= len(V):
        raise AutobonesError(f"{name}: face indices out of range 0..{len(V) - 1}")
    if not np.isfinite(V).all():
        raise AutobonesError(f"{name}: vertices contain NaN or infinite coordinates")
    return V, F


def barycentric(P, A, B, C):
    """Barycentric coordinates of points in their triangles.

    Parameters
    ----------
    P, A, B, C : (n, 3) float
        Points and the corners of the triangle each lies on (or near).

    Returns
    -------
    W : (n, 3) float64
        Coordinates ``(wa, wb, wc)``, summing to one, of the projection of P
        onto the triangle's plane; degenerate triangles give the nearest corner
        weights ``(1, 0, 0)``.
    """
    v0, v1, v2 = B - A, C - A, P - A
    d00 = np.einsum("ij,ij->i", v0, v0)
    d01 = np.einsum("ij,ij->i", v0, v1)
    d11 = np.einsum("ij,ij->i", v1, v1)
    d20 = np.einsum("ij,ij->i", v2, v0)
    d21 = np.einsum("ij,ij->i", v2, v1)
    den = d00 * d11 - d01 * d01
    ok = den > 1e-300
    den = np.where(ok, den, 1.0)
    wb = np.where(ok, (d11 * d20 - d01 * d21) / den, 0.0)
    wc = np.where(ok, (d00 * d21 - d01 * d20) / den, 0.0)
    W = np.stack([1.0 - wb - wc, wb, wc], axis=1)
    # closest points lie in their triangle: clean round-off outside [0, 1]
    W = np.clip(W, 0.0, 1.0)
    return W / W.sum(axis=1, keepdims=True)


def closest_points(P, V, F, labels=None, face_labels=None):
    """Closest point of a triangle mesh to each query point.

    Parameters
    ----------
    P : (n, 3) float
        Query points, in the mesh's frame and units.
    V : (m_v, 3) float
        Target vertices.
    F : (m, 3) int
        Target triangles.
    labels : (n,) int, optional
        Part of each query point; with ``face_labels``, a point with label
        ``g >= 0`` only lands on faces labelled ``g`` (if there are any);
        ``-1`` lands anywhere.
    face_labels : (m,) int, optional
        Part of each target face.

    Returns
    -------
    C : (n, 3) float64
        Closest points on the surface.
    face : (n,) int64
        Target face of each closest point.
    bary : (n, 3) float64
        Barycentric coordinates of ``C`` in ``V[F[face]]``.
    sqrd : (n,) float64
        Squared distances, in squared mesh units.
    """
    P = np.ascontiguousarray(P, dtype=np.float64)
    n = len(P)
    C = np.empty((n, 3))
    face = np.empty(n, dtype=np.int64)
    sqrd = np.empty(n)
    if labels is None or face_labels is None:
        groups = [(np.arange(n), np.arange(len(F)))]
    else:
        labels = np.asarray(labels)
        face_labels = np.asarray(face_labels)
        groups = []
        anywhere = labels < 0
        for g in np.unique(labels[labels >= 0]):
            fi = np.flatnonzero(face_labels == g)
            pi = np.flatnonzero(labels == g)
            if len(fi) == 0:
                anywhere[pi] = True
            else:
                groups.append((pi, fi))
        if anywhere.any():
            groups.append((np.flatnonzero(anywhere), np.arange(len(F))))
    for pi, fi in groups:
        d, i, c = igl.point_mesh_squared_distance(P[pi], V, np.ascontiguousarray(F[fi]))
        C[pi], face[pi], sqrd[pi] = c, fi[i], d
    T = V[F[face]]
    return C, face, barycentric(C, T[:, 0], T[:, 1], T[:, 2]), sqrd


def triangle_normals(V, F):
    """Unnormalised face normals (twice the area vector), ``(m, 3)``."""
    return np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])


def vertex_normals(V, F):
    """Area-weighted unit vertex normals ``(n, 3)``; zero for vertices in no face."""
    N = np.zeros_like(V)
    FN = triangle_normals(V, F)
    for k in range(3):
        np.add.at(N, F[:, k], FN)
    length = np.linalg.norm(N, axis=1, keepdims=True)
    return N / np.where(length > 0, length, 1.0)


def stick(V_src, F_src, V_tgt, F_tgt, max_angle=60.0, min_area_ratio=0.01, labels=None, face_labels=None):
    """Project every source vertex to the closest point of the target surface.

    Parameters
    ----------
    V_src : (n, 3) float
        Source vertices already warped into the target's frame and units
        (e.g. by :class:`autobones.tps.ThinPlateSpline`).
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
    V_src, F_src = _check(V_src, F_src, "source mesh")
    V_tgt, F_tgt = _check(V_tgt, F_tgt, "target mesh")
    if labels is not None and len(labels) != len(V_src):
        raise AutobonesError(f"labels: {len(labels)} values for {len(V_src)} source vertices")
    if face_labels is not None and len(face_labels) != len(F_tgt):
        raise AutobonesError(f"face_labels: {len(face_labels)} values for {len(F_tgt)} target faces")
    P, face, bary, _ = closest_points(V_src, V_tgt, F_tgt, labels, face_labels)
    reliable = fold_free(V_src, F_src, P, V_tgt, F_tgt, face, max_angle, min_area_ratio)
    return P, face, bary, reliable


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
