"""Pictures around the face and back to 3-D: cameras, lifting pixels to the surface, combining views.

Frames: every function here works in the canonical head frame (+Y up, +Z out of the face,
+X toward the subject's left), in the mesh's units scaled by :class:`autobones.orient.Frame`
(canonical units). Pixel coordinates are x = column, y = row, pixel centres at integers
(:mod:`autobones.render.camera`).
"""
from __future__ import annotations

import numpy as np

from ..geometry.areas import triangle_areas
from ..geometry.proxy import decimate_parts, mesh_proxy
from ..geometry.topology import mesh_parts, weld
from ..render.camera import Camera, look_at


def view_direction(yaw, pitch):
    """Unit (3,) canonical direction from the head toward a camera turned by ``yaw`` (toward
    the subject's left, +X) and ``pitch`` (upward) degrees from straight ahead (+Z)."""
    a, b = np.radians(yaw), np.radians(pitch)
    return np.array([np.sin(a) * np.cos(b), np.sin(b), np.cos(a) * np.cos(b)])


def face_camera(target, view_dir, width, size):
    """An orthographic camera looking at ``target`` (3,) along ``-view_dir``, ``width`` canonical
    units across the picture, ``size`` pixels square; world +Y shows upward."""
    view = look_at(np.asarray(target) + 4.0 * np.asarray(view_dir), target, (0.0, 1.0, 0.0))
    return Camera(view=view, scale=size / float(width), center=np.zeros(2), width=size, height=size)


# Pictures of a dense scan are drawn from a vertex-clustered copy of about PICTURE_VERTICES: a
# 512-pixel picture shows no more, and the rasteriser's cost grows with the triangles drawn. The
# landmarks are snapped to the full surface at the end.
PICTURE_ABOVE = 40000
PICTURE_VERTICES = 30000


def pictured_mesh(V, F, above=None, vertices=None):
    """The mesh to draw pictures of, and the skin on it and on the input.

    ``(V, F)`` itself up to ``above`` (default :data:`PICTURE_ABOVE`) vertices, else welded and
    each connected part vertex-clustered to a common fraction (about ``vertices``, default
    :data:`PICTURE_VERTICES`, in all). The skin is the connected part with the largest area (after
    welding coincident vertices) when it holds at least half the area, else every triangle:
    scanned or modelled heads often carry eyeballs, eyelashes, teeth in separate parts, and a
    landmark lifted from an oblique picture must land on the skin, not on an eyelash. A dense
    mesh's parts come from its welded copy, so they are found once.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int

    Returns
    -------
    Vp : (k, 3) float64
        Same frame and units as ``V`` (``V`` itself when small enough).
    Fp : (mp, 3) int64
    skin : (m,) bool
        The skin's triangles in ``F``.
    pictured_skin : (mp,) bool
        The skin's triangles in ``Fp``.
    """
    above = PICTURE_ABOVE if above is None else above
    vertices = PICTURE_VERTICES if vertices is None else vertices
    if len(V) <= above:
        skin = skin_faces(V, F)
        return V, F, skin, skin
    proxy = mesh_proxy(V, F, 1e-6 * float(np.ptp(V, axis=0).max()))
    if len(proxy.vertices) <= above:
        Vp, Fp = proxy.vertices, proxy.faces
        part = mesh_parts(len(Vp), Fp)
        pictured = part[Fp[:, 0]]
    else:
        Vp, Fp, part, pictured, _ = decimate_parts(proxy.vertices, proxy.faces, vertices, quadric=False)
    F = np.asarray(F, dtype=np.int64)
    face_part = part[proxy.index[F[:, 0]]]
    skin = _largest_by_area(face_part, triangle_areas(V, F))
    if skin is None:
        return Vp, Fp, np.ones(len(F), dtype=bool), np.ones(len(Fp), dtype=bool)
    return Vp, Fp, face_part == skin, pictured == skin


def _largest_by_area(face_part, area):
    """The part label holding the most area, or None when it holds less than half of it."""
    totals = np.bincount(face_part, weights=area)
    return None if totals.max() < 0.5 * totals.sum() else int(np.argmax(totals))


def skin_faces(V, F):
    """(m,) bool: the triangles of the skin, the connected part with the largest area (after
    welding coincident vertices), when it holds at least half the area; else every triangle."""
    _, _, index = weld(V, F, 1e-9 * max(float(np.ptp(V, axis=0).max()), 1e-300))
    part = mesh_parts(int(index.max()) + 1, index[F])[index[F[:, 0]]]
    skin = _largest_by_area(part, triangle_areas(V, F))
    return np.ones(len(F), dtype=bool) if skin is None else part == skin


def lift(points_at, covered, px, reach=3):
    """Surface points under pixel positions.

    Parameters
    ----------
    points_at : callable
        ``points_at(rows, cols)`` -> (k, 3) float, the surface point seen at those pixel
        centres (NaN where empty), e.g. :func:`autobones.render.surface_points` bound to a
        rendering: only the pixels around ``px`` are evaluated, not the whole picture.
    covered : (H, W) bool
        Pixels the surface covers.
    px : (k, 2) float
        Pixel coordinates (x = column, y = row).
    reach : int
        An empty pixel takes the nearest covered pixel within this many pixels.

    Returns
    -------
    (k, 3) float64
        Bilinear interpolation of the four surrounding pixels' points where all four
        are covered; else the nearest covered pixel within ``reach``; else NaN.
    """
    H, W = covered.shape
    px = np.asarray(px, dtype=np.float64)
    out = np.full((len(px), 3), np.nan)
    x0 = np.floor(px[:, 0]).astype(np.int64)
    y0 = np.floor(px[:, 1]).astype(np.int64)
    inside = (x0 >= 0) & (y0 >= 0) & (x0 < W - 1) & (y0 < H - 1)
    i = np.flatnonzero(inside)
    fx = (px[i, 0] - x0[i])[:, None]
    fy = (px[i, 1] - y0[i])[:, None]
    c = points_at(np.concatenate([y0[i] + dy for dy in (0, 0, 1, 1)]),
                  np.concatenate([x0[i] + dx for dx in (0, 1, 0, 1)])).reshape(4, len(i), 3)
    bil = (c[0] * (1 - fx) * (1 - fy) + c[1] * fx * (1 - fy) + c[2] * (1 - fx) * fy + c[3] * fx * fy)
    ok = np.all(np.isfinite(bil), axis=1)
    out[i[ok]] = bil[ok]
    rest = np.flatnonzero(~np.all(np.isfinite(out), axis=1) & np.all(np.isfinite(px), axis=1))
    if len(rest):
        # the covered pixel centres within reach lie in a window around each point
        span = np.arange(-reach, reach + 2)
        r = np.floor(px[rest, 1])[:, None, None].astype(np.int64) + span[None, :, None]
        q = np.floor(px[rest, 0])[:, None, None].astype(np.int64) + span[None, None, :]
        r, q = np.broadcast_arrays(r, q)
        d = np.hypot(q - px[rest, 0][:, None, None], r - px[rest, 1][:, None, None])
        valid = (r >= 0) & (r < H) & (q >= 0) & (q < W) & (d <= reach)
        valid[valid] = covered[r[valid], q[valid]]
        d = np.where(valid, d, np.inf).reshape(len(rest), -1)
        best = np.argmin(d, axis=1)
        near = np.isfinite(d[np.arange(len(rest)), best])
        pick = np.flatnonzero(near)
        out[rest[pick]] = points_at(r.reshape(len(rest), -1)[pick, best[pick]], q.reshape(len(rest), -1)[pick, best[pick]])
    return out


def weighted_median(X, w):
    """Per-coordinate weighted median of candidate points.

    Parameters
    ----------
    X : (v, k, 3) float
        ``v`` candidates for each of ``k`` points; NaN rows are ignored.
    w : (v, k) float
        Non-negative weights (0 ignores a candidate).

    Returns
    -------
    (k, 3) float64
        NaN where a point has no candidate with positive weight.
    """
    w = np.where(np.all(np.isfinite(X), axis=2), w, 0.0)
    out = np.full(X.shape[1:], np.nan)
    for d in range(3):
        x = np.where(w > 0, X[..., d], np.inf)
        order = np.argsort(x, axis=0)
        xs = np.take_along_axis(x, order, axis=0)
        ws = np.take_along_axis(w, order, axis=0)
        cw = np.cumsum(ws, axis=0)
        total = cw[-1]
        idx = np.argmax(cw >= 0.5 * total[None], axis=0)
        val = np.take_along_axis(xs, idx[None], axis=0)[0]
        out[:, d] = np.where(total > 0, val, np.nan)
    return out
