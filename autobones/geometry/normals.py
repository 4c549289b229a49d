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
    return np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])


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
