"""Improve a decimated half head: Delaunay edge flips and tangential relaxation.

Meshes are ``V`` (n, 3) float (metres) and ``F`` (m, 3) int, outward
oriented, open along the plane x = 0.  Border vertices stay in that plane:
they slide along it, interior vertices slide over the surface, and every
move is re-projected onto the dense marching-cubes reference surface so the
shape does not shrink.
"""

from __future__ import annotations

import igl
import numpy as np

from .half_mesh import boundary_edges, tri_angles


def _directed_edge_map(F):
    """{(u, v): (face index, opposite vertex)} for every directed edge of F."""
    edge_map = {}
    for fi, (a, b, c) in enumerate(F):
        for (u, v, w) in ((a, b, c), (b, c, a), (c, a, b)):
            edge_map[(u, v)] = (fi, w)
    return edge_map


def _angle(at, p, q):
    """Angle (radians) at point ``at`` between the directions to p and q (each (3,))."""
    a_, b_ = p - at, q - at
    return np.arccos(np.clip(a_ @ b_ / (np.linalg.norm(a_) * np.linalg.norm(b_)
                                        + 1e-30), -1, 1))


def _flip_improves(V, u, v, w1, w2, max_normal_deg):
    """Whether flipping edge u-v (faces (u, v, w1), (v, u, w2)) to w1-w2 helps.

    Requires: the Delaunay criterion fails (opposite angles sum > 180 deg);
    the two faces are nearly coplanar (within ``max_normal_deg``), so the
    flip does not change the shape; the new faces keep the orientation; and
    the smallest angle of the pair grows.
    """
    pu, pv, p1, p2 = V[u], V[v], V[w1], V[w2]
    if _angle(p1, pu, pv) + _angle(p2, pu, pv) <= np.pi + 1e-9:
        return False
    n1 = np.cross(pv - pu, p1 - pu)
    n2 = np.cross(pu - pv, p2 - pv)
    n1 /= np.linalg.norm(n1) + 1e-30
    n2 /= np.linalg.norm(n2) + 1e-30
    if n1 @ n2 < np.cos(np.radians(max_normal_deg)):
        return False
    na = np.cross(pu - p1, p2 - p1)
    nb = np.cross(pv - p2, p1 - p2)
    if na @ (n1 + n2) <= 0 or nb @ (n1 + n2) <= 0:
        return False
    old = min(tri_angles(V, np.array([[u, v, w1], [v, u, w2]])).min(), 180)
    new = tri_angles(V, np.array([[w1, u, w2], [w2, v, w1]])).min()
    return new > old


def _flip(F, edge_map, u, v, f1, w1, f2, w2):
    """Replace faces f1, f2 by (w1, u, w2), (w2, v, w1) in F and edge_map, in place."""
    F[f1] = (w1, u, w2)
    F[f2] = (w2, v, w1)
    for key in ((u, v), (v, u)):
        edge_map.pop(key, None)
    edge_map[(w1, u)] = (f1, w2)
    edge_map[(u, w2)] = (f1, w1)
    edge_map[(w2, w1)] = (f1, u)
    edge_map[(w2, v)] = (f2, w1)
    edge_map[(v, w1)] = (f2, w2)
    edge_map[(w1, w2)] = (f2, v)


def _flip_pass(V, F, border_v, max_normal_deg):
    """One sweep over the edges (in sorted order, for determinism): flips made."""
    nflip = 0
    edge_map = _directed_edge_map(F)
    done = set()
    # the sorted snapshot can be stale after a flip; the face checks below catch it
    for (u, v), (f1, w1) in sorted(edge_map.items()):
        if (v, u) not in edge_map or (min(u, v), max(u, v)) in done:
            continue
        f2, w2 = edge_map[(v, u)]
        done.add((min(u, v), max(u, v)))
        if set(F[f1]) != {u, v, w1} or set(F[f2]) != {u, v, w2}:
            continue
        if w1 == w2 or (w1, w2) in edge_map or (w2, w1) in edge_map:
            continue                    # tetrahedron corner or existing edge
        if border_v[w1] and border_v[w2]:
            continue                    # would make a face lying in x = 0
        if not _flip_improves(V, u, v, w1, w2, max_normal_deg):
            continue
        _flip(F, edge_map, u, v, f1, w1, f2, w2)
        nflip += 1
    return nflip


def delaunay_flips(V, F, border_v, max_normal_deg=25.0, passes=6):
    """Flip interior edges that break the Delaunay criterion on near-flat pairs.

    ``border_v`` (n,) bool marks the x = 0 border vertices.  Returns a new
    F (m, 3); V is not changed.  Stops early after a pass without flips.
    """
    F = F.copy()
    for _ in range(passes):
        if _flip_pass(V, F, border_v, max_normal_deg) == 0:
            break
    return F


def _nearest_on_segments_2d(q, ra, rb, chunk=256):
    """Closest points (k, 2) to q (k, 2) on the segments ra[i]-rb[i] (each (s, 2)).

    Chunked over segments to bound memory; ties keep the first segment.
    """
    ab = rb - ra
    best = np.full(len(q), np.inf)
    bp = np.zeros_like(q)
    for s in range(0, len(ra), chunk):
        A = ra[s:s + chunk]
        AB = ab[s:s + chunk]
        t = np.clip(((q[:, None, :] - A[None]) * AB[None]).sum(-1)
                    / np.maximum((AB * AB).sum(-1), 1e-30)[None], 0, 1)
        pts = A[None] + t[..., None] * AB[None]
        dd = ((q[:, None, :] - pts) ** 2).sum(-1)
        j = dd.argmin(1)
        dj = dd[np.arange(len(q)), j]
        upd = dj < best
        best[upd] = dj[upd]
        bp[upd] = pts[np.arange(len(q)), j][upd]
    return bp


def _relax_step(V, F, be, on_b, lam):
    """Move vertices ``lam`` of the way to their smoothing target: new V (n, 3).

    Interior: the area-weighted centroid of the one-ring face centroids
    (CVT-like), minus its normal component.  Border: the mean of the two
    border neighbours.
    """
    n = len(V)
    v0, v1, v2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    fa = 0.5 * np.linalg.norm(np.cross(v1 - v0, v2 - v0), axis=1)
    fc = (v0 + v1 + v2) / 3
    acc = np.zeros((n, 3))
    w = np.zeros(n)
    for k in range(3):
        np.add.at(acc, F[:, k], fc * fa[:, None])
        np.add.at(w, F[:, k], fa)
    target = acc / np.maximum(w, 1e-30)[:, None]
    N = igl.per_vertex_normals(V, F)
    d = target - V
    d -= (d * N).sum(1, keepdims=True) * N
    bt = np.zeros((n, 3))
    bc = np.zeros(n)
    np.add.at(bt, be[:, 0], V[be[:, 1]])
    np.add.at(bt, be[:, 1], V[be[:, 0]])
    np.add.at(bc, be[:, 0], 1)
    np.add.at(bc, be[:, 1], 1)
    db = bt / np.maximum(bc, 1)[:, None] - V
    d[on_b] = db[on_b]
    return V + lam * d


def relax(V, F, refV, refF, iters=8, lam=0.5):
    """Tangential relaxation of V (n, 3) with re-projection onto (refV, refF).

    Interior vertices go to the closest point of the reference surface;
    x = 0 border vertices to the closest point of the reference border
    polyline within the plane x = 0.  Returns the new V (n, 3); F unchanged.
    """
    V = V.copy()
    be = boundary_edges(F)
    on_b = np.zeros(len(V), bool)
    on_b[be.ravel()] = True
    rbe = boundary_edges(refF)
    ra, rb = refV[rbe[:, 0]][:, 1:], refV[rbe[:, 1]][:, 1:]     # (y, z) only
    for _ in range(iters):
        Vn = _relax_step(V, F, be, on_b, lam)
        inner = ~on_b
        _, _, C = igl.point_mesh_squared_distance(Vn[inner], refV, refF)
        Vn[inner] = C
        Vb = np.zeros((on_b.sum(), 3))
        Vb[:, 1:] = _nearest_on_segments_2d(Vn[on_b][:, 1:], ra, rb)
        Vn[on_b] = Vb
        V = Vn
    return V
