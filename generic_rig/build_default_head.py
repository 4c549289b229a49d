"""Build autobones' built-in default head: ``generic_rig/default_head.obj``.

What it builds
    A neutral, closed-eyed, closed-mouthed adult human head with neck, made
    procedurally (no third-party mesh is read or used).  The shape is an
    implicit surface: a smooth union / smooth subtraction of ellipsoids,
    capsules, tubes and bent ellipsoids (cranium, forehead, brow ridge, face,
    cheekbones, jaw, chin, nose bridge/tip/alae/nostrils, lips and mouth line,
    eyelid bulges with lid fissure and upper-lid crease, ears with helix rim,
    concha, tragus and lobe, neck), sized from ``shared/spec/anthropometry.md``
    (adult means between the male and female values).

Pipeline
    1. Sample the field on a regular grid covering x >= 0 only (the field only
       ever sees |x|, so the head is mirror-symmetric by construction).
    2. Marching cubes (scikit-image) on that half volume -> an open half-surface
       whose border lies exactly on the plane x = 0.
    3. Quadric edge-collapse decimation (libigl qslim, which keeps the mesh
       manifold); the border vertices are then snapped exactly onto x = 0.
    4. A few rounds of Delaunay edge flips + tangential relaxation, each
       vertex re-projected onto the dense marching-cubes surface (border
       vertices slide inside the plane x = 0).
    5. Mirror the half across x = 0 and weld the border -> closed, manifold,
       single-component, outward-oriented triangle mesh whose vertex set is
       exactly symmetric (the mirrored copy uses -x bit-for-bit).
    6. Write an OBJ with only ``v``/``f`` lines (``%.7f``), deterministically.

Frame, units, origin
    Metres.  +Y up, +Z out of the face (the head looks along +Z), +X toward
    the subject's own LEFT ear.  Origin: x = 0 on the mid-sagittal (symmetry)
    plane, y = 0 at the height of menton (lowest point of the chin), z = 0 on
    the coronal plane through the ear canals (tragion is at z = -0.003).
    The neck is cut flat at y = NECK_CUT_Y (= -0.085) and capped.

    ``ANATOMY`` (below) gives the positions of key anatomical points in this
    frame; they are measured on the built surface (see ``--measure``).

Run
    python generic_rig/build_default_head.py            # writes default_head.obj
    python generic_rig/build_default_head.py --render gallery/default_head.png
    python generic_rig/build_default_head.py --check    # print mesh statistics
    python generic_rig/build_default_head.py --measure  # print the ANATOMY table
    (about 1.5 min; the output is byte-identical from run to run.)

Build-time requirements: numpy, scipy, scikit-image, libigl (``igl``);
matplotlib only for ``--render``.  Importing this module needs only numpy.
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
OUT_OBJ = os.path.join(HERE, "default_head.obj")

NECK_CUT_Y = -0.085          # flat bottom of the neck (m)
GRID_STEP = 0.0008           # marching-cubes sampling step (m)
TARGET_TRIANGLES = 8000      # full-head triangle budget

# Key anatomical points in the output frame (metres), measured on the built
# mesh with ``--measure`` (surface points snapped to the mesh; eye_centre is
# the centre of the closed-lid/eyeball bulge, inside the head).  "_l" = the
# subject's left (+x); the "_r" entries are added below as exact mirror images
# (x -> -x).  Midline points have x = 0.  Re-run --measure after changing the
# shape and paste the table here.
ANATOMY: dict[str, tuple[float, float, float]] = {
    "pronasale": (0.0000, 0.0829, 0.1075),
    "glabella": (0.0000, 0.1367, 0.0946),
    "nasion": (0.0000, 0.1201, 0.0913),
    "subnasale": (0.0000, 0.0691, 0.0908),
    "stomion": (0.0000, 0.0478, 0.0896),
    "labrale_superius": (0.0000, 0.0535, 0.0928),
    "labrale_inferius": (0.0000, 0.0413, 0.0914),
    "pogonion": (0.0000, 0.0150, 0.0837),
    "menton": (0.0000, 0.0004, 0.0700),
    "vertex": (0.0000, 0.2260, -0.0020),
    "opisthocranion": (0.0000, 0.1430, -0.0964),
    "exocanthion_l": (0.0464, 0.1142, 0.0631),
    "endocanthion_l": (0.0166, 0.1118, 0.0688),
    "eye_centre_l": (0.0315, 0.1130, 0.0575),
    "cheilion_l": (0.0264, 0.0484, 0.0718),
    "alare_l": (0.0211, 0.0720, 0.0839),
    "zygion_l": (0.0689, 0.1000, 0.0149),
    "gonion_l": (0.0551, 0.0198, -0.0103),
    "tragion_l": (0.0710, 0.1061, -0.0031),
    "superaurale_l": (0.0768, 0.1329, -0.0246),
    "subaurale_l": (0.0680, 0.0718, -0.0078),
}
ANATOMY.update({k[:-2] + "_r": (-v[0] + 0.0, v[1], v[2])
                for k, v in list(ANATOMY.items()) if k.endswith("_l")})


# ---------------------------------------------------------------------------
# implicit-modelling primitives (all vectorised over an (N, 3) array)
# ---------------------------------------------------------------------------

def smin(a, b, k):
    """Polynomial smooth minimum (smooth union) with blend radius k."""
    if k <= 0:
        return np.minimum(a, b)
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return b + (a - b) * h - k * h * (1.0 - h)


def smax(a, b, k):
    """Smooth maximum (smooth intersection / subtraction with -b)."""
    return -smin(-a, -b, k)


def rot_x(deg):
    t = np.radians(deg)
    c, s = np.cos(t), np.sin(t)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(deg):
    t = np.radians(deg)
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(deg):
    t = np.radians(deg)
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def ellipsoid(p, c, r, R=None):
    """Approximate signed distance to an ellipsoid (centre c, radii r).

    R (3x3) rotates the ellipsoid's local axes into world: local = (p-c) @ R.
    """
    q = p - np.asarray(c, float)
    if R is not None:
        q = q @ np.asarray(R, float)
    r = np.asarray(r, float)
    k0 = np.sqrt(((q / r) ** 2).sum(-1))
    k1 = np.sqrt(((q / (r * r)) ** 2).sum(-1))
    return k0 * (k0 - 1.0) / np.maximum(k1, 1e-12)


def capsule(p, a, b, ra, rb=None):
    """Distance to a round cone / capsule from a (radius ra) to b (radius rb)."""
    if rb is None:
        rb = ra
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    ab = b - a
    t = np.clip(((p - a) @ ab) / (ab @ ab), 0.0, 1.0)
    d = np.linalg.norm(p - (a + t[:, None] * ab), axis=-1)
    return d - (ra + (rb - ra) * t)


def polyline_tube(p, pts, r):
    """Distance to a tube of radius r (scalar or per-point) around a polyline."""
    pts = np.asarray(pts, float)
    r = np.broadcast_to(np.asarray(r, float), (len(pts),))
    best = np.full(len(p), np.inf)
    for i in range(len(pts) - 1):
        a, b = pts[i], pts[i + 1]
        ab = b - a
        t = np.clip(((p - a) @ ab) / (ab @ ab), 0.0, 1.0)
        d = np.linalg.norm(p - (a + t[:, None] * ab), axis=-1)
        d = d - (r[i] + (r[i + 1] - r[i]) * t)
        best = np.minimum(best, d)
    return best


def local(p, lo, hi, fun, far=1.0):
    """Evaluate fun only for points inside the box [lo, hi]; `far` elsewhere."""
    lo = np.asarray(lo, float)
    hi = np.asarray(hi, float)
    m = np.all((p >= lo) & (p <= hi), axis=1)
    out = np.full(len(p), far)
    if m.any():
        out[m] = fun(p[m])
    return out


def smoothstep(e0, e1, x):
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3 - 2 * t)


# ---------------------------------------------------------------------------
# the head
# ---------------------------------------------------------------------------

# Eye (closed lid bulge) parameters: centre of the lid "ball" of the left eye.
EYE_C = np.array([0.0315, 0.1130, 0.0575])
EYE_R = np.array([0.0165, 0.0118, 0.0120])
EYE_ROT = rot_y(-14.0)            # lateral side of the eye set further back


def _lid_surface_z(x, y):
    """z of the front of the closed-lid ellipsoid at (x, y) (left eye)."""
    q = np.stack([x - EYE_C[0], y - EYE_C[1], np.zeros_like(x)], -1)
    # solve for z on the rotated ellipsoid by a few fixed-point steps
    z = np.full_like(x, EYE_C[2] + EYE_R[2])
    for _ in range(30):
        q[:, 2] = z - EYE_C[2]
        loc = q @ EYE_ROT
        s = np.sqrt(((loc / EYE_R) ** 2).sum(-1))
        z = EYE_C[2] + (z - EYE_C[2]) / np.maximum(s, 1e-9) ** 0.5
    return z


def _eye_curves():
    """Lid fissure and upper-lid crease polylines (left eye)."""
    t = np.linspace(0.0, 1.0, 15)
    en = np.array([0.0165, 0.1118])
    ex = np.array([0.0462, 0.1142])
    x = en[0] + (ex[0] - en[0]) * t
    y = en[1] + (ex[1] - en[1]) * t - 0.0022 * np.sin(np.pi * t) ** 1.2
    fiss = np.stack([x, y, _lid_surface_z(x, y) + 0.0005], -1)
    # upper-lid crease: an arc above the fissure
    xc = 0.0175 + (0.0470 - 0.0175) * t
    yc = 0.1148 + 0.0022 * (1 - t) + 0.0060 * np.sin(np.pi * t) ** 0.8
    crease = np.stack([xc, yc, _lid_surface_z(xc, yc) + 0.0016], -1)
    return fiss, crease


_FISSURE, _CREASE = _eye_curves()


def _ear(p):
    """Left ear (x > 0), in an ear-local frame."""
    E = np.array([0.0705, 0.1030, -0.0170])
    th, ph = np.radians(22.0), np.radians(16.0)
    n = np.array([np.cos(th), 0.0, np.sin(th)])
    fwd = np.array([-np.sin(th), 0.0, np.cos(th)])
    upv = np.array([0.0, 1.0, 0.0])
    up = np.cos(ph) * upv - np.sin(ph) * fwd
    fw = np.sin(ph) * upv + np.cos(ph) * fwd
    d = p - E
    u = d @ up          # along the ear's long axis (up)
    v = d @ fw          # toward the face
    w = d @ n           # out of the ear plane (lateral)
    ru = 0.0310
    rv = 0.0175 * (1.0 - 0.30 * smoothstep(0.0, 1.0, -u / ru)) \
        * (1.0 + 0.06 * smoothstep(0.0, 1.0, u / ru))
    vc = -0.0015 * smoothstep(-1.0, 1.0, u / ru)
    rr = np.sqrt((u / ru) ** 2 + ((v - vc) / rv) ** 2)
    d2 = (rr - 1.0) * rv                    # ~2D distance to the outline
    # dish: rim flares out laterally, centre sits closer to the head
    bowl = 0.0030 * np.clip(rr, 0, 1.2) ** 2
    plate = np.maximum(d2, np.abs(w - bowl) - 0.0017)
    # helix: a rolled rim along the top and back
    front_low = smoothstep(0.004, 0.012, v) * smoothstep(0.004, -0.010, u)
    rim_r = 0.0030 * (1.0 - front_low) + 1e-4
    rim = np.sqrt((d2 + 0.0030) ** 2 + (w - 0.0040) ** 2) - rim_r
    ear = smin(plate, rim, 0.0015)
    # antihelix: a softer inner ridge
    rr2 = np.sqrt((u / (ru * 0.62)) ** 2 + ((v - 0.001) / (rv * 0.62)) ** 2)
    ah = np.sqrt(((rr2 - 1.0) * rv * 0.62) ** 2 + (w - 0.0032) ** 2) - 0.0018
    ah = np.maximum(ah, -(0.0 - u) - 0.004)        # only upper/back part
    ah = np.maximum(ah, v - 0.006)
    ear = smin(ear, ah, 0.0015)
    # lobe
    ear = smin(ear, ellipsoid(np.stack([u, v, w], -1), (-0.0235, 0.0010, 0.0010),
                              (0.0085, 0.0080, 0.0036)), 0.003)
    # root / back of the concha joining the ear to the head
    ear = smin(ear, ellipsoid(np.stack([u, v, w], -1), (-0.0020, 0.0050, -0.0060),
                              (0.0150, 0.0115, 0.0085)), 0.004)
    # concha: bowl carved into the front-middle of the ear
    conch = ellipsoid(np.stack([u, v, w], -1), (-0.0045, 0.0040, 0.0062),
                      (0.0115, 0.0085, 0.0062))
    ear = smax(ear, -conch, 0.0015)
    # tragus: small flap in front of the concha
    ear = smin(ear, ellipsoid(np.stack([u, v, w], -1), (-0.0070, 0.0135, 0.0030),
                              (0.0050, 0.0028, 0.0030)), 0.0015)
    return ear


def head_field(P):
    """Signed field (metres, negative inside) of the head at points P (N, 3)."""
    p = np.array(P, dtype=float)
    p[:, 0] = np.abs(p[:, 0])                 # mirror symmetry by construction
    x, y, z = p[:, 0], p[:, 1], p[:, 2]

    # --- cranium and forehead
    f = ellipsoid(p, (0.0, 0.1430, -0.0045), (0.0745, 0.0830, 0.0920))
    f = smin(f, ellipsoid(p, (0.0, 0.1500, 0.0150), (0.0640, 0.0700, 0.0760)), 0.010)
    # --- brow ridge + glabella
    brow = capsule(p, (0.0, 0.1350, 0.0830), (0.0300, 0.1370, 0.0775), 0.0085, 0.0080)
    brow = smin(brow, capsule(p, (0.0300, 0.1370, 0.0775), (0.0520, 0.1330, 0.0580),
                              0.0080, 0.0065), 0.004)
    f = smin(f, brow, 0.014)
    # --- mid face (maxilla) and cheekbones
    f = smin(f, ellipsoid(p, (0.0, 0.0920, 0.0200), (0.0600, 0.0520, 0.0620)), 0.012)
    zyg = capsule(p, (0.0470, 0.0990, 0.0450), (0.0640, 0.1010, 0.0080), 0.0060, 0.0050)
    f = smin(f, zyg, 0.014)
    f = smin(f, ellipsoid(p, (0.0420, 0.0950, 0.0480), (0.0160, 0.0130, 0.0160)), 0.020)
    # --- lower face: muzzle, jaw, chin
    f = smin(f, ellipsoid(p, (0.0, 0.0520, 0.0420), (0.0400, 0.0360, 0.0440)), 0.012)
    jaw = capsule(p, (0.0510, 0.0880, -0.0080), (0.0405, 0.0330, -0.0030), 0.0090, 0.0100)
    jaw = smin(jaw, capsule(p, (0.0405, 0.0330, -0.0030), (0.0180, 0.0090, 0.0620),
                            0.0100, 0.0100), 0.006)
    f = smin(f, jaw, 0.018)
    f = smin(f, ellipsoid(p, (0.0, 0.0300, 0.0300), (0.0480, 0.0300, 0.0450)), 0.012)
    f = smin(f, ellipsoid(p, (0.0, 0.0150, 0.0700), (0.0200, 0.0150, 0.0140)), 0.008)
    # --- neck (slightly inclined forward at the top), cut flat at the bottom
    yl = np.minimum(y, 0.0)
    nzc = -0.0180 + 0.06 * y                       # axis leans forward at the top
    nrz = 0.0540 - 0.10 * yl                       # thicker toward the base
    nrx = 0.0520 - 0.07 * yl
    neck = (np.sqrt((x / nrx) ** 2 + ((z - nzc) / nrz) ** 2) - 1.0) * 0.053
    neck = smax(neck, y - 0.090, 0.01)
    f = smin(f, neck, 0.025)

    # --- eye sockets, then the closed-lid bulges
    sock = ellipsoid(p, (0.0330, 0.1160, 0.0770), (0.0200, 0.0140, 0.0140), rot_y(-12))
    f = smax(f, -sock, 0.008)
    lid = ellipsoid(p, EYE_C, EYE_R, EYE_ROT)
    f = smin(f, lid, 0.005)
    fiss = local(p, (0.008, 0.100, 0.035), (0.056, 0.125, 0.085),
                 lambda q: polyline_tube(q, _FISSURE, 0.0013))
    f = smax(f, -fiss, 0.0008)
    crease = local(p, (0.008, 0.100, 0.035), (0.058, 0.130, 0.085),
                   lambda q: polyline_tube(q, _CREASE, np.concatenate(
                       [np.linspace(0.0018, 0.0027, 8), np.linspace(0.0027, 0.0018, 8)[1:]])))
    f = smax(f, -crease, 0.0015)

    # --- nose
    nose = capsule(p, (0.0, 0.1190, 0.0795), (0.0, 0.0850, 0.0985), 0.0055, 0.0075)
    nose = smin(nose, ellipsoid(p, (0.0, 0.0935, 0.0800), (0.0120, 0.0265, 0.0140),
                                rot_x(34)), 0.005)
    nose = smin(nose, ellipsoid(p, (0.0, 0.0818, 0.0985), (0.0085, 0.0080, 0.0085)), 0.005)
    nose = smin(nose, capsule(p, (0.0130, 0.0750, 0.0815), (0.0075, 0.0760, 0.0930),
                              0.0052, 0.0040), 0.006)
    f = smin(f, nose, 0.004)
    nostril = ellipsoid(p, (0.0068, 0.0705, 0.0925), (0.0038, 0.0026, 0.0062), rot_y(18))
    f = smax(f, -nostril, 0.0015)

    # --- lips and mouth line (bent along the dental arch)
    def arch(xx):
        return -0.020 * (xx / 0.027) ** 2
    pa = p.copy()
    pa[:, 2] = z - arch(x)
    upper = ellipsoid(pa, (0.0, 0.0530, 0.0865), (0.0280, 0.0060, 0.0065), rot_x(-12))
    lower = ellipsoid(pa, (0.0, 0.0415, 0.0845), (0.0235, 0.0065, 0.0070), rot_x(15))
    # skin of the upper lip (subnasale -> vermilion), fuller than the muzzle
    f = smin(f, ellipsoid(p, (0.0, 0.0615, 0.0785), (0.0230, 0.0120, 0.0100)), 0.018)
    f = smin(f, smin(upper, lower, 0.002), 0.004)
    slit = ellipsoid(pa, (0.0, 0.0480, 0.0925), (0.0295, 0.0011, 0.0055))
    f = smax(f, -slit, 0.0010)
    phil = ellipsoid(p, (0.0, 0.0625, 0.0915), (0.0035, 0.0070, 0.0025))
    f = smax(f, -phil, 0.0020)

    # --- ears
    ear = local(p, (0.040, 0.060, -0.065), (0.110, 0.150, 0.020), _ear)
    f = smin(f, ear, 0.0025)

    # --- flat neck cut (small fillet at the rim)
    f = smax(f, NECK_CUT_Y - y, 0.004)
    return f


# ---------------------------------------------------------------------------
# meshing
# ---------------------------------------------------------------------------

def sample_half(step=GRID_STEP):
    """Sample the field on a grid with x in [0, xmax] (first plane at x=0)."""
    xs = np.arange(0, int(round(0.105 / step)) + 1) * step
    y0, y1 = NECK_CUT_Y - 3.5 * step, 0.240
    ys = y0 + np.arange(0, int(np.ceil((y1 - y0) / step)) + 1) * step
    z0, z1 = -0.115, 0.125
    zs = z0 + np.arange(0, int(np.ceil((z1 - z0) / step)) + 1) * step
    # put the neck cut half-way between two grid planes -> flat cap
    vol = np.empty((len(xs), len(ys), len(zs)), dtype=np.float64)
    Y, Z = np.meshgrid(ys, zs, indexing="ij")
    for i, xv in enumerate(xs):
        P = np.stack([np.full(Y.size, xv), Y.ravel(), Z.ravel()], -1)
        vol[i] = head_field(P).reshape(Y.shape)
    return vol, (xs, ys, zs)


def marching_half(step=GRID_STEP):
    from skimage.measure import marching_cubes
    vol, (xs, ys, zs) = sample_half(step)
    vol[vol == 0.0] = 1e-12            # no vertex exactly on a grid node
    verts, faces, _, _ = marching_cubes(vol, level=0.0, spacing=(step, step, step),
                                        allow_degenerate=False)
    verts = verts + np.array([xs[0], ys[0], zs[0]])
    verts[np.abs(verts[:, 0]) < 1e-12, 0] = 0.0
    faces = faces.astype(np.int64)
    # orient outward: field increases outward; skimage gives faces whose
    # orientation depends on gradient convention -> check and flip if needed
    v0, v1, v2 = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    n = np.cross(v1 - v0, v2 - v0)
    c = (v0 + v1 + v2) / 3
    eps = 1e-4
    nn = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-20)
    sel = np.arange(0, len(faces), max(1, len(faces) // 2000))
    outward = head_field(c[sel] + eps * nn[sel]) > head_field(c[sel] - eps * nn[sel])
    if outward.mean() < 0.5:
        faces = faces[:, ::-1].copy()
    verts, faces = _clean(verts, faces)
    return verts, faces


def _clean(V, F):
    """Drop degenerate faces and unreferenced vertices (order-preserving)."""
    F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])]
    used = np.zeros(len(V), bool)
    used[F.ravel()] = True
    remap = -np.ones(len(V), np.int64)
    remap[used] = np.arange(used.sum())
    return V[used], remap[F]


def is_manifold(F):
    """Edge- and vertex-manifold, consistently oriented (borders allowed)."""
    d = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    if len(np.unique(d, axis=0)) != len(d):
        return False
    _, c = np.unique(np.sort(d, axis=1), axis=0, return_counts=True)
    if c.max() > 2:
        return False
    # vertex manifold: the one-ring edges (opposite edges) form one fan/cycle
    opp = {}
    for a, b, c_ in F.tolist():
        opp.setdefault(a, []).append((b, c_))
        opp.setdefault(b, []).append((c_, a))
        opp.setdefault(c_, []).append((a, b))
    for v, edges in opp.items():
        nxt = dict(edges)
        if len(nxt) != len(edges):
            return False
        starts = set(nxt) - set(nxt.values())
        if len(starts) > 1:
            return False
        s = next(iter(starts)) if starts else edges[0][0]
        seen, cur = 0, s
        while cur in nxt and seen <= len(edges):
            cur = nxt[cur]
            seen += 1
            if cur == s:
                break
        if seen != len(edges):
            return False
    return True


def keep_largest_component(V, F):
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components
    n = len(V)
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    A = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    _, lab = connected_components(A, directed=False)
    big = np.argmax(np.bincount(lab[F[:, 0]]))
    F = F[lab[F[:, 0]] == big]
    return _clean(V, F)


def boundary_edges(F):
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    key = np.sort(e, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return e[cnt[inv.ravel()] == 1]


def tri_angles(V, F):
    a = V[F[:, 1]] - V[F[:, 0]]
    b = V[F[:, 2]] - V[F[:, 1]]
    c = V[F[:, 0]] - V[F[:, 2]]

    def ang(u, v):
        cu = np.einsum("ij,ij->i", u, v) / np.maximum(
            np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1), 1e-30)
        return np.degrees(np.arccos(np.clip(cu, -1, 1)))
    return np.stack([ang(a, -c), ang(b, -a), ang(c, -b)], -1)


def delaunay_flips(V, F, border_v, max_normal_deg=25.0, passes=6):
    """Flip interior edges whose opposite angles sum > 180 deg (planar-ish)."""
    F = F.copy()
    for _ in range(passes):
        nflip = 0
        edge_map = {}
        for fi, (a, b, c) in enumerate(F):
            for (u, v, w) in ((a, b, c), (b, c, a), (c, a, b)):
                edge_map[(u, v)] = (fi, w)
        done = set()
        for (u, v), (f1, w1) in sorted(edge_map.items()):
            if (v, u) not in edge_map or (min(u, v), max(u, v)) in done:
                continue
            f2, w2 = edge_map[(v, u)]
            done.add((min(u, v), max(u, v)))
            if F[f1].tolist().count(u) == 0 or F[f2].tolist().count(v) == 0:
                continue
            # still the same faces?
            if set(F[f1]) != {u, v, w1} or set(F[f2]) != {u, v, w2}:
                continue
            if w1 == w2 or (w1, w2) in edge_map or (w2, w1) in edge_map:
                continue
            if border_v[w1] and border_v[w2]:
                continue                    # would make a face lying in x = 0
            pu, pv, p1, p2 = V[u], V[v], V[w1], V[w2]

            def angle(at, p, q):
                a_, b_ = p - at, q - at
                return np.arccos(np.clip(a_ @ b_ / (np.linalg.norm(a_) * np.linalg.norm(b_)
                                                    + 1e-30), -1, 1))
            if angle(p1, pu, pv) + angle(p2, pu, pv) <= np.pi + 1e-9:
                continue
            n1 = np.cross(pv - pu, p1 - pu)
            n2 = np.cross(pu - pv, p2 - pv)
            n1 /= np.linalg.norm(n1) + 1e-30
            n2 /= np.linalg.norm(n2) + 1e-30
            if n1 @ n2 < np.cos(np.radians(max_normal_deg)):
                continue
            # new faces (w1, u, w2) and (w2, v, w1) keep orientation
            na = np.cross(pu - p1, p2 - p1)
            nb = np.cross(pv - p2, p1 - p2)
            if na @ (n1 + n2) <= 0 or nb @ (n1 + n2) <= 0:
                continue
            # do not make the minimum angle worse
            old = min(tri_angles(V, np.array([[u, v, w1], [v, u, w2]])).min(), 180)
            new = tri_angles(V, np.array([[w1, u, w2], [w2, v, w1]])).min()
            if new <= old:
                continue
            F[f1] = (w1, u, w2)
            F[f2] = (w2, v, w1)
            for key in ((u, v), (v, u)):
                edge_map.pop(key, None)
            edge_map[(w1, u)] = (f1, w2)
            edge_map[(u, w2)] = (f1, w1)
            edge_map[(w2, w1)] = (f1, u)
            edge_map[(w2, v)] = (f2, w1)
            edge_map[(v, w1)] = (f2, w2)
            edge_map[(w1, w2)] = (f2, v)
            nflip += 1
        if nflip == 0:
            break
    return F


def relax(V, F, refV, refF, iters=8, lam=0.5):
    """Tangential relaxation with re-projection onto the reference surface.

    Vertices on the x = 0 border move along the border (re-projected onto the
    reference border polyline in the plane x = 0)."""
    import igl
    V = V.copy()
    n = len(V)
    be = boundary_edges(F)
    on_b = np.zeros(n, bool)
    on_b[be.ravel()] = True
    # reference border polyline (2D in the y-z plane)
    rbe = boundary_edges(refF)
    ra, rb = refV[rbe[:, 0]][:, 1:], refV[rbe[:, 1]][:, 1:]
    for _ in range(iters):
        # area-weighted centroid of the one-ring faces (CVT-like)
        v0, v1, v2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
        fa = 0.5 * np.linalg.norm(np.cross(v1 - v0, v2 - v0), axis=1)
        fc = (v0 + v1 + v2) / 3
        acc = np.zeros((n, 3))
        w = np.zeros(n)
        for k in range(3):
            np.add.at(acc, F[:, k], fc * fa[:, None])
            np.add.at(w, F[:, k], fa)
        target = acc / np.maximum(w, 1e-30)[:, None]
        N = igl.per_vertex_normals(V, F)
        d = target - V
        d -= (d * N).sum(1, keepdims=True) * N
        # border: average of the two border neighbours
        bt = np.zeros((n, 3))
        bc = np.zeros(n)
        np.add.at(bt, be[:, 0], V[be[:, 1]])
        np.add.at(bt, be[:, 1], V[be[:, 0]])
        np.add.at(bc, be[:, 0], 1)
        np.add.at(bc, be[:, 1], 1)
        db = bt / np.maximum(bc, 1)[:, None] - V
        d[on_b] = db[on_b]
        Vn = V + lam * d
        # re-project interior vertices onto the reference surface
        inner = ~on_b
        _, _, C = igl.point_mesh_squared_distance(Vn[inner], refV, refF)
        Vn[inner] = C
        # border vertices: nearest point on the reference border polyline
        q = Vn[on_b][:, 1:]
        ab = rb - ra
        best = np.full(len(q), np.inf)
        bp = np.zeros_like(q)
        for s in range(0, len(ra), 256):
            A = ra[s:s + 256]
            AB = ab[s:s + 256]
            t = np.clip(((q[:, None, :] - A[None]) * AB[None]).sum(-1)
                        / np.maximum((AB * AB).sum(-1), 1e-30)[None], 0, 1)
            pts = A[None] + t[..., None] * AB[None]
            dd = ((q[:, None, :] - pts) ** 2).sum(-1)
            j = dd.argmin(1)
            dj = dd[np.arange(len(q)), j]
            upd = dj < best
            best[upd] = dj[upd]
            bp[upd] = pts[np.arange(len(q)), j][upd]
        Vb = np.zeros((on_b.sum(), 3))
        Vb[:, 1:] = bp
        Vn[on_b] = Vb
        V = Vn
    return V


def mirror_weld(V, F):
    """Mirror a half mesh (border on x=0) and weld the border vertices."""
    n = len(V)
    on0 = np.zeros(n, bool)
    on0[boundary_edges(F).ravel()] = True
    assert np.all(V[on0, 0] == 0.0) and np.all(V[~on0, 0] > 0.0)
    idx = np.arange(n)
    mir_idx = np.where(on0, idx, n + np.cumsum(~on0) - 1)
    Vm = V[~on0].copy()
    Vm[:, 0] = -Vm[:, 0]
    Vall = np.concatenate([V, Vm])
    Fm = mir_idx[F][:, ::-1]
    Fall = np.concatenate([F, Fm])
    return Vall, Fall


def build(step=GRID_STEP, target=TARGET_TRIANGLES, verbose=True, relax_rounds=3):
    import igl
    Vd, Fd = marching_half(step)
    Vd, Fd = keep_largest_component(Vd, Fd)
    if verbose:
        print(f"marching cubes (half): {len(Vd)} verts, {len(Fd)} tris", file=sys.stderr)
    # quadric edge-collapse decimation (libigl; link condition keeps it manifold)
    out = igl.qslim(np.asfortranarray(Vd), np.asfortranarray(Fd.astype(np.int32)),
                    target // 2, False)
    Vs, Fs = _clean(np.asarray(out[0], float), np.asarray(out[1], np.int64))
    be = boundary_edges(Fs)
    on_b = np.zeros(len(Vs), bool)
    on_b[be.ravel()] = True
    Vs[on_b, 0] = 0.0
    if not (is_manifold(Fs) and np.all(Vs[~on_b, 0] > 1e-6)):
        raise RuntimeError("decimated half mesh is not a clean half")
    for _ in range(relax_rounds):
        Fs = delaunay_flips(Vs, Fs, on_b)
        Vs = relax(Vs, Fs, Vd, Fd, iters=2, lam=0.4)
    Fs = delaunay_flips(Vs, Fs, on_b)
    # flat neck cap: snap vertices lying on the cut plane exactly onto it
    cap = np.abs(Vs[:, 1] - NECK_CUT_Y) < 2e-4
    Vs[cap, 1] = NECK_CUT_Y
    Vs[on_b, 0] = 0.0
    V, F = mirror_weld(Vs, Fs)
    V = np.round(V, 9) + 0.0        # no negative zeros
    return V, F


def write_obj(path, V, F):
    lines = ["# generated by build_default_head.py (autobones default head; metres, "
             "+Y up, +Z forward, +X subject's left)\n"]
    lines += ["v %.7f %.7f %.7f\n" % tuple(v) for v in V]
    lines += ["f %d %d %d\n" % tuple(f) for f in (F + 1)]
    with open(path, "w", newline="\n") as fh:
        fh.write("".join(lines))


def read_obj(path):
    V, F = [], []
    with open(path) as fh:
        for line in fh:
            if line.startswith("v "):
                V.append([float(t) for t in line.split()[1:4]])
            elif line.startswith("f "):
                F.append([int(t) - 1 for t in line.split()[1:4]])
    return np.array(V), np.array(F, np.int64)


# ---------------------------------------------------------------------------
# rendering (for the gallery picture) and checks
# ---------------------------------------------------------------------------

def render(V, F, path, size=520, span=0.36, center=(0.0, 0.075), angles=(0.0, 35.0, 90.0)):
    """Three orthographic views (front, 3/4, side), smooth-shaded z-buffer."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def vnormals(V, F):
        fn = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
        cap = fn[:, 1] < -0.95 * np.linalg.norm(fn, axis=1)   # keep the cap rim sharp
        fn = fn * ~cap[:, None]
        vn = np.zeros_like(V)
        for k in range(3):
            np.add.at(vn, F[:, k], fn)
        return vn / np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-30)

    vn = vnormals(V, F)
    imgs = []
    for ang in angles:
        R = rot_y(ang)                       # rotate the head, camera on +z
        P = V @ R.T
        N = vn @ R.T
        c = np.array([center[0], center[1], 0.0])
        s = size / span
        px = (P[:, 0] - c[0]) * s + size / 2
        py = size / 2 - (P[:, 1] - c[1]) * s
        zb = np.full((size, size), -np.inf)
        img = np.ones((size, size))
        L = np.array([-0.35, 0.45, 0.82])
        L /= np.linalg.norm(L)
        shade = np.clip(N @ L, 0, 1) * 0.8 + 0.2
        for f in F:
            xs_, ys_ = px[f], py[f]
            x0, x1 = int(np.floor(xs_.min())), int(np.ceil(xs_.max()))
            y0, y1 = int(np.floor(ys_.min())), int(np.ceil(ys_.max()))
            x0, y0 = max(x0, 0), max(y0, 0)
            x1, y1 = min(x1, size - 1), min(y1, size - 1)
            if x1 < x0 or y1 < y0:
                continue
            gx, gy = np.meshgrid(np.arange(x0, x1 + 1) + 0.5, np.arange(y0, y1 + 1) + 0.5)
            (ax, bx, cx), (ay, by, cy) = xs_, ys_
            den = (by - cy) * (ax - cx) + (cx - bx) * (ay - cy)
            if abs(den) < 1e-12:
                continue
            l0 = ((by - cy) * (gx - cx) + (cx - bx) * (gy - cy)) / den
            l1 = ((cy - ay) * (gx - cx) + (ax - cx) * (gy - cy)) / den
            l2 = 1 - l0 - l1
            m = (l0 >= -1e-6) & (l1 >= -1e-6) & (l2 >= -1e-6)
            if not m.any():
                continue
            zz = l0 * P[f[0], 2] + l1 * P[f[1], 2] + l2 * P[f[2], 2]
            sh = l0 * shade[f[0]] + l1 * shade[f[1]] + l2 * shade[f[2]]
            iy, ix = gy[m].astype(int), gx[m].astype(int)
            upd = zz[m] > zb[iy, ix]
            zb[iy[upd], ix[upd]] = zz[m][upd]
            img[iy[upd], ix[upd]] = sh[m][upd]
        imgs.append(img)
    fig, axs = plt.subplots(1, len(imgs), figsize=(len(imgs) * size / 100, size / 100), dpi=100)
    for a, im, t in zip(np.atleast_1d(axs), imgs, angles):
        a.imshow(im, cmap="gray", vmin=0, vmax=1)
        a.set_title({0.0: "front", 90.0: "side"}.get(t, f"{t:g} deg"))
        a.axis("off")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def check(V, F):
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    und = np.sort(e, axis=1)
    _, cnt = np.unique(und, axis=0, return_counts=True)
    _, dcnt = np.unique(e, axis=0, return_counts=True)
    n = len(V)
    A = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    ncomp, _ = connected_components(A, directed=False)
    ang = tri_angles(V, F).min(1)
    # symmetry
    from scipy.spatial import cKDTree
    Vm = V * np.array([-1, 1, 1])
    dist, _ = cKDTree(V).query(Vm)
    # volume (outward orientation -> positive)
    v0, v1, v2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    vol = np.einsum("ij,ij->i", v0, np.cross(v1, v2)).sum() / 6
    chi = len(V) - len(cnt) + len(F)
    stats = dict(
        vertices=len(V), triangles=len(F),
        every_edge_two_faces=bool((cnt == 2).all()),
        consistent_orientation=bool((dcnt == 1).all()),
        components=int(ncomp), euler=int(chi), volume_m3=float(vol),
        symmetry_max_err=float(dist.max()),
        min_angle=float(ang.min()), min_angle_p1=float(np.percentile(ang, 1)),
        min_angle_p5=float(np.percentile(ang, 5)),
        min_angle_median=float(np.median(ang)),
        frac_min_angle_lt_20=float((ang < 20).mean()),
        bbox_min=V.min(0).round(4).tolist(), bbox_max=V.max(0).round(4).tolist(),
    )
    return stats


def self_intersections(V, F):
    """Count pairs of non-adjacent triangles whose edges cross the other."""
    from scipy.spatial import cKDTree
    c = V[F].mean(1)
    rad = np.linalg.norm(V[F] - c[:, None], axis=2).max(1)
    tree = cKDTree(c)
    pairs = tree.query_pairs(2 * rad.max(), output_type="ndarray")
    i, j = pairs[:, 0], pairs[:, 1]
    close = np.linalg.norm(c[i] - c[j], axis=1) <= rad[i] + rad[j]
    i, j = i[close], j[close]
    share = (F[i][:, :, None] == F[j][:, None, :]).any((1, 2))
    i, j = i[~share], j[~share]
    hits = np.zeros(len(i), bool)
    for (a, b) in ((i, j), (j, i)):
        T = V[F[b]]
        for k in range(3):
            p0 = V[F[a][:, k]]
            p1 = V[F[a][:, (k + 1) % 3]]
            hits |= _seg_tri(p0, p1, T)
    return int(hits.sum())


def _seg_tri(p0, p1, T):
    e1 = T[:, 1] - T[:, 0]
    e2 = T[:, 2] - T[:, 0]
    d = p1 - p0
    h = np.cross(d, e2)
    a = np.einsum("ij,ij->i", e1, h)
    ok = np.abs(a) > 1e-18
    f = np.where(ok, 1.0 / np.where(ok, a, 1), 0)
    s = p0 - T[:, 0]
    u = f * np.einsum("ij,ij->i", s, h)
    q = np.cross(s, e1)
    v = f * np.einsum("ij,ij->i", d, q)
    t = f * np.einsum("ij,ij->i", e2, q)
    return ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0) & (t <= 1)


def _ray_hit(o, d, tmax=0.25, n=2500):
    """First point where the ray o + t d (t in [0, tmax]) enters the head."""
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


def _ear_to_world(u, v, w):
    E = np.array([0.0705, 0.1030, -0.0170])
    th, ph = np.radians(22.0), np.radians(16.0)
    n = np.array([np.cos(th), 0.0, np.sin(th)])
    fwd = np.array([-np.sin(th), 0.0, np.cos(th)])
    upv = np.array([0.0, 1.0, 0.0])
    up = np.cos(ph) * upv - np.sin(ph) * fwd
    fw = np.sin(ph) * upv + np.cos(ph) * fwd
    return E + u * up + v * fw + w * n


def measure_anatomy(V=None, F=None):
    """Locate key anatomical points on the implicit surface (and, if a mesh
    is given, snap them to the closest point of the mesh)."""
    A = {}
    ys = np.arange(-0.003, 0.1605, 0.00025)
    front = np.array([_ray_hit((0.0, y, 0.15), (0, 0, -1))[2] for y in ys])

    def prof_pt(lo, hi, mode):
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
    # menton: lowest point of the chin in the mid-sagittal plane
    hits = [_ray_hit((0.0, -0.04, z), (0, 1, 0)) for z in np.arange(0.060, 0.0801, 0.0005)]
    A["menton"] = min(hits, key=lambda p: (p[1], -p[2]))
    hits = [_ray_hit((0.0, 0.30, z), (0, -1, 0)) for z in np.arange(-0.04, 0.0401, 0.0005)]
    A["vertex"] = max(hits, key=lambda p: p[1])
    hits = [_ray_hit((0.0, y, -0.15), (0, 0, 1)) for y in np.arange(0.10, 0.2001, 0.0005)]
    A["opisthocranion"] = min(hits, key=lambda p: p[2])
    # eyes (closed): ends of the lid fissure
    A["exocanthion_l"] = _ray_hit((_FISSURE[-1, 0], _FISSURE[-1, 1], 0.15), (0, 0, -1))
    A["endocanthion_l"] = _ray_hit((_FISSURE[0, 0], _FISSURE[0, 1], 0.15), (0, 0, -1))
    A["eye_centre_l"] = EYE_C.copy()
    # mouth corner: lateral end of the mouth-line groove
    best = None
    for xx in np.arange(0.015, 0.0320, 0.00025):
        zc = _ray_hit((xx, 0.0480, 0.15), (0, 0, -1))
        za = _ray_hit((xx, 0.0440, 0.15), (0, 0, -1))
        zb = _ray_hit((xx, 0.0520, 0.15), (0, 0, -1))
        if 0.5 * (za[2] + zb[2]) - zc[2] > 0.0003:
            best = zc
    A["cheilion_l"] = best
    # nose wing: most lateral point of the ala
    hits = [_ray_hit((0.06, y, z), (-1, 0, 0)) for y in np.arange(0.072, 0.0861, 0.0005)
            for z in np.arange(0.084, 0.0961, 0.0005)]
    hits = [h for h in hits if h is not None and h[0] < 0.03]
    A["alare_l"] = max(hits, key=lambda p: p[0])
    # cheekbone: most lateral point of the zygomatic arch (in front of the ear)
    hits = [_ray_hit((0.12, 0.100, z), (-1, 0, 0)) for z in np.arange(0.015, 0.0451, 0.0005)]
    A["zygion_l"] = max(hits, key=lambda p: p[0])
    # jaw angle
    c = np.array([0.0405, 0.0330, -0.0030])
    dirn = np.array([1.0, -0.9, -0.5])
    dirn /= np.linalg.norm(dirn)
    A["gonion_l"] = _ray_hit(c + 0.08 * dirn, -dirn)
    # ear: tragion (notch above the tragus), top and bottom of the ear
    tp = _ear_to_world(-0.0010, 0.0140, 0.0030)
    A["tragion_l"] = _ray_hit((0.12, tp[1], tp[2]), (-1, 0, 0))
    top = _ear_to_world(0.0310, -0.0010, 0.0030)
    A["superaurale_l"] = _ray_hit((top[0], 0.25, top[2]), (0, -1, 0))
    bot = _ear_to_world(-0.0310, 0.0010, 0.0010)
    A["subaurale_l"] = _ray_hit((bot[0], 0.0, bot[2]), (0, 1, 0))
    if V is not None:
        import igl
        # midline points: closest point on the mesh's x = 0 seam polyline
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
    for k in A:
        if not k.endswith("_l"):
            A[k] = np.array([0.0, A[k][1], A[k][2]])
    return {k: tuple(round(float(t), 4) + 0.0 for t in A[k]) for k in A}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=OUT_OBJ)
    ap.add_argument("--render", default=None, help="also write a 3-view PNG")
    ap.add_argument("--check", action="store_true", help="print mesh statistics")
    ap.add_argument("--step", type=float, default=GRID_STEP)
    ap.add_argument("--target", type=int, default=TARGET_TRIANGLES)
    ap.add_argument("--measure", action="store_true",
                    help="print the ANATOMY table measured on the built mesh")
    a = ap.parse_args(argv)
    V, F = build(a.step, a.target)
    write_obj(a.out, V, F)
    print(f"wrote {a.out}: {len(V)} vertices, {len(F)} triangles", file=sys.stderr)
    if a.check:
        for k, v in check(V, F).items():
            print(f"{k}: {v}")
        print("self_intersections:", self_intersections(V, F))
    if a.render:
        render(V, F, a.render)
    if a.measure:
        print("ANATOMY_LEFT_AND_MIDLINE = {")
        for k, v in measure_anatomy(V, F).items():
            print(f'    "{k}": ({v[0]:.4f}, {v[1]:.4f}, {v[2]:.4f}),')
        print("}")


if __name__ == "__main__":
    main()
