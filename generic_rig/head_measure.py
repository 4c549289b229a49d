"""Measure the ANATOMY table (``head_anatomy.py``) on the default head.

Each landmark (names and definitions after Farkas 1994) is found by casting
rays at the implicit surface of ``head_field`` and taking the extreme or
deepest hit in a small search window; with a mesh given, the points are then
snapped onto it.  Metres, default head frame (+Y up, +Z front, +X subject's
left); "_l" points are on the subject's left (x > 0).
"""

from __future__ import annotations

import igl
import numpy as np

from .head_field import EYE_C, FISSURE, ear_to_world, head_field


def _ray_hit(o, d, tmax=0.25, n=2500):
    """First point (3,) where the ray o + t d, t in [0, tmax] m, enters the head.

    Marches ``n`` samples, then bisects the crossing; None if the ray starts
    inside or never enters.
    """
    o = np.asarray(o, float)
    d = np.asarray(d, float)
    d = d / np.linalg.norm(d)
    t = np.linspace(0.0, tmax, n)
    f = head_field(o + t[:, None] * d)
    inside = np.flatnonzero(f < 0)
    if len(inside) == 0 or inside[0] == 0:
        return None
    lo, hi = t[inside[0] - 1], t[inside[0]]
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        if head_field((o + mid * d)[None])[0] < 0:
            hi = mid
        else:
            lo = mid
    return o + 0.5 * (lo + hi) * d


def _profile_points():
    """Mid-sagittal face-profile landmarks, found on the frontal profile z(y) at x = 0."""
    A = {}
    ys = np.arange(-0.003, 0.1605, 0.00025)
    front = np.array([_ray_hit((0.0, y, 0.15), (0, 0, -1))[2] for y in ys])

    def prof_pt(lo, hi, mode):
        """Most (mode "max") or least anterior profile point with lo <= y <= hi."""
        m = (ys >= lo) & (ys <= hi)
        i = np.flatnonzero(m)[(np.argmax if mode == "max" else np.argmin)(front[m])]
        return np.array([0.0, ys[i], front[i]])
    A["pronasale"] = prof_pt(0.07, 0.11, "max")
    A["glabella"] = prof_pt(0.125, 0.150, "max")
    A["nasion"] = prof_pt(0.105, A["glabella"][1], "min")
    # subnasale: top of the upper-lip skin, where the columella leaves it
    lip = prof_pt(0.060, A["pronasale"][1], "min")
    m = (ys >= 0.060) & (ys <= A["pronasale"][1]) & (front < lip[2] + 0.0015)
    i = np.flatnonzero(m).max()
    A["subnasale"] = np.array([0.0, ys[i], front[i]])
    A["stomion"] = prof_pt(0.044, 0.052, "min")
    A["labrale_superius"] = prof_pt(A["stomion"][1], A["subnasale"][1], "max")
    A["labrale_inferius"] = prof_pt(0.030, A["stomion"][1], "max")
    A["pogonion"] = prof_pt(0.0, 0.030, "max")
    return A


def _outline_points():
    """Menton, vertex and opisthocranion: extremes of the midline outline."""
    A = {}
    hits = [_ray_hit((0.0, -0.04, z), (0, 1, 0)) for z in np.arange(0.060, 0.0801, 0.0005)]
    A["menton"] = min(hits, key=lambda p: (p[1], -p[2]))
    hits = [_ray_hit((0.0, 0.30, z), (0, -1, 0)) for z in np.arange(-0.04, 0.0401, 0.0005)]
    A["vertex"] = max(hits, key=lambda p: p[1])
    hits = [_ray_hit((0.0, y, -0.15), (0, 0, 1)) for y in np.arange(0.10, 0.2001, 0.0005)]
    A["opisthocranion"] = min(hits, key=lambda p: p[2])
    return A


def _face_points_left():
    """Eye corners and centre, mouth corner, nose wing, cheekbone and jaw angle."""
    A = {}
    # the eyes are closed: the corners are the ends of the lid fissure
    A["exocanthion_l"] = _ray_hit((FISSURE[-1, 0], FISSURE[-1, 1], 0.15), (0, 0, -1))
    A["endocanthion_l"] = _ray_hit((FISSURE[0, 0], FISSURE[0, 1], 0.15), (0, 0, -1))
    A["eye_centre_l"] = EYE_C.copy()
    # mouth corner: lateral end of the mouth-line groove (> 0.3 mm deep)
    best = None
    for xx in np.arange(0.015, 0.0320, 0.00025):
        zc = _ray_hit((xx, 0.0480, 0.15), (0, 0, -1))
        za = _ray_hit((xx, 0.0440, 0.15), (0, 0, -1))
        zb = _ray_hit((xx, 0.0520, 0.15), (0, 0, -1))
        if 0.5 * (za[2] + zb[2]) - zc[2] > 0.0003:
            best = zc
    A["cheilion_l"] = best
    # nose wing: most lateral point of the ala (hits beyond 3 cm are the cheek)
    hits = [_ray_hit((0.06, y, z), (-1, 0, 0)) for y in np.arange(0.072, 0.0861, 0.0005)
            for z in np.arange(0.084, 0.0961, 0.0005)]
    hits = [h for h in hits if h is not None and h[0] < 0.03]
    A["alare_l"] = max(hits, key=lambda p: p[0])
    # cheekbone: most lateral point of the zygomatic arch (in front of the ear)
    hits = [_ray_hit((0.12, 0.100, z), (-1, 0, 0)) for z in np.arange(0.015, 0.0451, 0.0005)]
    A["zygion_l"] = max(hits, key=lambda p: p[0])
    # jaw angle: ray aimed down-back-out from the jaw capsule's corner
    c = np.array([0.0405, 0.0330, -0.0030])
    dirn = np.array([1.0, -0.9, -0.5])
    dirn /= np.linalg.norm(dirn)
    A["gonion_l"] = _ray_hit(c + 0.08 * dirn, -dirn)
    return A


def _ear_points_left():
    """Tragion (notch above the tragus), top and bottom of the left ear."""
    A = {}
    tp = ear_to_world(-0.0010, 0.0140, 0.0030)
    A["tragion_l"] = _ray_hit((0.12, tp[1], tp[2]), (-1, 0, 0))
    top = ear_to_world(0.0310, -0.0010, 0.0030)
    A["superaurale_l"] = _ray_hit((top[0], 0.25, top[2]), (0, -1, 0))
    bot = ear_to_world(-0.0310, 0.0010, 0.0010)
    A["subaurale_l"] = _ray_hit((bot[0], 0.0, bot[2]), (0, 1, 0))
    return A


def _snap_to_mesh(A, V, F):
    """Move the points of A (name -> (3,)) onto the mesh V (n, 3), F (m, 3), in place.

    Midline points go to the closest point of the mesh's x = 0 seam, so they
    stay exactly on the symmetry plane; left points go to the closest surface
    point; eye_centre is inside the head and stays.
    """
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    e = e[(V[e[:, 0], 0] == 0.0) & (V[e[:, 1], 0] == 0.0)]
    sa, sb = V[e[:, 0]], V[e[:, 1]]
    for k in [k for k in A if not k.endswith("_l")]:
        ab = sb - sa
        t = np.clip(((A[k] - sa) * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-30), 0, 1)
        q = sa + t[:, None] * ab
        A[k] = q[np.argmin(((q - A[k]) ** 2).sum(1))]
    keys = [k for k in A if k.endswith("_l") and k != "eye_centre_l"]
    P = np.array([A[k] for k in keys])
    _, _, C = igl.point_mesh_squared_distance(P, V, F)
    for k, c_ in zip(keys, C):
        A[k] = c_


def measure_anatomy(V=None, F=None):
    """Key anatomical points of the default head: {name: (x, y, z)} in metres.

    Midline points first, then the subject's left ("_l"); rounded to 0.1 mm.
    If the mesh V (n, 3), F (m, 3) is given, the points are snapped onto it.
    """
    A = _profile_points()
    A.update(_outline_points())
    A.update(_face_points_left())
    A.update(_ear_points_left())
    if V is not None:
        _snap_to_mesh(A, V, F)
    for k in A:
        if not k.endswith("_l"):
            A[k] = np.array([0.0, A[k][1], A[k][2]])
    return {k: tuple(round(float(t), 4) + 0.0 for t in A[k]) for k in A}
