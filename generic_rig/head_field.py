"""The default head's shape as one implicit (signed-distance-like) field.

A smooth union / smooth subtraction of ellipsoids, capsules, tubes and bent
ellipsoids: cranium, forehead, brow ridge, face, cheekbones, jaw, chin, nose
(bridge, tip, alae, nostrils), lips and mouth line, closed-lid bulges with lid
fissure and upper-lid crease, ears (helix rim, antihelix, concha, tragus,
lobe) and the neck.  Sizes aim at the adult means between the male and female
values of Farkas (1994), *Anthropometry of the Head and Face*.

Frame: metres, +Y up, +Z out of the face, +X toward the subject's left;
x = 0 mid-sagittal, y = 0 at menton, z = 0 through the ear canals.  The
field only ever sees |x|, so the head is mirror-symmetric by construction and
the left-side constants below (x > 0) serve both sides.
"""

from __future__ import annotations

import numpy as np

from .implicit_primitives import (capsule, ellipsoid, local, polyline_tube, rot_x,
                                  rot_y, smax, smin, smoothstep)

NECK_CUT_Y = -0.085          # flat bottom of the neck (m)

# Closed-lid bulge of the left eye: centre, radii (m) and orientation.
EYE_C = np.array([0.0315, 0.1130, 0.0575])
EYE_R = np.array([0.0165, 0.0118, 0.0120])
EYE_ROT = rot_y(-14.0)            # lateral side of the eye set further back


def _lid_surface_z(x, y):
    """z (m) of the front of the left closed-lid ellipsoid above (x, y), each (K,)."""
    q = np.stack([x - EYE_C[0], y - EYE_C[1], np.zeros_like(x)], -1)
    # the ellipsoid is rotated, so solve for z by fixed-point steps
    z = np.full_like(x, EYE_C[2] + EYE_R[2])
    for _ in range(30):
        q[:, 2] = z - EYE_C[2]
        loc = q @ EYE_ROT
        s = np.sqrt(((loc / EYE_R) ** 2).sum(-1))
        z = EYE_C[2] + (z - EYE_C[2]) / np.maximum(s, 1e-9) ** 0.5
    return z


def _eye_curves():
    """Lid fissure and upper-lid crease of the left eye, each a (15, 3) polyline (m).

    The fissure runs from endocanthion to exocanthion, sagging slightly; the
    crease is an arc above it.  Both sit just proud of the lid surface so
    the tubes around them cut a groove.
    """
    t = np.linspace(0.0, 1.0, 15)
    en = np.array([0.0165, 0.1118])
    ex = np.array([0.0462, 0.1142])
    x = en[0] + (ex[0] - en[0]) * t
    y = en[1] + (ex[1] - en[1]) * t - 0.0022 * np.sin(np.pi * t) ** 1.2
    fiss = np.stack([x, y, _lid_surface_z(x, y) + 0.0005], -1)
    xc = 0.0175 + (0.0470 - 0.0175) * t
    yc = 0.1148 + 0.0022 * (1 - t) + 0.0060 * np.sin(np.pi * t) ** 0.8
    crease = np.stack([xc, yc, _lid_surface_z(xc, yc) + 0.0016], -1)
    return fiss, crease


FISSURE, CREASE = _eye_curves()
# the crease groove is widest in the middle
_CREASE_R = np.concatenate([np.linspace(0.0018, 0.0027, 8), np.linspace(0.0027, 0.0018, 8)[1:]])


def ear_frame():
    """Left ear's local frame: origin (3,) m and unit axes up, fw, n (each (3,)).

    up runs along the ear's long axis, fw toward the face, n out of the ear
    plane.  The ear is turned 22 deg back about +Y and tilted 16 deg.
    """
    E = np.array([0.0705, 0.1030, -0.0170])
    th, ph = np.radians(22.0), np.radians(16.0)
    n = np.array([np.cos(th), 0.0, np.sin(th)])
    fwd = np.array([-np.sin(th), 0.0, np.cos(th)])
    upv = np.array([0.0, 1.0, 0.0])
    up = np.cos(ph) * upv - np.sin(ph) * fwd
    fw = np.sin(ph) * upv + np.cos(ph) * fwd
    return E, up, fw, n


def ear_to_world(u, v, w):
    """World point (3,) of the ear-local coordinates (u up, v forward, w out), m."""
    E, up, fw, n = ear_frame()
    return E + u * up + v * fw + w * n


def _ear(p):
    """Field of the left ear at points p (N, 3), built in the ear-local frame."""
    E, up, fw, n = ear_frame()
    d = p - E
    u, v, w = d @ up, d @ fw, d @ n
    ru = 0.0310
    rv = 0.0175 * (1.0 - 0.30 * smoothstep(0.0, 1.0, -u / ru)) \
        * (1.0 + 0.06 * smoothstep(0.0, 1.0, u / ru))
    vc = -0.0015 * smoothstep(-1.0, 1.0, u / ru)
    rr = np.sqrt((u / ru) ** 2 + ((v - vc) / rv) ** 2)
    d2 = (rr - 1.0) * rv                    # ~2D distance to the outline
    # dish: rim flares out laterally, centre sits closer to the head
    bowl = 0.0030 * np.clip(rr, 0, 1.2) ** 2
    plate = np.maximum(d2, np.abs(w - bowl) - 0.0017)
    # helix: a rolled rim along the top and back, fading out at the front-low end
    front_low = smoothstep(0.004, 0.012, v) * smoothstep(0.004, -0.010, u)
    rim_r = 0.0030 * (1.0 - front_low) + 1e-4
    rim = np.sqrt((d2 + 0.0030) ** 2 + (w - 0.0040) ** 2) - rim_r
    ear = smin(plate, rim, 0.0015)
    # antihelix: a softer inner ridge, upper/back part only
    rr2 = np.sqrt((u / (ru * 0.62)) ** 2 + ((v - 0.001) / (rv * 0.62)) ** 2)
    ah = np.sqrt(((rr2 - 1.0) * rv * 0.62) ** 2 + (w - 0.0032) ** 2) - 0.0018
    ah = np.maximum(ah, -(0.0 - u) - 0.004)
    ah = np.maximum(ah, v - 0.006)
    ear = smin(ear, ah, 0.0015)
    uvw = np.stack([u, v, w], -1)
    ear = smin(ear, ellipsoid(uvw, (-0.0235, 0.0010, 0.0010),
                              (0.0085, 0.0080, 0.0036)), 0.003)          # lobe
    ear = smin(ear, ellipsoid(uvw, (-0.0020, 0.0050, -0.0060),
                              (0.0150, 0.0115, 0.0085)), 0.004)          # root on the head
    conch = ellipsoid(uvw, (-0.0045, 0.0040, 0.0062), (0.0115, 0.0085, 0.0062))
    ear = smax(ear, -conch, 0.0015)                                       # concha bowl
    ear = smin(ear, ellipsoid(uvw, (-0.0070, 0.0135, 0.0030),
                              (0.0050, 0.0028, 0.0030)), 0.0015)          # tragus
    return ear


def _skull_and_face(p):
    """Cranium, brow, cheekbones, jaw and chin, before the neck: field at p (N, 3)."""
    f = ellipsoid(p, (0.0, 0.1430, -0.0045), (0.0745, 0.0830, 0.0920))
    f = smin(f, ellipsoid(p, (0.0, 0.1500, 0.0150), (0.0640, 0.0700, 0.0760)), 0.010)
    # brow ridge and glabella
    brow = capsule(p, (0.0, 0.1350, 0.0830), (0.0300, 0.1370, 0.0775), 0.0085, 0.0080)
    brow = smin(brow, capsule(p, (0.0300, 0.1370, 0.0775), (0.0520, 0.1330, 0.0580),
                              0.0080, 0.0065), 0.004)
    f = smin(f, brow, 0.014)
    # mid face (maxilla) and cheekbones
    f = smin(f, ellipsoid(p, (0.0, 0.0920, 0.0200), (0.0600, 0.0520, 0.0620)), 0.012)
    zyg = capsule(p, (0.0470, 0.0990, 0.0450), (0.0640, 0.1010, 0.0080), 0.0060, 0.0050)
    f = smin(f, zyg, 0.014)
    f = smin(f, ellipsoid(p, (0.0420, 0.0950, 0.0480), (0.0160, 0.0130, 0.0160)), 0.020)
    # lower face: muzzle, jaw, chin
    f = smin(f, ellipsoid(p, (0.0, 0.0520, 0.0420), (0.0400, 0.0360, 0.0440)), 0.012)
    jaw = capsule(p, (0.0510, 0.0880, -0.0080), (0.0405, 0.0330, -0.0030), 0.0090, 0.0100)
    jaw = smin(jaw, capsule(p, (0.0405, 0.0330, -0.0030), (0.0180, 0.0090, 0.0620),
                            0.0100, 0.0100), 0.006)
    f = smin(f, jaw, 0.018)
    f = smin(f, ellipsoid(p, (0.0, 0.0300, 0.0300), (0.0480, 0.0300, 0.0450)), 0.012)
    f = smin(f, ellipsoid(p, (0.0, 0.0150, 0.0700), (0.0200, 0.0150, 0.0140)), 0.008)
    return f


def _neck(x, y, z):
    """Neck field from coordinate arrays x, y, z (each (N,), m).

    An elliptic column whose axis leans forward at the top and which thickens
    toward the base; capped above so it does not poke through the head.
    """
    yl = np.minimum(y, 0.0)
    nzc = -0.0180 + 0.06 * y
    nrz = 0.0540 - 0.10 * yl
    nrx = 0.0520 - 0.07 * yl
    neck = (np.sqrt((x / nrx) ** 2 + ((z - nzc) / nrz) ** 2) - 1.0) * 0.053
    return smax(neck, y - 0.090, 0.01)


def _eyes(f, p):
    """Carve the eye sockets, add the closed lids, cut fissure and crease: new field."""
    sock = ellipsoid(p, (0.0330, 0.1160, 0.0770), (0.0200, 0.0140, 0.0140), rot_y(-12))
    f = smax(f, -sock, 0.008)
    f = smin(f, ellipsoid(p, EYE_C, EYE_R, EYE_ROT), 0.005)
    fiss = local(p, (0.008, 0.100, 0.035), (0.056, 0.125, 0.085),
                 lambda q: polyline_tube(q, FISSURE, 0.0013))
    f = smax(f, -fiss, 0.0008)
    crease = local(p, (0.008, 0.100, 0.035), (0.058, 0.130, 0.085),
                   lambda q: polyline_tube(q, CREASE, _CREASE_R))
    return smax(f, -crease, 0.0015)


def _nose(f, p):
    """Add bridge, dorsum, tip and alae; carve the nostrils: new field."""
    nose = capsule(p, (0.0, 0.1190, 0.0795), (0.0, 0.0850, 0.0985), 0.0055, 0.0075)
    nose = smin(nose, ellipsoid(p, (0.0, 0.0935, 0.0800), (0.0120, 0.0265, 0.0140),
                                rot_x(34)), 0.005)
    nose = smin(nose, ellipsoid(p, (0.0, 0.0818, 0.0985), (0.0085, 0.0080, 0.0085)), 0.005)
    nose = smin(nose, capsule(p, (0.0130, 0.0750, 0.0815), (0.0075, 0.0760, 0.0930),
                              0.0052, 0.0040), 0.006)
    f = smin(f, nose, 0.004)
    nostril = ellipsoid(p, (0.0068, 0.0705, 0.0925), (0.0038, 0.0026, 0.0062), rot_y(18))
    return smax(f, -nostril, 0.0015)


def _lips(f, p):
    """Add the upper-lip skin and both lips, cut the mouth line and philtrum: new field.

    The lips and the mouth line are bent back along the dental arch (z shifted
    by -0.020 (x / 0.027)^2 m) so the mouth corners sit behind the lip centre.
    """
    pa = p.copy()
    pa[:, 2] = p[:, 2] + 0.020 * (p[:, 0] / 0.027) ** 2
    upper = ellipsoid(pa, (0.0, 0.0530, 0.0865), (0.0280, 0.0060, 0.0065), rot_x(-12))
    lower = ellipsoid(pa, (0.0, 0.0415, 0.0845), (0.0235, 0.0065, 0.0070), rot_x(15))
    # skin of the upper lip (subnasale -> vermilion), fuller than the muzzle
    f = smin(f, ellipsoid(p, (0.0, 0.0615, 0.0785), (0.0230, 0.0120, 0.0100)), 0.018)
    f = smin(f, smin(upper, lower, 0.002), 0.004)
    slit = ellipsoid(pa, (0.0, 0.0480, 0.0925), (0.0295, 0.0011, 0.0055))
    f = smax(f, -slit, 0.0010)
    phil = ellipsoid(p, (0.0, 0.0625, 0.0915), (0.0035, 0.0070, 0.0025))
    return smax(f, -phil, 0.0020)


def head_field(P):
    """Signed field of the head at points P (N, 3), metres: (N,), negative inside."""
    p = np.array(P, dtype=float)
    p[:, 0] = np.abs(p[:, 0])                 # mirror symmetry by construction
    f = _skull_and_face(p)
    f = smin(f, _neck(p[:, 0], p[:, 1], p[:, 2]), 0.025)
    f = _eyes(f, p)
    f = _nose(f, p)
    f = _lips(f, p)
    ear = local(p, (0.040, 0.060, -0.065), (0.110, 0.150, 0.020), _ear)
    f = smin(f, ear, 0.0025)
    return smax(f, NECK_CUT_Y - p[:, 1], 0.004)    # flat neck cut, small fillet
