"""Thumbnails of rigs for the batch page, drawn with the project's own CPU renderer and kept in memory.

Beyond the seeds (issue #17): a reviewer scanning 300 rigs wants to see at a glance which came out
wrong, so each thumbnail colours the skin by the bone with the largest weight (the glb's
``JOINTS_0``/``WEIGHTS_0``) from the front and at three quarters. Nothing is written to disk: the
folder served is read-only, so the PNG bytes live in a small in-memory cache keyed by the file's
size and modification time.
"""
from __future__ import annotations

import colorsys
import os
import threading
from collections import OrderedDict

import numpy as np

from ..errors import AutobonesError
from ..io.gltf import read_accessor, read_glb
from ..orient import Frame
from ..render import encode_png, render_views
from .site import read_sidecar

THUMB_VIEWS = ("front", "three_quarter")


def bone_palette(k):
    """(k, 3) float RGB in [0, 1]: well-separated hues (golden-ratio steps), soft saturation."""
    return np.array([colorsys.hsv_to_rgb((0.08 + 0.618034 * i) % 1.0, 0.55, 0.95) for i in range(k)]).reshape(-1, 3)


def thumbnail_png(glb_path, size=160):
    """PNG bytes of a rig seen from the front and at three quarters, coloured by dominant bone.

    Parameters
    ----------
    glb_path : str
        A glb written by autobones, its ``.rig.json`` beside it (for the head frame).
    size : int
        Height of the picture and width of each of the two panels, pixels.

    Returns
    -------
    bytes
        A (size, 2 * size) RGB PNG.

    Raises
    ------
    AutobonesError
        The glb or its sidecar cannot be read.
    """
    try:
        doc, body = read_glb(glb_path)
        prim = doc["meshes"][0]["primitives"][0]
        P = read_accessor(doc, body, prim["attributes"]["POSITION"]).astype(np.float64)
        F = read_accessor(doc, body, prim["indices"]).astype(np.int64).reshape(-1, 3)
        J = W = None
        if "JOINTS_0" in prim["attributes"] and "WEIGHTS_0" in prim["attributes"]:
            J = read_accessor(doc, body, prim["attributes"]["JOINTS_0"]).astype(np.int64)
            W = read_accessor(doc, body, prim["attributes"]["WEIGHTS_0"])
    except (OSError, ValueError, KeyError, IndexError, TypeError) as exc:
        raise AutobonesError(f"{os.path.basename(glb_path)}: cannot read its mesh ({type(exc).__name__}: {exc})") from None
    fr = read_sidecar(glb_path).get("frame") or {}
    try:
        frame = Frame.from_dict(fr)
        # the renderer's views are named in the head's axes (a transferred rig's anatomical ones)
        V = (P - frame.origin) @ frame.turn_axes.T / frame.size
    except (KeyError, TypeError, ValueError):
        V = P - P.mean(axis=0) if len(P) else P
    colors = None
    if J is not None and len(J):
        dominant = J[np.arange(len(J)), np.argmax(W, axis=1)]
        colors = bone_palette(int(dominant.max()) + 1)[dominant]
    img = render_views(V, F, vertex_colors=colors, views=THUMB_VIEWS, size=(int(size), int(size)))
    return encode_png(img)


class ThumbnailCache:
    """Thread-safe in-memory cache of :func:`thumbnail_png`, at most ``max_items`` pictures, least
    recently used dropped first; at most ``max_renders`` drawn at once (the CPU is shared)."""

    def __init__(self, max_items=1000, max_renders=2, size=160):
        self.max_items = int(max_items)
        self.size = int(size)
        self._items = OrderedDict()
        self._lock = threading.Lock()
        self._renders = threading.Semaphore(int(max_renders))

    def get(self, glb_path):
        """PNG bytes of ``glb_path``; drawn on first request and again when the file changes."""
        st = os.stat(glb_path)
        key = (glb_path, st.st_size, st.st_mtime_ns)
        with self._lock:
            if key in self._items:
                self._items.move_to_end(key)
                return self._items[key]
        with self._renders:
            png = thumbnail_png(glb_path, self.size)
        with self._lock:
            self._items[key] = png
            while len(self._items) > self.max_items:
                self._items.popitem(last=False)
        return png
