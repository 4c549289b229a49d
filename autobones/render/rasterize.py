"""A small CPU renderer for triangle meshes: pictures for the gallery, pixel -> surface maps.

Goes beyond the seeds: the gallery needs pictures of rigged heads, and 2-D face
landmark detection needs a rendered head whose every pixel can be lifted back
to a triangle and a 3-D point on it. No display, GPU or OpenGL: numpy only,
Pillow for markers, text and PNG files.

Conventions
-----------
World frame
    Whatever frame ``V`` is in; :func:`render_views` assumes the canonical head
    frame (+Y up, +Z out of the face, +X toward the subject's own left ear).
Camera frame
    OpenGL convention: the camera looks along its -Z axis, +Y is up in the
    image, +X is right in the image. :func:`look_at` builds the world -> camera
    matrix.
Projection
    Orthographic. A camera-space point (xc, yc, zc) lands on pixel coordinates
    ``x = (W - 1)/2 + scale * (xc - center[0])`` (columns, rightward) and
    ``y = (H - 1)/2 - scale * (yc - center[1])`` (rows, downward), so pixel
    ``[row, col]`` of an image array has its centre at ``(x, y) = (col, row)``;
    the same convention as Pillow's drawing coordinates. Depth is ``-zc``: the
    distance in world units in front of the camera plane, growing away from the
    camera. There is no near or far plane.

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

from dataclasses import dataclass, replace

import numpy as np

from ..errors import AutobonesError
from ..geometry.normals import vertex_normals
from ..geometry.validate import mesh_arrays

# At most this many candidate pixels (triangle bounding-box pixels) per batch.
_BATCH = 1 << 21
# Barycentric tolerance for "inside": pixel centres on a shared edge are
# covered by both triangles instead of neither.
_INSIDE_EPS = 1e-9

DEFAULT_COLOR = (0.78, 0.78, 0.78)

# name -> (view_dir, up) in the canonical head frame; view_dir points from the
# head toward the camera.
VIEWS = {
    "front": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    "side": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    "left": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    "right": ((-1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    "three_quarter": ((1.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    "back": ((0.0, 0.0, -1.0), (0.0, 1.0, 0.0)),
    "top": ((0.0, 1.0, 0.0), (0.0, 0.0, -1.0)),
    "bottom": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
}


# ---------------------------------------------------------------------------
# cameras


def _unit(v, what):
    v = np.asarray(v, dtype=np.float64).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise AutobonesError(f"{what} must be 3 finite numbers, got {v!r}")
    n = np.linalg.norm(v)
    if n < 1e-12:
        raise AutobonesError(f"{what} must not be the zero vector")
    return v / n


def look_at(eye, target, up):
    """World -> camera matrix of a camera at ``eye`` looking at ``target``.

    Parameters
    ----------
    eye, target : (3,) float
        Camera position and the point it looks at, world coordinates and units.
    up : (3,) float
        World direction that should appear upward in the image; must not be
        parallel to ``target - eye``.

    Returns
    -------
    (4, 4) float64
        Homogeneous rigid transform world -> camera; OpenGL convention: the
        camera looks along its -Z axis, +Y up, +X right.

    Examples
    --------
    >>> M = look_at((0, 0, 5), (0, 0, 0), (0, 1, 0))
    >>> (M @ [0, 0, 0, 1])[:3]
    array([ 0.,  0., -5.])
    """
    eye = np.asarray(eye, dtype=np.float64).reshape(3)
    target = np.asarray(target, dtype=np.float64).reshape(3)
    z = _unit(eye - target, "look_at: eye - target")
    up = _unit(up, "look_at: up")
    x = np.cross(up, z)
    nx = np.linalg.norm(x)
    if nx < 1e-9:
        raise AutobonesError(
            "look_at: 'up' is parallel to the viewing direction; pass an up vector "
            "perpendicular to it (e.g. (0, 0, -1) for a view from above)")
    x /= nx
    y = np.cross(z, x)
    M = np.eye(4)
    M[0, :3], M[1, :3], M[2, :3] = x, y, z
    M[:3, 3] = -M[:3, :3] @ eye
    return M


@dataclass
class Camera:
    """An orthographic camera.

    Attributes
    ----------
    view : (4, 4) float64
        World -> camera rigid transform (camera looks along its -Z).
    scale : float
        Pixels per world unit.
    center : (2,) float64
        Camera-space (x, y) shown at the image centre, world units.
    width, height : int
        Image size in pixels.
    """

    view: np.ndarray
    scale: float
    center: np.ndarray
    width: int
    height: int

    @property
    def direction(self):
        """(3,) float64 unit world direction the camera looks along."""
        return -self.view[2, :3].copy()

    def project(self, P):
        """Project world points to pixel coordinates.

        Parameters
        ----------
        P : (k, 3) float
            World points.

        Returns
        -------
        px : (k, 2) float64
            Pixel coordinates (x = column, y = row; pixel centres at integers).
        depth : (k,) float64
            Distance in front of the camera plane, world units.
        """
        P = np.asarray(P, dtype=np.float64).reshape(-1, 3)
        C = P @ self.view[:3, :3].T + self.view[:3, 3]
        px = np.empty((len(P), 2))
        px[:, 0] = (self.width - 1) / 2.0 + self.scale * (C[:, 0] - self.center[0])
        px[:, 1] = (self.height - 1) / 2.0 - self.scale * (C[:, 1] - self.center[1])
        return px, -C[:, 2]

    def ray(self, px):
        """World rays through pixel coordinates.

        Parameters
        ----------
        px : (k, 2) float
            Pixel coordinates (x = column, y = row).

        Returns
        -------
        origins : (k, 3) float64
            World points on the camera plane (depth 0).
        directions : (k, 3) float64
            Unit world directions (all equal to :attr:`direction`); the point
            at depth ``d`` is ``origins + d * directions``.
        """
        px = np.asarray(px, dtype=np.float64).reshape(-1, 2)
        C = np.zeros((len(px), 3))
        C[:, 0] = (px[:, 0] - (self.width - 1) / 2.0) / self.scale + self.center[0]
        C[:, 1] = -(px[:, 1] - (self.height - 1) / 2.0) / self.scale + self.center[1]
        R, t = self.view[:3, :3], self.view[:3, 3]
        origins = (C - t) @ R
        directions = np.broadcast_to(self.direction, origins.shape).copy()
        return origins, directions


def _size(size):
    try:
        W, H = (int(s) for s in size)
    except (TypeError, ValueError):
        raise AutobonesError(f"image size must be (width, height), got {size!r}") from None
    if W < 1 or H < 1:
        raise AutobonesError(f"image size must be positive, got {size!r}")
    return W, H


def orthographic_camera(V, view_dir, up=(0.0, 1.0, 0.0), size=(512, 512), margin=0.05):
    """An orthographic camera that frames the points ``V``.

    Parameters
    ----------
    V : (n, 3) float
        Points to frame, world coordinates (e.g. a mesh's vertices).
    view_dir : (3,) float
        Direction from the points toward the camera: the camera sits on the
        ``+view_dir`` side and looks along ``-view_dir``. In the canonical head
        frame ``(0, 0, 1)`` is a front view of the face.
    up : (3,) float
        World direction shown upward in the image; not parallel to ``view_dir``.
    size : (int, int)
        Image (width, height) in pixels.
    margin : float
        Empty border on each side, as a fraction of the image size.

    Returns
    -------
    Camera
        The bounding box of ``V``'s projection is centred and fills the image
        minus the margins in its limiting direction. Every point of ``V`` has a
        positive depth.
    """
    W, H = _size(size)
    V = np.asarray(V, dtype=np.float64).reshape(-1, 3)
    V = V[np.all(np.isfinite(V), axis=1)]
    d = _unit(view_dir, "view_dir")
    if len(V) == 0:
        mid, radius = np.zeros(3), 1.0
    else:
        mid = (V.min(axis=0) + V.max(axis=0)) / 2.0
        radius = float(np.linalg.norm(V - mid, axis=1).max())
    radius = radius if radius > 0 else 1.0
    view = look_at(mid + 2.0 * radius * d, mid, up)
    C = (V @ view[:3, :3].T + view[:3, 3])[:, :2] if len(V) else np.zeros((1, 2))
    lo, hi = C.min(axis=0), C.max(axis=0)
    span = hi - lo
    usable = np.array([W, H], dtype=np.float64) * (1.0 - 2.0 * float(margin))
    usable = np.maximum(usable, 1.0)
    with np.errstate(divide="ignore"):
        s = np.where(span > 1e-12 * radius, usable / np.where(span > 0, span, 1.0), np.inf)
    scale = float(s.min())
    if not np.isfinite(scale):  # a single point
        scale = float(min(usable) / (2.0 * radius))
    return Camera(view=view, scale=scale, center=(lo + hi) / 2.0, width=W, height=H)


# ---------------------------------------------------------------------------
# rasterisation


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
    npix = W * H
    zbuf = np.full(npix, np.inf)
    fbuf = np.full(npix, -1, dtype=np.int64)
    bbuf = np.zeros((npix, 3))
    out = lambda: RenderBuffers(zbuf.reshape(H, W), fbuf.reshape(H, W),  # noqa: E731
                                bbuf.reshape(H, W, 3), camera)
    if len(F) == 0 or len(V) == 0:
        return out()

    px, dep = camera.project(V)
    T = px[F]                       # (m, 3, 2)
    Z = dep[F]                      # (m, 3)
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
    if len(tri) == 0:
        return out()

    # Barycentric coordinates as affine functions of the pixel position:
    # l_k(x, y) = a_k x + b_k y + c_k, evaluated at the bounding-box corner plus
    # increments, per triangle.
    inv = 1.0 / area[tri]
    x0, y0, x1, y1, x2, y2 = (a[tri] for a in (x0, y0, x1, y1, x2, y2))
    a0, b0 = (y1 - y2) * inv, (x2 - x1) * inv
    a1, b1 = (y2 - y0) * inv, (x0 - x2) * inv
    ox, oy = xmin[tri].astype(np.float64), ymin[tri].astype(np.float64)
    l0o = ((x1 - ox) * (y2 - oy) - (x2 - ox) * (y1 - oy)) * inv
    l1o = ((x2 - ox) * (y0 - oy) - (x0 - ox) * (y2 - oy)) * inv
    z0, z1, z2 = Z[tri, 0], Z[tri, 1], Z[tri, 2]
    bw = xmax[tri] - xmin[tri] + 1
    count = bw * (ymax[tri] - ymin[tri] + 1)
    base = ymin[tri] * W + xmin[tri]

    # Batches of consecutive triangles holding about _BATCH candidates each.
    ends = np.cumsum(count)
    cuts = np.searchsorted(ends, np.arange(_BATCH, ends[-1], _BATCH), side="left") + 1
    bounds = np.unique(np.concatenate([[0], cuts, [len(tri)]]))
    for s, e in zip(bounds[:-1], bounds[1:]):
        c = count[s:e]
        t = np.repeat(np.arange(s, e), c)              # local triangle per candidate
        starts = np.cumsum(c) - c
        off = np.arange(len(t)) - np.repeat(starts, c)
        w = bw[t]
        dy = off // w
        dx = off - dy * w
        l0 = l0o[t] + a0[t] * dx + b0[t] * dy
        l1 = l1o[t] + a1[t] * dx + b1[t] * dy
        l2 = 1.0 - l0 - l1
        inside = (l0 >= -_INSIDE_EPS) & (l1 >= -_INSIDE_EPS) & (l2 >= -_INSIDE_EPS)
        if not inside.any():
            continue
        t, l0, l1, l2 = t[inside], l0[inside], l1[inside], l2[inside]
        pix = base[t] + dy[inside] * W + dx[inside]
        z = l0 * z0[t] + l1 * z1[t] + l2 * z2[t]
        np.minimum.at(zbuf, pix, z)
        win = np.flatnonzero(z <= zbuf[pix])
        if len(win) == 0:
            continue
        # One winner per pixel even on exact depth ties, so face and bary come
        # from the same fragment (repeated pixels in pw then write equal values).
        pw = pix[win]
        pick = np.empty(npix, dtype=np.int64)
        pick[pw] = win
        f = pick[pw]
        fbuf[pw] = tri[t[f]]
        bbuf[pw, 0], bbuf[pw, 1], bbuf[pw, 2] = l0[f], l1[f], l2[f]
    return out()


def surface_points(V, F, buffers):
    """The 3-D surface point seen at each pixel centre.

    Parameters
    ----------
    V : (n, 3) float
        The vertices that were rasterised, world coordinates.
    F : (m, 3) int
        The triangles that were rasterised.
    buffers : RenderBuffers
        From :func:`rasterize` ``(V, F, camera)``.

    Returns
    -------
    (H, W, 3) float64
        World point under each pixel (on triangle ``face_id`` at ``bary``);
        NaN where empty.
    """
    V, F = mesh_arrays(V, F, "mesh", allow_no_faces=True, finite=False)
    H, W = buffers.face_id.shape
    P = np.full((H, W, 3), np.nan)
    m = buffers.mask
    if m.any():
        tri = F[buffers.face_id[m]]                       # (k, 3)
        b = buffers.bary[m]                               # (k, 3)
        P[m] = np.einsum("kj,kjd->kd", b, V[tri])
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
        light = _unit(light_dir, "light_dir")
    fid = buffers.face_id[m]
    b = buffers.bary[m]
    tri = F[fid]
    VN = vertex_normals(V, F)
    n = np.einsum("kj,kjd->kd", b, VN[tri])
    ln = np.linalg.norm(n, axis=1)
    bad = ln < 1e-6
    if bad.any():
        t = tri[bad]
        n[bad] = np.cross(V[t[:, 1]] - V[t[:, 0]], V[t[:, 2]] - V[t[:, 0]])
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


# ---------------------------------------------------------------------------
# 2-D overlays and files


def _rgb_image(image):
    image = np.asarray(image)
    if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
        raise AutobonesError(
            f"image must be an (H, W, 3) uint8 array, got {image.dtype} {image.shape}")
    return image


def _colors(color, k):
    c = np.asarray(color)
    if c.ndim == 1:
        c = np.broadcast_to(c, (k, c.shape[0]))
    if c.shape != (k, 3) and c.shape != (k, 4):
        raise AutobonesError(f"color must be one RGB triple or one per item ({k}), got {c.shape}")
    if np.issubdtype(c.dtype, np.floating) and c.size and c.max() <= 1.0:
        c = c * 255.0
    return [tuple(int(round(v)) for v in row[:3]) for row in c]


def draw_points(image, px, labels=None, color=(255, 0, 0), radius=3, filled=True):
    """Draw round markers, optionally labelled, on an image.

    Parameters
    ----------
    image : (H, W, 3) uint8
        Not modified.
    px : (k, 2) float
        Pixel coordinates (x = column, y = row); non-finite rows are skipped.
    labels : sequence of k str or None
        Text drawn to the upper right of each marker.
    color : (3,) or (k, 3)
        RGB, uint8 range (floats all <= 1 are taken as [0, 1]).
    radius : float
        Marker radius in pixels.
    filled : bool or (k,) bool
        False draws a ring (e.g. for points hidden behind the surface).

    Returns
    -------
    (H, W, 3) uint8
        A new image with the markers.
    """
    from PIL import Image, ImageDraw, ImageFont

    image = _rgb_image(image)
    px = np.asarray(px, dtype=np.float64).reshape(-1, 2)
    k = len(px)
    cols = _colors(color, k)
    fill = np.broadcast_to(np.asarray(filled, dtype=bool), (k,))
    if labels is not None and len(labels) != k:
        raise AutobonesError(f"{len(labels)} labels for {k} points")
    pil = Image.fromarray(image)
    draw = ImageDraw.Draw(pil)
    font = ImageFont.load_default() if labels is not None else None
    r = float(radius)
    for i in range(k):
        x, y = px[i]
        if not (np.isfinite(x) and np.isfinite(y)):
            continue
        box = [x - r, y - r, x + r, y + r]
        if fill[i]:
            draw.ellipse(box, fill=cols[i], outline=(0, 0, 0))
        else:
            draw.ellipse(box, outline=cols[i], width=max(1, int(round(r / 3))))
        if labels is not None and labels[i] is not None and str(labels[i]):
            draw.text((x + r + 2, y - r - 10), str(labels[i]), fill=cols[i], font=font)
    return np.asarray(pil).copy()


def draw_segments(image, p0, p1, color=(0, 90, 255), width=2):
    """Draw line segments on an image.

    Parameters
    ----------
    image : (H, W, 3) uint8
        Not modified.
    p0, p1 : (k, 2) float
        Segment end points in pixel coordinates (x = column, y = row);
        segments with a non-finite end are skipped.
    color : (3,) or (k, 3)
        RGB, uint8 range (floats all <= 1 are taken as [0, 1]).
    width : int
        Line width in pixels.

    Returns
    -------
    (H, W, 3) uint8
        A new image with the segments.
    """
    from PIL import Image, ImageDraw

    image = _rgb_image(image)
    p0 = np.asarray(p0, dtype=np.float64).reshape(-1, 2)
    p1 = np.asarray(p1, dtype=np.float64).reshape(-1, 2)
    if p0.shape != p1.shape:
        raise AutobonesError(f"p0 and p1 must have the same shape, got {p0.shape} and {p1.shape}")
    cols = _colors(color, len(p0))
    pil = Image.fromarray(image)
    draw = ImageDraw.Draw(pil)
    for i in range(len(p0)):
        if not (np.all(np.isfinite(p0[i])) and np.all(np.isfinite(p1[i]))):
            continue
        draw.line([tuple(p0[i]), tuple(p1[i])], fill=cols[i], width=int(width))
    return np.asarray(pil).copy()


def encode_png(image):
    """PNG file bytes of an (H, W, 3) or (H, W, 4) uint8 RGB(A) or (H, W) uint8 grey image."""
    import io

    from PIL import Image

    image = np.asarray(image)
    ok = image.dtype == np.uint8 and (image.ndim == 2 or (image.ndim == 3 and image.shape[2] in (3, 4)))
    if not ok:
        raise AutobonesError(
            f"PNG image must be uint8 (H, W), (H, W, 3) or (H, W, 4), got {image.dtype} {image.shape}")
    buf = io.BytesIO()
    Image.fromarray(image).save(buf, format="PNG")
    return buf.getvalue()


def save_png(path, image):
    """Write :func:`encode_png` of ``image`` to ``path``, atomically."""
    from ..io.atomic import write_bytes_atomic

    return write_bytes_atomic(path, encode_png(image), "the picture")


def _view(v):
    if isinstance(v, str):
        if v not in VIEWS:
            raise AutobonesError(f"unknown view {v!r}; expected one of {', '.join(VIEWS)}")
        d, up = VIEWS[v]
        return np.array(d) / np.linalg.norm(d), np.array(up)
    d = _unit(v, "view direction")
    up = np.array([0.0, 1.0, 0.0]) if abs(d[1]) < 0.99 else np.array([0.0, 0.0, -np.sign(d[1])])
    return d, up


def render_views(V, F, vertex_colors=None, views=("front", "side"), size=(512, 512),
                 points=None, point_labels=None, segments=None,
                 point_color=(255, 0, 0), segment_color=(0, 90, 255)):
    """Shaded pictures of a head from several directions, side by side.

    Parameters
    ----------
    V : (n, 3) float
        Vertices in the canonical head frame (+Y up, +Z out of the face, +X
        toward the subject's left), any unit.
    F : (m, 3) int
        Triangles.
    vertex_colors : (n, 3) float in [0, 1] or None
        See :func:`shade`.
    views : sequence of str or (3,) float
        ``'front'`` (looking at the face), ``'side'`` (= ``'left'``, from the
        subject's left, +X), ``'right'``, ``'three_quarter'`` (45 degrees
        between front and left), ``'back'``, ``'top'``, ``'bottom'``, or a
        direction from the head toward the camera.
    size : (int, int)
        (width, height) of each panel in pixels.
    points : (k, 3) float or None
        3-D points (same frame as ``V``) drawn as markers; those behind the
        surface are drawn as rings.
    point_labels : sequence of k str or None
        Text next to each marker.
    segments : (s, 2, 3) float or None
        3-D segments (start, end) drawn as lines on top of the surface.
    point_color, segment_color : (3,) or per-item (k, 3) RGB
        uint8 range.

    Returns
    -------
    (H, W * len(views), 3) uint8
        The panels left to right; all at the same scale (pixels per unit).
    """
    V, F = mesh_arrays(V, F, "mesh", allow_no_faces=True, finite=False)
    W, H = _size(size)
    if isinstance(views, str):
        views = (views,)
    if len(views) == 0:
        raise AutobonesError("render_views: give at least one view")
    cams = [orthographic_camera(V, *_view(v), size=(W, H)) for v in views]
    scale = min(c.scale for c in cams)
    cams = [replace(c, scale=scale) for c in cams]
    if points is not None:
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if segments is not None:
        segments = np.asarray(segments, dtype=np.float64).reshape(-1, 2, 3)
    panels = []
    tol = 0.01 * max(float(np.ptp(V, axis=0).max()) if len(V) else 1.0, 1e-12)
    for cam in cams:
        buf = rasterize(V, F, cam)
        img = shade(V, F, buf, vertex_colors)
        if segments is not None and len(segments):
            a, _ = cam.project(segments[:, 0])
            b, _ = cam.project(segments[:, 1])
            img = draw_segments(img, a, b, color=segment_color)
        if points is not None and len(points):
            p, d = cam.project(points)
            q = np.nan_to_num(np.rint(p), nan=0.0, posinf=0.0, neginf=0.0)
            r = np.clip(q[:, 1], 0, H - 1).astype(np.int64)
            c = np.clip(q[:, 0], 0, W - 1).astype(np.int64)
            visible = ~(d > buf.depth[r, c] + tol)
            img = draw_points(img, p, labels=point_labels, color=point_color, filled=visible)
        panels.append(img)
    return np.concatenate(panels, axis=1)
