"""Depth-buffered rasterisation of triangle meshes on the CPU: which triangle, where, under each
pixel; the surface point seen at each pixel; Lambert shading.

Goes beyond the papers the project implements: the gallery needs pictures of rigged heads,
and 2-D face landmark detection needs a rendered head whose every pixel can be lifted back
to a triangle and a 3-D point on it. No display, GPU or OpenGL: numpy only. Cameras and
pixel conventions: :mod:`autobones.render.camera`.

Rasterisation
    A pixel is covered by a triangle when its centre lies inside it (closed
    triangle, with a tiny tolerance so shared edges leave no gaps). Triangles
    are rasterised in vectorised batches: every triangle contributes the
    pixels of its bounding box, flattened into one candidate list per batch,
    and a depth buffer keeps the nearest fragment per pixel. Barycentric
    coordinates in the image are also the 3-D barycentric coordinates (the
    projection is affine).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..errors import AutobonesError
from ..geometry.normals import triangle_normals, vertex_normals
from ..geometry.validate import mesh_arrays
from .camera import Camera, unit_vector

# At most this many candidate pixels (triangle bounding-box pixels) per batch.
_BATCH = 1 << 21
# Barycentric tolerance for "inside": pixel centres on a shared edge are
# covered by both triangles instead of neither.
_INSIDE_EPS = 1e-9

DEFAULT_COLOR = (0.78, 0.78, 0.78)


@dataclass
class RenderBuffers:
    """Per-pixel results of :func:`rasterize`.

    Attributes
    ----------
    depth : (H, W) float64
        Depth of the nearest surface (world units from the camera plane);
        ``inf`` where no triangle covers the pixel.
    face_id : (H, W) int64
        Index into ``F`` of the visible triangle; -1 where empty.
    bary : (H, W, 3) float64
        Barycentric coordinates of the pixel centre in that triangle (weights
        of ``F[face_id, 0..2]``); 0 where empty.
    camera : Camera
        The camera that produced them.
    """

    depth: np.ndarray
    face_id: np.ndarray
    bary: np.ndarray
    camera: Camera

    @property
    def mask(self):
        """(H, W) bool: pixels covered by the mesh."""
        return self.face_id >= 0


def rasterize(V, F, camera):
    """Depth-buffered rasterisation: which triangle, where, under each pixel.

    Parameters
    ----------
    V : (n, 3) float
        Vertices, world coordinates.
    F : (m, 3) int
        Triangles. Degenerate triangles (zero area in the image) and triangles
        with non-finite vertices cover no pixels; both sides of every triangle
        are drawn.
    camera : Camera
        See :func:`orthographic_camera`.

    Returns
    -------
    RenderBuffers
        ``depth``, ``face_id``, ``bary`` of shape (H, W[, 3]), H and W the
        camera's height and width.

    Examples
    --------
    >>> import trimesh
    >>> m = trimesh.creation.icosphere(3)
    >>> cam = orthographic_camera(m.vertices, (0, 0, 1), size=(64, 64))
    >>> buf = rasterize(m.vertices, m.faces, cam)
    >>> buf.face_id.shape, bool(buf.mask[32, 32])
    ((64, 64), True)
    """
    V, F = mesh_arrays(V, F, "mesh", allow_no_faces=True, finite=False)
    W, H = int(camera.width), int(camera.height)
    zbuf = np.full(W * H, np.inf)
    fbuf = np.full(W * H, -1, dtype=np.int64)
    bbuf = np.zeros((W * H, 3))
    if len(F) and len(V):
        px, dep = camera.project(V)
        tri, edges = _edge_functions(px[F], dep[F], W, H)
        for s, e in _batches(edges.count):
            _fill_batch(tri, edges, s, e, W, zbuf, fbuf, bbuf)
    return RenderBuffers(zbuf.reshape(H, W), fbuf.reshape(H, W), bbuf.reshape(H, W, 3), camera)


class _Edges(NamedTuple):
    """Per kept triangle: barycentric coordinates as affine functions of the pixel offset
    (dx, dy) from its bounding box's top-left pixel, ``l_k = lko + ak dx + bk dy`` (k = 0, 1;
    ``l_2 = 1 - l_0 - l_1``), its vertex depths, and its box (width, pixel count, first pixel)."""

    a0: np.ndarray
    b0: np.ndarray
    a1: np.ndarray
    b1: np.ndarray
    l0o: np.ndarray
    l1o: np.ndarray
    z0: np.ndarray
    z1: np.ndarray
    z2: np.ndarray
    bw: np.ndarray
    count: np.ndarray
    base: np.ndarray


def _edge_functions(T, Z, W, H):
    """The triangles that can cover a pixel and their :class:`_Edges`.

    ``T`` (m, 3, 2) float: the triangles' pixel coordinates; ``Z`` (m, 3) float: their depths;
    ``W``, ``H``: image size. Returns ``tri`` (t,) int64, indices of the kept triangles (finite,
    not degenerate in the image, bounding box on the image), and their edges.
    """
    x0, y0 = T[:, 0, 0], T[:, 0, 1]
    x1, y1 = T[:, 1, 0], T[:, 1, 1]
    x2, y2 = T[:, 2, 0], T[:, 2, 1]
    with np.errstate(invalid="ignore", over="ignore"):
        area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
        finite = np.all(np.isfinite(T), axis=(1, 2)) & np.all(np.isfinite(Z), axis=1)
        xmin = np.ceil(np.clip(T[:, :, 0].min(axis=1), -1, W)).astype(np.int64)
        xmax = np.floor(np.clip(T[:, :, 0].max(axis=1), -1, W)).astype(np.int64)
        ymin = np.ceil(np.clip(T[:, :, 1].min(axis=1), -1, H)).astype(np.int64)
        ymax = np.floor(np.clip(T[:, :, 1].max(axis=1), -1, H)).astype(np.int64)
    xmin, ymin = np.maximum(xmin, 0), np.maximum(ymin, 0)
    xmax, ymax = np.minimum(xmax, W - 1), np.minimum(ymax, H - 1)
    keep = finite & (np.abs(area) > 1e-12) & (xmax >= xmin) & (ymax >= ymin)
    tri = np.flatnonzero(keep)
    # l_k(x, y) = a_k x + b_k y + c_k, evaluated at the bounding-box corner plus
    # increments, per triangle
    inv = 1.0 / area[tri]
    x0, y0, x1, y1, x2, y2 = (a[tri] for a in (x0, y0, x1, y1, x2, y2))
    ox, oy = xmin[tri].astype(np.float64), ymin[tri].astype(np.float64)
    bw = xmax[tri] - xmin[tri] + 1
    return tri, _Edges(
        a0=(y1 - y2) * inv, b0=(x2 - x1) * inv, a1=(y2 - y0) * inv, b1=(x0 - x2) * inv,
        l0o=((x1 - ox) * (y2 - oy) - (x2 - ox) * (y1 - oy)) * inv,
        l1o=((x2 - ox) * (y0 - oy) - (x0 - ox) * (y2 - oy)) * inv,
        z0=Z[tri, 0], z1=Z[tri, 1], z2=Z[tri, 2],
        bw=bw, count=bw * (ymax[tri] - ymin[tri] + 1), base=ymin[tri] * W + xmin[tri])


def _batches(count):
    """(start, end) ranges of consecutive triangles holding about ``_BATCH`` candidate pixels
    each, from the (t,) pixel counts of their bounding boxes; none when ``t == 0``."""
    if len(count) == 0:
        return []
    ends = np.cumsum(count)
    cuts = np.searchsorted(ends, np.arange(_BATCH, ends[-1], _BATCH), side="left") + 1
    bounds = np.unique(np.concatenate([[0], cuts, [len(count)]]))
    return list(zip(bounds[:-1], bounds[1:]))


def _fill_batch(tri, edges, s, e, W, zbuf, fbuf, bbuf):
    """Rasterise the kept triangles ``s:e`` into the flat buffers (modified in place): every
    bounding-box pixel whose centre is inside, nearest fragment wins."""
    c = edges.count[s:e]
    t = np.repeat(np.arange(s, e), c)              # local triangle per candidate
    starts = np.cumsum(c) - c
    off = np.arange(len(t)) - np.repeat(starts, c)
    w = edges.bw[t]
    dy = off // w
    dx = off - dy * w
    l0 = edges.l0o[t] + edges.a0[t] * dx + edges.b0[t] * dy
    l1 = edges.l1o[t] + edges.a1[t] * dx + edges.b1[t] * dy
    l2 = 1.0 - l0 - l1
    inside = np.flatnonzero((l0 >= -_INSIDE_EPS) & (l1 >= -_INSIDE_EPS) & (l2 >= -_INSIDE_EPS))
    if len(inside) == 0:
        return
    t, l0, l1, l2 = t[inside], l0[inside], l1[inside], l2[inside]
    pix = edges.base[t] + dy[inside] * W + dx[inside]
    z = l0 * edges.z0[t] + l1 * edges.z1[t] + l2 * edges.z2[t]
    np.minimum.at(zbuf, pix, z)
    win = np.flatnonzero(z <= zbuf[pix])
    if len(win) == 0:
        return
    # One winner per pixel even on exact depth ties, so face and bary come
    # from the same fragment (repeated pixels in pw then write equal values).
    pw = pix[win]
    pick = np.empty(len(zbuf), dtype=np.int64)
    pick[pw] = win
    f = pick[pw]
    fbuf[pw] = tri[t[f]]
    bbuf[pw, 0], bbuf[pw, 1], bbuf[pw, 2] = l0[f], l1[f], l2[f]


def surface_points(V, F, buffers, rows=None, cols=None):
    """The 3-D surface point seen at pixel centres.

    Parameters
    ----------
    V : (n, 3) float
        The vertices that were rasterised, world coordinates.
    F : (m, 3) int
        The triangles that were rasterised.
    buffers : RenderBuffers
        From :func:`rasterize` ``(V, F, camera)``.
    rows, cols : (k,) int or None
        Only these pixels (in range); None: every pixel.

    Returns
    -------
    (H, W, 3) float64, or (k, 3) with ``rows`` and ``cols``
        World point under each pixel (on triangle ``face_id`` at ``bary``);
        NaN where empty.
    """
    V, F = mesh_arrays(V, F, "mesh", allow_no_faces=True, finite=False)
    if rows is None:
        face, bary = buffers.face_id, buffers.bary
    else:
        face, bary = buffers.face_id[rows, cols], buffers.bary[rows, cols]
    P = np.full(face.shape + (3,), np.nan)
    m = face >= 0
    if m.any():
        tri = F[face[m]]                                  # (k, 3)
        P[m] = np.einsum("kj,kjd->kd", bary[m], V[tri])
    return P


def shade(V, F, buffers, vertex_colors=None, light_dir=None, ambient=0.25):
    """Lambert-shade the rasterised mesh.

    Parameters
    ----------
    V : (n, 3) float
        The vertices that were rasterised, world coordinates.
    F : (m, 3) int
        The triangles that were rasterised.
    buffers : RenderBuffers
        From :func:`rasterize`.
    vertex_colors : (n, 3) float in [0, 1], (n, 3) uint8, or None
        Per-vertex RGB, interpolated barycentrically; None gives light grey.
    light_dir : (3,) float or None
        World direction toward a directional light; None puts the light
        behind the camera, a little up and to the left in the image.
    ambient : float
        Brightness of a surface edge-on to the light, in [0, 1].

    Returns
    -------
    (H, W, 3) uint8
        ``color * (ambient + (1 - ambient) * |n . l|)`` with ``n`` the
        interpolated area-weighted vertex normal (the triangle's own normal
        where the vertex normals cancel); two-sided, white background.
    """
    V, F = mesh_arrays(V, F, "mesh", allow_no_faces=True, finite=False)
    H, W = buffers.face_id.shape
    img = np.full((H, W, 3), 255, dtype=np.uint8)
    m = buffers.mask
    if not m.any():
        return img
    if light_dir is None:
        R = buffers.camera.view[:3, :3]
        light = R.T @ np.array([-0.35, 0.45, 1.0])
        light /= np.linalg.norm(light)
    else:
        light = unit_vector(light_dir, "light_dir")
    fid = buffers.face_id[m]
    b = buffers.bary[m]
    tri = F[fid]
    VN = vertex_normals(V, F)
    n = np.einsum("kj,kjd->kd", b, VN[tri])
    ln = np.linalg.norm(n, axis=1)
    bad = ln < 1e-6
    if bad.any():
        n[bad] = triangle_normals(V, tri[bad])
        ln[bad] = np.linalg.norm(n[bad], axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        lam = np.abs(n @ light) / ln
    lam = np.nan_to_num(lam, nan=0.0, posinf=0.0)
    if vertex_colors is None:
        col = np.broadcast_to(np.array(DEFAULT_COLOR), (len(fid), 3))
    else:
        C = np.asarray(vertex_colors)
        if C.shape != (len(V), 3):
            raise AutobonesError(
                f"vertex_colors must be ({len(V)}, 3) RGB, one row per vertex; got shape {C.shape}")
        C = C / 255.0 if np.issubdtype(C.dtype, np.integer) else C.astype(np.float64)
        col = np.einsum("kj,kjd->kd", b, np.clip(C, 0.0, 1.0)[tri])
    a = float(ambient)
    val = col * (a + (1.0 - a) * np.clip(lam, 0.0, 1.0))[:, None]
    img[m] = np.clip(np.rint(val * 255.0), 0, 255).astype(np.uint8)
    return img
