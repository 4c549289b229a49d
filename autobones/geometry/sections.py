"""Points along a mesh's sections by parallel planes: a profile read from the surface itself.

A profile read from a random surface sample or from the vertices near a plane depends on the draw and
on the tessellation: a 1% height bin of a 3% midline strip holds a few points on a 4k-vertex head, some
tens on the same surface split 1-to-4, and a bin's front-most point then moved by up to 0.04 head sizes
(the chin step read from it by up to 0.45: ``benchmarks/README.md``, "the same surface, four times the
vertices"). The planes' sections are the surface's own curves, so their points, spaced along each curve,
fill every bin whatever the mesh's resolution.
"""
from __future__ import annotations

import numpy as np


def section_points(V, F, axis, offsets, spacing):
    """Points on the sections of a mesh by the planes ``x[axis] = offset``, at most ``spacing`` apart.

    Parameters
    ----------
    V : (n, 3) float
        Vertices, any frame and unit.
    F : (m, 3) int
        Triangles.
    axis : int
        The planes' normal axis (0, 1 or 2).
    offsets : (k,) float
        The planes' positions along ``axis``, units of ``V``.
    spacing : float
        Largest gap between consecutive points along a section's segment, units of ``V``.

    Returns
    -------
    P : (p, 3) float64
        Each segment's two ends and the points between them; ordered by plane, then by triangle.
    """
    import trimesh

    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    offsets = np.atleast_1d(np.asarray(offsets, dtype=np.float64))
    if len(F) == 0 or len(offsets) == 0:
        return np.empty((0, 3))
    # only the triangles that reach the planes' span (a midline strip is a few % of a head)
    x = V[F, axis]
    F = F[(x.min(axis=1) <= np.max(offsets)) & (x.max(axis=1) >= np.min(offsets))]
    # trimesh's plane section (a well-kept one: the edge crossings of every triangle the plane cuts,
    # vertices on the plane handled); process=False keeps the faces as given
    mesh = trimesh.Trimesh(V, F, process=False, validate=False)
    normal = np.eye(3)[axis]
    segments = [trimesh.intersections.mesh_plane(mesh, normal, normal * float(c)) for c in offsets]
    S = np.concatenate([s.reshape(-1, 2, 3) for s in segments])
    if len(S) == 0:
        return np.empty((0, 3))
    length = np.linalg.norm(S[:, 1] - S[:, 0], axis=1)
    steps = np.maximum(np.ceil(length / spacing).astype(np.int64), 1)
    # each segment's steps + 1 points at fractions 0, 1/steps, ..., 1 along it: a point's fraction is its
    # index less its segment's first index, over its segment's steps
    seg = np.repeat(np.arange(len(S)), steps + 1)
    first = np.cumsum(steps + 1) - (steps + 1)
    t = (np.arange(len(seg)) - first[seg]) / steps[seg]
    return S[seg, 0] + t[:, None] * (S[seg, 1] - S[seg, 0])
