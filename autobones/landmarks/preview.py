"""A picture to check landmarks by eye: the head from the front and the side, every landmark named.

Works for any head (human, cartoon, animal) and any landmarks, detected or read from a
file. Landmarks on the side of the head turned away from a view are drawn as rings.
"""
from __future__ import annotations

import os

import numpy as np

from ..errors import AutobonesError
from ..io.atomic import output_folder
from ..orient import detect_frame, frame_from_landmarks
from ..render.draw import draw_points, save_png
from ..render.raster import rasterize, shade
from .views import face_camera

#: Marker colours: midline names, subject's left, subject's right (RGB).
COLORS = {"mid": (220, 30, 30), "l": (20, 120, 230), "r": (20, 160, 60)}


def landmark_preview(V, F, landmarks, frame=None, size=640, confidence=None):
    """A front and a side picture of the head with every landmark drawn, numbered and named.

    Parameters
    ----------
    V : (n, 3) float
        Vertices, the mesh's own frame and units.
    F : (m, 3) int
        Triangles.
    landmarks : mapping str -> (3,)
        Landmarks in the same frame and units.
    frame : autobones.orient.Frame or None
        The head's canonical frame; None takes it from the landmarks when they tell it,
        else from :func:`autobones.orient.detect_frame`.
    size : int
        Height (and width of each picture) in pixels.
    confidence : mapping str -> float or None
        Printed after the name in the legend (e.g. detection confidence in [0, 1]).

    Returns
    -------
    (size, 2 * size + legend, 3) uint8
        Front view, the subject's left side, and a legend: number, name (and confidence).
        Both views are zoomed on the landmarks; a landmark hidden from a view is a ring.
    """
    from PIL import Image, ImageDraw, ImageFont

    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    if not landmarks:
        raise AutobonesError("no landmarks to draw")
    if frame is None:
        frame = frame_from_landmarks(V, F, landmarks) or detect_frame(V, F)
    names = list(landmarks)
    Vc = frame.to_canonical(V)
    P = frame.to_canonical(np.array([landmarks[n] for n in names], dtype=np.float64).reshape(-1, 3))
    colors = np.array([COLORS["l"] if n.endswith("_l") else COLORS["r"] if n.endswith("_r") else COLORS["mid"]
                       for n in names])
    lo, hi = P.min(axis=0), P.max(axis=0)
    extent = float(max((hi - lo).max(), 0.25))          # canonical units: head sizes
    target = (lo + hi) / 2.0
    tol = 0.01
    panels = []
    for view_dir in ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0)):
        cam = face_camera(target, np.array(view_dir), 1.6 * extent, size)
        buf = rasterize(Vc, F, cam)
        img = shade(Vc, F, buf)
        px, depth = cam.project(P)
        r = np.clip(np.rint(px[:, 1]), 0, size - 1).astype(np.int64)
        c = np.clip(np.rint(px[:, 0]), 0, size - 1).astype(np.int64)
        visible = ~(depth > buf.depth[r, c] + tol)
        img = draw_points(img, px, labels=[str(i + 1) for i in range(len(names))], color=colors,
                          radius=4, filled=visible)
        panels.append(img)
    # the legend: one line per landmark, in the marker's colour
    font = ImageFont.load_default()
    line = 13
    columns = max(1, int(np.ceil(len(names) * line / (size - 20))))
    legend = Image.new("RGB", (230 * columns, size), (255, 255, 255))
    draw = ImageDraw.Draw(legend)
    per_column = max(1, (size - 20) // line)
    for i, n in enumerate(names):
        text = f"{i + 1:2d} {n}"
        if confidence is not None and n in confidence:
            text += f"  {confidence[n]:.2f}"
        x, y = 10 + 230 * (i // per_column), 10 + line * (i % per_column)
        draw.text((x, y), text, fill=tuple(int(v) for v in colors[i]), font=font)
    return np.concatenate(panels + [np.asarray(legend)], axis=1)


def save_preview(path, V, F, landmarks, **kwargs):
    """Write :func:`landmark_preview` to the PNG file ``path`` (a temporary file renamed into
    place, so a failure leaves no partial picture). Returns ``path``."""
    path = os.fspath(path)
    if not path.lower().endswith(".png"):
        raise AutobonesError(f"{path}: the preview must be a .png file")
    output_folder(path)
    save_png(path, landmark_preview(V, F, landmarks, **kwargs))
    return path
