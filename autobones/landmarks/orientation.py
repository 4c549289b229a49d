"""Which way the face in the pictures is turned: the upright/turn search and plausibility checks.

A head may come in any of the 24 axis-aligned orientations (a file's choice of up and front)
or turned off them. :func:`turns` lists the candidate rotations of the canonical frame to
picture the head in; :func:`face_axes` reads the face's own left and up from a detector's
points with depth; :func:`squared_frame` turns a frame square to the landmarks' mirror plane;
:func:`nose_forward` and :func:`plausible` refuse a face the detector imagines (the hollow
inside of a face-only shell, a head upside down or seen from behind).

Frames: the canonical head frame is +Y up, +Z out of the face, +X toward the subject's left;
a picture's frame is x right, y up, z toward the viewer.
"""
from __future__ import annotations

import numpy as np

from ..io.landmark_names import mirror_name
from ..orient import Frame
from .refine import symmetry_plane


#: Midline names from top to bottom: a face's landmarks come in this order along its up.
TOP_DOWN = ("nasion", "pronasale", "subnasale", "labiale_superius", "stomion", "labiale_inferius", "menton")


def nose_forward(P, table):
    """Whether the nose tip is nearer the viewer (+z) than the outer eye corners, given the
    table's points lifted to the surface ((p, 3), picture frame). False for the inside of a
    face-only shell seen from behind, which a face detector takes for a face (the hollow-face
    illusion)."""
    if not all(n in table for n in ("pronasale", "exocanthion_l", "exocanthion_r")):
        return True
    tip = P[table["pronasale"][0], 2]
    eyes = P[[table["exocanthion_l"][0], table["exocanthion_r"][0]], 2]
    return bool(np.isfinite(tip) and np.all(np.isfinite(eyes)) and tip > eyes.mean())


def plausible(landmarks):
    """Whether detected landmarks look like a face in their frame: midline names in top-down
    order, eyes above the mouth, the nose tip in front of the eyes, every ``_l`` on the
    subject's left of its ``_r``. Guards against a face the detector imagines in a head
    pictured upside down or from behind."""
    Q = {n: landmarks.frame.to_canonical(np.asarray(p)[None])[0] for n, p in landmarks.items()}
    eyes = [Q[n][2] for n in ("exocanthion_l", "exocanthion_r") if n in Q]
    if "pronasale" in Q and eyes and Q["pronasale"][2] <= np.mean(eyes):
        return False
    ys = [Q[n][1] for n in TOP_DOWN if n in Q]
    if any(a < b for a, b in zip(ys, ys[1:])):
        return False
    for eye, mouth in (("exocanthion_l", "cheilion_l"), ("exocanthion_r", "cheilion_r")):
        if eye in Q and mouth in Q and Q[eye][1] <= Q[mouth][1]:
            return False
    return all(Q[n][0] > Q[mirror_name(n)][0] for n in Q if n.endswith("_l") and mirror_name(n) in Q)


def face_axes(points, table):
    """The subject's left and up as unit (3,) vectors in the picture's frame (x right, y up,
    z toward the viewer), from a detector's points with depth ((p, 3): pixels, depth in pixels
    growing away from the viewer); (None, None) without depth. Left: mean direction right ->
    left over the table's bilateral pairs; up: menton -> nasion."""
    if points.shape[1] < 3 or "menton" not in table or "nasion" not in table:
        return None, None
    P = points * np.array([1.0, -1.0, -1.0])
    u = [P[table[n][0]] - P[table[mirror_name(n)][0]] for n in table
         if n.endswith("_l") and mirror_name(n) in table]
    if not u:
        return None, None
    u = np.array(u)
    left = (u / np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-12)).mean(axis=0)
    up = P[table["nasion"][0]] - P[table["menton"][0]]
    if np.linalg.norm(left) == 0 or np.linalg.norm(up) == 0:
        return None, None
    return left / np.linalg.norm(left), up / np.linalg.norm(up)


def squared_frame(frame, landmarks):
    """``frame`` turned so that its left axis is the normal of the landmarks' own mirror plane
    (yaw and roll corrected, pitch kept)."""
    names = list(landmarks)
    Q = frame.to_canonical(np.array([landmarks[n] for n in names]))
    normal, _ = symmetry_plane(dict(zip(names, Q)))
    up = np.array([0.0, 1.0, 0.0]) - normal[1] * normal
    up /= np.linalg.norm(up)
    M = np.vstack([normal, up, np.cross(normal, up)])
    return Frame(rotation=M @ frame.rotation, origin=frame.origin, size=frame.size,
                 symmetry_error=frame.symmetry_error)


def turn_degrees(A, B):
    """Angle in degrees of the rotation taking the (3, 3) rotation ``B`` to ``A``."""
    return float(np.degrees(np.arccos(np.clip((np.trace(A @ B.T) - 1.0) / 2.0, -1.0, 1.0))))


def turns(search=True):
    """Candidate rotations of the canonical frame: None (keep it) first, then with ``search``
    the (3, 3) rotations that bring each axis direction to the front and another to the top
    (the identity among them)."""
    yield None
    if not search:
        return
    axes = [np.array(a, dtype=np.float64) for a in
            ((0, 0, 1), (0, 0, -1), (1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0))]
    for front in axes:
        for up in axes:
            if abs(front @ up) > 0.5:
                continue
            yield np.vstack([np.cross(up, front), up, front])
