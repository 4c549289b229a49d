"""Triangle and per-vertex areas of a triangle mesh."""
import numpy as np


def triangle_areas(V, F):
    """``(m,)`` triangle areas, in squared mesh units."""
    return 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)


def vertex_areas(V, F):
    """``(n,)`` barycentric area per vertex: a third of each incident triangle's area
    (squared mesh units; zero for vertices in no face)."""
    return np.bincount(F.ravel(), weights=np.repeat(triangle_areas(V, F) / 3.0, 3), minlength=len(V))
