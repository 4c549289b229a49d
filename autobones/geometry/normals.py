"""Triangle and vertex normals of a triangle mesh."""
import numpy as np


def triangle_normals(V, F):
    """Unnormalised face normals ``(m, 3)``: the cross product of two edges (twice the area vector).

    Parameters
    ----------
    V : (n, 3) float
        Vertices, any frame and unit.
    F : (m, 3) int
        Triangles.
    """
    a = V[F[:, 0]]
    return cross_rows(V[F[:, 1]] - a, V[F[:, 2]] - a)


def cross_rows(a, b):
    """Row-wise cross products ``(k, 3)`` of ``a`` and ``b`` (k, 3) (either may broadcast as (1, 3)).

    Component by component: ``np.cross`` moves axes about, and took 2.5x as long on scans (and
    far longer in loops over small arrays).
    """
    N = np.empty(np.broadcast_shapes(a.shape, b.shape), dtype=np.result_type(a, b))
    N[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    N[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    N[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return N


def vertex_normals(V, F):
    """Area-weighted unit vertex normals.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int

    Returns
    -------
    (n, 3) float64
        Sum of the adjacent triangles' normals weighted by area, normalised; zero rows for
        vertices on no non-degenerate triangle (non-finite triangle normals count as zero).
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64).reshape(-1, 3)
    N = np.zeros_like(V)
    if len(F):
        fn = triangle_normals(V, F)
        fn[~np.all(np.isfinite(fn), axis=1)] = 0.0
        idx = F.reshape(-1)
        for d in range(3):
            N[:, d] = np.bincount(idx, weights=np.repeat(fn[:, d], 3), minlength=len(V))
    n = np.linalg.norm(N, axis=1, keepdims=True)
    return np.divide(N, n, out=np.zeros_like(N), where=n > 0)
