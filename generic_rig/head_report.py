"""Quality report and picture of a built head mesh.

``check`` and ``self_intersections`` give the statistics printed by
``build_default_head.py --check``; ``render`` draws the three-view picture of
``--render``.  Meshes are V (n, 3) float in metres (+Y up, +Z front) and
F (m, 3) int, outward oriented.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from .half_mesh import tri_angles
from .implicit_primitives import rot_y


def check(V, F):
    """Mesh statistics: {name: value} (topology, symmetry, angles in degrees, bbox in m)."""
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    und = np.sort(e, axis=1)
    _, cnt = np.unique(und, axis=0, return_counts=True)
    _, dcnt = np.unique(e, axis=0, return_counts=True)
    n = len(V)
    A = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    ncomp, _ = connected_components(A, directed=False)
    ang = tri_angles(V, F).min(1)
    # symmetry: distance from each mirrored vertex to the nearest vertex
    dist, _ = cKDTree(V).query(V * np.array([-1, 1, 1]))
    # volume (outward orientation -> positive)
    v0, v1, v2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    vol = np.einsum("ij,ij->i", v0, np.cross(v1, v2)).sum() / 6
    chi = len(V) - len(cnt) + len(F)
    return dict(
        vertices=len(V), triangles=len(F),
        every_edge_two_faces=bool((cnt == 2).all()),
        consistent_orientation=bool((dcnt == 1).all()),
        components=int(ncomp), euler=int(chi), volume_m3=float(vol),
        symmetry_max_err=float(dist.max()),
        min_angle=float(ang.min()), min_angle_p1=float(np.percentile(ang, 1)),
        min_angle_p5=float(np.percentile(ang, 5)),
        min_angle_median=float(np.median(ang)),
        frac_min_angle_lt_20=float((ang < 20).mean()),
        bbox_min=V.min(0).round(4).tolist(), bbox_max=V.max(0).round(4).tolist(),
    )


def self_intersections(V, F):
    """Number of non-adjacent triangle pairs where an edge of one crosses the other."""
    c = V[F].mean(1)
    rad = np.linalg.norm(V[F] - c[:, None], axis=2).max(1)
    pairs = cKDTree(c).query_pairs(2 * rad.max(), output_type="ndarray")
    i, j = pairs[:, 0], pairs[:, 1]
    close = np.linalg.norm(c[i] - c[j], axis=1) <= rad[i] + rad[j]
    i, j = i[close], j[close]
    share = (F[i][:, :, None] == F[j][:, None, :]).any((1, 2))
    i, j = i[~share], j[~share]
    hits = np.zeros(len(i), bool)
    for (a, b) in ((i, j), (j, i)):
        T = V[F[b]]
        for k in range(3):
            p0 = V[F[a][:, k]]
            p1 = V[F[a][:, (k + 1) % 3]]
            hits |= _seg_tri(p0, p1, T)
    return int(hits.sum())


def _seg_tri(p0, p1, T):
    """(k,) bool: segment p0-p1 (each (k, 3)) meets triangle T (k, 3, 3).

    Möller & Trumbore (1997) ray-triangle test restricted to t in [0, 1].
    """
    e1 = T[:, 1] - T[:, 0]
    e2 = T[:, 2] - T[:, 0]
    d = p1 - p0
    h = np.cross(d, e2)
    a = np.einsum("ij,ij->i", e1, h)
    ok = np.abs(a) > 1e-18
    f = np.where(ok, 1.0 / np.where(ok, a, 1), 0)
    s = p0 - T[:, 0]
    u = f * np.einsum("ij,ij->i", s, h)
    q = np.cross(s, e1)
    v = f * np.einsum("ij,ij->i", d, q)
    t = f * np.einsum("ij,ij->i", e2, q)
    return ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0) & (t <= 1)


def _vertex_normals(V, F):
    """(n, 3) unit area-weighted vertex normals; the flat neck cap is left out
    so the cap's rim renders as a sharp edge."""
    fn = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    cap = fn[:, 1] < -0.95 * np.linalg.norm(fn, axis=1)
    fn = fn * ~cap[:, None]
    vn = np.zeros_like(V)
    for k in range(3):
        np.add.at(vn, F[:, k], fn)
    return vn / np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-30)


def _raster_triangle(img, zb, xs_, ys_, zs_, sh_, size):
    """Z-buffer one screen triangle (pixel coords xs_, ys_, depths zs_, shades sh_)."""
    x0, x1 = int(np.floor(xs_.min())), int(np.ceil(xs_.max()))
    y0, y1 = int(np.floor(ys_.min())), int(np.ceil(ys_.max()))
    x0, y0 = max(x0, 0), max(y0, 0)
    x1, y1 = min(x1, size - 1), min(y1, size - 1)
    if x1 < x0 or y1 < y0:
        return
    gx, gy = np.meshgrid(np.arange(x0, x1 + 1) + 0.5, np.arange(y0, y1 + 1) + 0.5)
    (ax, bx, cx), (ay, by, cy) = xs_, ys_
    den = (by - cy) * (ax - cx) + (cx - bx) * (ay - cy)
    if abs(den) < 1e-12:
        return
    l0 = ((by - cy) * (gx - cx) + (cx - bx) * (gy - cy)) / den
    l1 = ((cy - ay) * (gx - cx) + (ax - cx) * (gy - cy)) / den
    l2 = 1 - l0 - l1
    m = (l0 >= -1e-6) & (l1 >= -1e-6) & (l2 >= -1e-6)
    if not m.any():
        return
    zz = l0 * zs_[0] + l1 * zs_[1] + l2 * zs_[2]
    sh = l0 * sh_[0] + l1 * sh_[1] + l2 * sh_[2]
    iy, ix = gy[m].astype(int), gx[m].astype(int)
    upd = zz[m] > zb[iy, ix]
    zb[iy[upd], ix[upd]] = zz[m][upd]
    img[iy[upd], ix[upd]] = sh[m][upd]


def _view(V, vn, F, ang, size, span, center):
    """(size, size) grey image in [0, 1] of the head turned ``ang`` deg about +Y.

    Orthographic camera on +Z; ``span`` (m) is the image width, ``center``
    the (x, y) it is centred on; one directional light from upper left front.
    """
    R = rot_y(ang)
    P = V @ R.T
    N = vn @ R.T
    c = np.array([center[0], center[1], 0.0])
    s = size / span
    px = (P[:, 0] - c[0]) * s + size / 2
    py = size / 2 - (P[:, 1] - c[1]) * s
    zb = np.full((size, size), -np.inf)
    img = np.ones((size, size))
    L = np.array([-0.35, 0.45, 0.82])
    L /= np.linalg.norm(L)
    shade = np.clip(N @ L, 0, 1) * 0.8 + 0.2
    for f in F:
        _raster_triangle(img, zb, px[f], py[f], P[f, 2], shade[f], size)
    return img


def render(V, F, path, size=520, span=0.36, center=(0.0, 0.075), angles=(0.0, 35.0, 90.0)):
    """Write a PNG at ``path``: orthographic views (front, 3/4, side), smooth-shaded."""
    import matplotlib                  # only this diagnostic picture needs it
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    vn = _vertex_normals(V, F)
    imgs = [_view(V, vn, F, ang, size, span, center) for ang in angles]
    fig, axs = plt.subplots(1, len(imgs), figsize=(len(imgs) * size / 100, size / 100), dpi=100)
    for a, im, t in zip(np.atleast_1d(axs), imgs, angles):
        a.imshow(im, cmap="gray", vmin=0, vmax=1)
        a.set_title({0.0: "front", 90.0: "side"}.get(t, f"{t:g} deg"))
        a.axis("off")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
