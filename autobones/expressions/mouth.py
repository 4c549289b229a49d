"""The mouth line (cheilion_r - stomion - cheilion_l) and the zone where it splits the lips.

Within the mouth zone a wire pulling one lip leaves the other (Bibliowicz 2005, §4.2, cuts the
wire influence at the mouth line), and the jaw opens the lower lip only.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import AutobonesError
from ..geometry.smooth import ramp


@dataclass
class MouthLine:
    """The mouth line of one head, canonical frame (+Y up, +Z front), head sizes; n vertices.

    Attributes
    ----------
    stomion : (3,) float
        Where the lips meet at the midline.
    line_x, line_y : (3,) float
        The line's corners and stomion (x, y), sorted by x: the line is ``interp(x, line_x, line_y)``.
    half_width : float
        Half the cheilion distance along x.
    signed : (n,) float
        Height above the line, biased by the normals (the upper lip's underside, facing down,
        counts as above the line).
    zone : (n,) float
        0..1: how much the line splits the skin there (lips, and the mouth's lining).
    upper : (n,) float
        0..1: 1 on the upper lip side of the line (a soft step over the cut width).
    dx : (n,) float
        Distance in x from the stomion.
    inward : (n,) bool
        Vertices whose normal faces into the head (the mouth's lining, the inner lips).
    """

    stomion: np.ndarray
    line_x: np.ndarray
    line_y: np.ndarray
    half_width: float
    signed: np.ndarray
    zone: np.ndarray
    upper: np.ndarray
    dx: np.ndarray
    inward: np.ndarray

    def height(self, x):
        """y of the mouth line at ``x`` (any shape, canonical head sizes)."""
        return np.interp(x, self.line_x, self.line_y)


def mouth_corners(landmarks, insertions, V, skin, fu):
    """The cheilions and the stomion (each (3,), canonical head sizes).

    ``landmarks`` and ``insertions`` (muscle name -> insertion) are dicts of canonical (3,)
    points; missing landmarks fall back to the buccinator insertions (corners) and to the most
    frontal skin vertex of ``V`` (n, 3) (``skin`` (n,) bool) between them (stomion); ``fu`` is
    the face unit in head sizes. Raises AutobonesError when the corners cannot be found.
    """
    ch_l = landmarks.get("cheilion_l", insertions.get("buccinator_l"))
    ch_r = landmarks.get("cheilion_r", insertions.get("buccinator_r"))
    if ch_l is None or ch_r is None:
        raise AutobonesError("expressions: the rig has no cheilion landmarks or buccinator muscles "
                             "to find the mouth corners by")
    st = landmarks.get("stomion")
    if st is None:
        mid = 0.5 * (ch_l + ch_r)
        near = skin & (np.abs(V[:, 0] - mid[0]) < 0.05 * fu) & (np.abs(V[:, 1] - mid[1]) < 0.1 * fu)
        st = V[np.flatnonzero(near)[np.argmax(V[near, 2])]] if near.any() else mid
    return ch_l, ch_r, st


def mouth_line(V, N, skin, corners, centre, fu, lips):
    """The :class:`MouthLine` of a head.

    Parameters
    ----------
    V, N : (n, 3) float
        Vertices and unit normals, canonical frame, head sizes.
    skin : (n,) bool
        Skin vertices.
    corners : tuple of three (3,) float
        ``(cheilion_l, cheilion_r, stomion)`` (:func:`mouth_corners`).
    centre : (3,) float
        A point inside the head (the head bone's pivot).
    fu : float
        Face unit in head sizes.
    lips : dict
        The definitions' ``model.lips``: ``zone_half_width`` (half mouth widths),
        ``zone_height``, ``cut_width``, ``normal_bias`` (fu).
    """
    ch_l, ch_r, st = corners
    xs = np.array([ch_r[0], st[0], ch_l[0]])
    order = np.argsort(xs)
    line_x, line_y = xs[order], np.array([ch_r[1], st[1], ch_l[1]])[order]
    y_line = np.interp(V[:, 0], line_x, line_y)
    # in the mouth groove the lip surfaces face each other: a downward normal is the upper
    # lip's underside, an upward one the lower lip's top, whatever the straight line says
    s_mouth = V[:, 1] - y_line - float(lips["normal_bias"]) * fu * N[:, 1]
    hw = 0.5 * abs(ch_l[0] - ch_r[0])
    dx = np.abs(V[:, 0] - st[0])
    z_ch = 0.5 * (ch_l[2] + ch_r[2])
    zh = float(lips["zone_height"]) * fu
    zone = (ramp(dx, float(lips["zone_half_width"]) * hw, 0.75 * hw) * ramp(np.abs(s_mouth), zh, 0.6 * zh)
            * ramp(V[:, 2], z_ch - 0.4 * fu, z_ch - 0.3 * fu) * skin)
    # the mouth's lining (skin behind the lips facing into the head, e.g. ICT's mouth sock)
    # splits by the same line, over its whole depth and height
    inward = (N * (V - centre)).sum(axis=1) < 0
    lining = inward & skin
    lining_zone = (ramp(dx, float(lips["zone_half_width"]) * hw, 0.75 * hw) * ramp(np.abs(s_mouth), 4.0 * zh, 3.0 * zh)
                   * ramp(V[:, 2], z_ch - 1.2 * fu, z_ch - 0.8 * fu))
    zone = np.where(lining, np.maximum(zone, lining_zone), zone)
    cut = float(lips["cut_width"]) * fu
    cut = cut * (1.0 + 4.0 * np.clip(dx / hw, 0.0, 1.2) ** 4)   # softer toward the corners
    upper = ramp(s_mouth, -0.5 * cut, 0.5 * cut)
    return MouthLine(stomion=st, line_x=line_x, line_y=line_y, half_width=hw, signed=s_mouth, zone=zone,
                     upper=upper, dx=dx, inward=inward)
