"""Triangle and per-vertex areas of a triangle mesh."""
import numpy as np

from .normals import triangle_normals


def triangle_areas(V, F):
    """``(m,)`` triangle areas, in squared mesh units."""
    return 0.5 * np.linalg.norm(triangle_normals(V, F), axis=1)


def vertex_areas(V, F):
    """``(n,)`` barycentric area per vertex: a third of each incident triangle's area
    (squared mesh units; zero for vertices in no face)."""
    return np.bincount(F.ravel(), weights=np.repeat(triangle_areas(V, F) / 3.0, 3), minlength=len(V))
