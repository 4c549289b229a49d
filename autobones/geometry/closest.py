"""Closest points on a triangle mesh and barycentric coordinates."""
import igl
import numpy as np

from .topology import sorted_unique


def barycentric(P, A, B, C):
    """Barycentric coordinates of points in their triangles.

    Parameters
    ----------
    P, A, B, C : (n, 3) float
        Points and the corners of the triangle each lies on (or near).

    Returns
    -------
    W : (n, 3) float64
        Coordinates ``(wa, wb, wc)``, summing to one, of the projection of P onto the
        triangle's plane, clipped to the triangle; degenerate triangles give ``(1, 0, 0)``.
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


# Fewer queries than one per FEW triangles take the near-triangle path: building the AABB tree over a
# scan's every triangle then costs more than the queries themselves.
FEW = 256


def near_faces(P, V, F):
    """Indices (k,) of the triangles of ``F`` (m, 3) on ``V`` (n, 3) that may hold the closest
    surface point of one of ``P`` (p, 3): the closest triangle lies no farther than the nearest
    vertex (distance d), so each of its corners lies within d plus the longest edge."""
    from scipy.spatial import cKDTree

    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    used = np.zeros(len(V), dtype=bool)
    used[F.ravel()] = True
    ids = np.flatnonzero(used)
    tree = cKDTree(V[ids])
    d, _ = tree.query(P)
    A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    longest = np.sqrt(max(((A - B) ** 2).sum(axis=1).max(), ((B - C) ** 2).sum(axis=1).max(),
                          ((C - A) ** 2).sum(axis=1).max()))
    radius = d * (1 + 1e-9) + longest * (1 + 1e-9)
    if not np.isfinite(radius).all() or radius.max() > 0.25 * np.linalg.norm(np.ptp(V[ids], axis=0)):
        return np.arange(len(F))  # points far off the mesh: the search would cover most of it anyway
    hits = tree.query_ball_point(P, radius)
    mark = np.zeros(len(V), dtype=bool)
    mark[ids[np.concatenate([np.asarray(h, dtype=np.int64) for h in hits])]] = True
    return np.flatnonzero(mark[F].any(axis=1))


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
    P = np.ascontiguousarray(P, dtype=np.float64).reshape(-1, 3)
    if (labels is None or face_labels is None) and 0 < len(P) * FEW < len(F):
        # a few points on a large mesh (landmarks on a scan): an AABB tree over every triangle
        # costs more than the queries; only triangles that can hold a closest point are searched
        near = near_faces(P, V, F)
        C, face, bary, sqrd = _closest(P, V, np.asarray(F)[near])
        return C, near[face], bary, sqrd
    return _closest(P, V, F, labels, face_labels)


def _closest(P, V, F, labels=None, face_labels=None):
    n = len(P)
    if n == 0:
        return np.zeros((0, 3)), np.zeros(0, dtype=np.int64), np.zeros((0, 3)), np.zeros(0)
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
        for g in sorted_unique(labels[labels >= 0]):
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
