"""Small pictures of where each landmark goes, drawn on the built-in generic head (issue #35).

The editor's name list shows, beside each of the contract's 44 names, the generic rig's skin with that
name's landmark marked: a person placing ``gonion_l`` on a cow sees where it sits on a human. Drawn on
the fly with the project's own CPU renderer (no picture files shipped), two base views rendered once
(the face from the front, the head from either side) and one marker per name; deterministic, the same
bytes every time. The marker's colour is the preview's (midline red, left blue, right green).
"""
from __future__ import annotations

import threading

import numpy as np

from ..errors import AutobonesError
from ..io.landmark_names import NAMES
from ..landmarks.preview import COLORS
from ..render import draw_points, encode_png, orthographic_camera, rasterize, shade
from ..render.views import VIEWS

#: Names pictured from the side (the subject's own side for a bilateral name, the left for midline ones):
#: from the front they sit on the silhouette or behind it.
SIDE_VIEW = {"vertex", "opisthocranion", "zygion", "gonion", "tragion", "superaurale", "subaurale"}


def _view_of(name):
    base = name[:-2] if name.endswith(("_l", "_r")) else name
    if base not in SIDE_VIEW:
        return "front"
    return "right" if name.endswith("_r") else "left"


def marker_colour(name):
    """RGB of ``name``'s marker: the ``--preview`` picture's midline / left / right colours."""
    return COLORS["l"] if name.endswith("_l") else COLORS["r"] if name.endswith("_r") else COLORS["mid"]


class LandmarkPictures:
    """PNG bytes of each contract name on the generic head, drawn on first request and kept.

    ``rig`` is a :class:`~autobones.labelled_rig.LabelledRig` (canonical frame: +Y up, +Z front, +X the
    subject's left, as the built-in one is); None loads the built-in rig when the first picture is asked for.
    """

    def __init__(self, rig=None, size=112):
        self.size = int(size)
        self._rig = rig
        self._bases = {}
        self._pngs = {}
        self._lock = threading.Lock()

    def _base(self, view):
        """(shaded picture, camera) of the generic head from ``view``; the front one framed on the face."""
        if view not in self._bases:
            if self._rig is None:
                from ..generic_rig import default_rig_path
                from ..labelled_rig import load_labelled_rig

                self._rig = load_labelled_rig(default_rig_path())
            V, F = self._rig.vertices, self._rig.faces
            d, up = VIEWS[view]
            framed = V
            if view == "front":  # the face: its landmarks, less those on the top, back and sides of the head
                framed = np.array([p for n, p in self._rig.landmarks.items() if _view_of(n) == "front"])
            cam = orthographic_camera(framed, d, up, size=(self.size, self.size), margin=0.12)
            self._bases[view] = (shade(V, F, rasterize(V, F, cam)), cam)
        return self._bases[view]

    def png(self, name):
        """PNG bytes of the generic head with ``name`` marked; AutobonesError for a name outside the
        contract or one the rig does not carry."""
        if name not in NAMES:
            raise AutobonesError(f"{name!r} is not a landmark name of the contract")
        with self._lock:  # one renderer at a time: the server answers requests on several threads
            if name not in self._pngs:
                img, cam = self._base(_view_of(name))
                if name not in self._rig.landmarks:
                    raise AutobonesError(f"the generic rig has no landmark {name}")
                px, _ = cam.project(self._rig.landmarks[name][None])
                drawn = draw_points(img, px, color=marker_colour(name), radius=max(3, self.size // 28))
                self._pngs[name] = encode_png(drawn)
            return self._pngs[name]
