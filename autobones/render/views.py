"""Side-by-side pictures of a head from named directions, with 3-D points and segments drawn on
top: the gallery's and the rig previews' pictures.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import AutobonesError
from ..geometry.ring import RING_KINDS, ring_outline
from ..geometry.validate import mesh_arrays
from .camera import image_size, orthographic_camera, unit_vector
from .draw import draw_points, draw_segments
from .raster import rasterize, shade

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


def _view(v):
    if isinstance(v, str):
        if v not in VIEWS:
            raise AutobonesError(f"unknown view {v!r}; expected one of {', '.join(VIEWS)}")
        d, up = VIEWS[v]
        return np.array(d) / np.linalg.norm(d), np.array(up)
    d = unit_vector(v, "view direction")
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
    W, H = image_size(size)
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


def muscle_segments(muscles, to_frame=None):
    """Segments (s, 2, 3) that picture a rig's muscles: a linear muscle's origin -> insertion, a
    sphincter's ring or a sheet's outline (``kind`` "sphincter" or "sheet": its ellipse at elliptical
    radius 0.7, 32 segments; the lateral half of it, 16 segments, for one half across the midline).

    ``muscles``: the rig's muscle dicts (``origin``, ``insertion``; a sphincter's ``reach`` too);
    ``to_frame``: (k, 3) -> (k, 3) applied to the ends first (e.g. ``rig.frame.to_canonical``) so
    that the points are canonical (+Y up, +Z front), which the rings' frame assumes.
    """
    move = to_frame or (lambda P: P)
    out = []
    for m in muscles:
        ends = move(np.array([m["origin"], m["insertion"]], dtype=np.float64))
        if m.get("kind") in RING_KINDS and isinstance(m.get("reach"), dict):
            if m.get("split") is None:                     # a closed ring
                P = ring_outline(ends[0], ends[1], m["reach"])
                out.append(np.stack([P, np.roll(P, -1, axis=0)], axis=1))
            else:                                          # one half of a ring across the midline
                P = ring_outline(ends[0], ends[1], m["reach"], count=17, arc=(-0.5 * np.pi, 0.5 * np.pi))
                out.append(np.stack([P[:-1], P[1:]], axis=1))
        else:
            out.append(ends[None])
    return np.concatenate(out) if out else np.zeros((0, 2, 3))
