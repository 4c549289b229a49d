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

from ..errors import AutobonesError
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
