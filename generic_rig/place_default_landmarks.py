"""Place the 44 contract landmarks on the built-in default head.

Orvalho, Zacur & Susin 2008 (§2): the generic rig is tagged with 44 anthropometric landmarks (lambda)
placed on its surface. The default head is procedural, so instead of an artist
clicking them we derive them from the committed ``default_head.obj`` with
geometric rules, seeded by ``build_default_head.ANATOMY`` (the builder's table
of key points) where it has an entry:

Midline (all exactly at x = 0, on the mid-sagittal profile: the polyline of
mesh edges that lie in the plane x = 0, which the symmetric build guarantees):
  vertex          highest profile point
  opisthocranion  most posterior profile point above the ear (tragion) height
  pronasale       most anterior profile point
  nasion          deepest (min z) profile point 1-6 cm above pronasale
  glabella        most anterior profile point 0-3.5 cm above nasion
  subnasale       deepest profile point between pronasale and labiale superius
  labiale_sup.    most anterior point within +-8 mm of ANATOMY's labrale superius
  stomion         deepest point between the two lip maxima (the closed mouth line)
  labiale_inf.    most anterior point 1-15 mm below stomion
  sublabiale      deepest point between labiale inferius and pogonion
  pogonion        most anterior profile point 1-4.5 cm below labiale inferius
  menton          lowest profile point within 2.5 cm behind pogonion
Bilateral (placed on the subject's left, x > 0, snapped to the closest surface
point, and mirrored x -> -x for the right; the mesh is exactly symmetric):
  exo/endocanthion, alare, cheilion, zygion, gonion, tragion, superaurale,
  subaurale  ANATOMY seeds (measured on the built surface by the builder) snapped
  palpebrale_sup/inf  the eyes are closed: +-1.5 mm above/below the lid
              fissure midway between the corners, projected from the front
  brow_inner/middle/outer  on the brow ridge, projected from the front: above
              the inner corner, above the eye middle (highest), beyond the outer corner
  crista_philtri  Cupid's bow peak, 1/4 of the way to the mouth corner, 1 mm
              above labiale superius, projected from the front
  frontotemporale 0.83 * zygion width (ft-ft/zy-zy ~ 115/136), 2.5 cm above the
              glabella, projected from the front

Run ``python generic_rig/place_default_landmarks.py`` to write
``default_head.landmarks.json`` and ``gallery/generic_rig_landmarks.png``.
Frame: the default head's own (metres, +Y up, +Z front, +X subject's left).
"""
from __future__ import annotations

import argparse
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

from autobones.io.landmarks import NAMES, MIDLINE, validate_landmarks, write_landmarks  # noqa: E402
from autobones.io.mesh import load_mesh  # noqa: E402
from autobones.generic_rig.build_default_head import ANATOMY  # noqa: E402

MESH = os.path.join(HERE, "default_head.obj")
OUT = os.path.join(HERE, "default_head.landmarks.json")
PICTURE = os.path.join(ROOT, "gallery", "generic_rig_landmarks.png")


def _a(name):
    alias = {"labiale_superius": "labrale_superius", "labiale_inferius": "labrale_inferius"}
    return np.array(ANATOMY.get(name, ANATOMY.get(alias.get(name, name))), dtype=float)


def midline_profile(V, F, tol=1e-9):
    """Points of the mesh's x = 0 cross-section: (k, 3) sorted by nothing in particular,
    densified along the cut edges (every edge between two x = 0 vertices, plus edge crossings)."""
    E = np.vstack([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    E = np.unique(np.sort(E, axis=1), axis=0)
    x0, x1 = V[E[:, 0], 0], V[E[:, 1], 0]
    pts = [V[np.abs(V[:, 0]) <= tol]]
    on = (np.abs(x0) <= tol) & (np.abs(x1) <= tol)
    for t in np.linspace(0.1, 0.9, 9):  # densify edges lying in the plane
        pts.append(V[E[on, 0]] * (1 - t) + V[E[on, 1]] * t)
    cross = (x0 * x1 < 0)
    t = x0[cross] / (x0[cross] - x1[cross])
    pts.append(V[E[cross, 0]] + t[:, None] * (V[E[cross, 1]] - V[E[cross, 0]]))
    P = np.vstack(pts)
    P[:, 0] = 0.0
    return P


def front_hit(V, F, x, y, z_max=None):
    """The frontmost surface point on the line (x, y, *) (a ray cast along -Z); None if missed.
    ``z_max`` ignores hits in front of it (e.g. the nose when aiming at the cheek)."""
    A, B, C = V[F[:, 0], :2], V[F[:, 1], :2], V[F[:, 2], :2]
    p = np.array([x, y])
    v0, v1, v2 = B - A, C - A, p - A
    den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
    ok = np.abs(den) > 1e-18
    den = np.where(ok, den, 1.0)
    b1 = (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / den
    b2 = (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / den
    b0 = 1 - b1 - b2
    inside = ok & (b0 >= -1e-12) & (b1 >= -1e-12) & (b2 >= -1e-12)
    z = b0 * V[F[:, 0], 2] + b1 * V[F[:, 1], 2] + b2 * V[F[:, 2], 2]
    if z_max is not None:
        inside &= z <= z_max
    if not inside.any():
        return None
    return np.array([x, y, z[inside].max()])


def snap(V, F, P):
    import igl

    P = np.atleast_2d(np.asarray(P, dtype=float))
    _, _, C = igl.point_mesh_squared_distance(P, V, F.astype(np.int64))
    return C


def place(V, F):
    """All 44 landmarks (dict name -> (3,)) on the default head (metres, its own frame)."""
    prof = midline_profile(V, F)
    y, z = prof[:, 1], prof[:, 2]

    def pick(mask, key):
        idx = np.flatnonzero(mask)
        if len(idx) == 0:
            raise RuntimeError("empty profile window")
        return prof[idx[np.argmax(key[idx])]].copy()

    lm = {}
    lm["vertex"] = pick(np.ones(len(prof), bool), y)
    front = z > 0.0
    lm["pronasale"] = pick(front & (y > _a("stomion")[1]) & (y < _a("nasion")[1]), z)
    prn = lm["pronasale"]
    lm["nasion"] = pick(front & (y > prn[1] + 0.01) & (y < prn[1] + 0.06), -z)
    lm["glabella"] = pick(front & (y > lm["nasion"][1]) & (y < lm["nasion"][1] + 0.035), z)
    ls0 = _a("labiale_superius")
    lm["labiale_superius"] = pick(front & (np.abs(y - ls0[1]) < 0.008), z)
    ls = lm["labiale_superius"]
    lm["subnasale"] = pick(front & (y > ls[1]) & (y < prn[1]) & (z > ls[2] - 0.02), -z)
    li0 = pick(front & (y < ls[1] - 0.002) & (y > ls[1] - 0.02), z)
    lm["stomion"] = pick(front & (y < ls[1]) & (y > li0[1]) & (z > li0[2] - 0.015), -z)
    sto = lm["stomion"]
    lm["labiale_inferius"] = pick(front & (y < sto[1] - 0.001) & (y > sto[1] - 0.015), z)
    li = lm["labiale_inferius"]
    pog = pick(front & (y < li[1] - 0.01) & (y > li[1] - 0.045), z)
    lm["pogonion"] = pog
    lm["sublabiale"] = pick(front & (y < li[1]) & (y > pog[1]) & (z > pog[2] - 0.02), -z)
    lm["menton"] = pick((z < pog[2]) & (z > pog[2] - 0.025) & (y < pog[1]), -y)
    tr0 = _a("tragion_l")
    lm["opisthocranion"] = pick((z < 0) & (y > tr0[1]), -z)

    L = {}
    for name in ("exocanthion", "endocanthion", "alare", "cheilion", "gonion", "tragion", "zygion",
                 "superaurale", "subaurale"):
        L[name] = snap(V, F, _a(name + "_l"))[0]
    ex, en = L["exocanthion"], L["endocanthion"]
    mid = 0.5 * (ex + en)
    # closed eyes: lid fissure = deepest point on the vertical line through the eye middle
    ys = np.linspace(mid[1] - 0.006, mid[1] + 0.006, 61)
    hits = [front_hit(V, F, mid[0], yy) for yy in ys]
    hits = np.array([h for h in hits if h is not None])
    fis = hits[np.argmin(hits[:, 2])]
    L["palpebrale_superius"] = front_hit(V, F, mid[0], fis[1] + 0.0015)
    L["palpebrale_inferius"] = front_hit(V, F, mid[0], fis[1] - 0.0015)
    gl = lm["glabella"]
    brow_y = gl[1]
    L["brow_inner"] = front_hit(V, F, en[0] + 0.002, brow_y)
    # brow middle: the highest point of the ridge above the eye middle = where the brow profile
    # is most anterior relative to the forehead above it; take the frontmost point 1.2-2.5 cm
    # above the fissure
    ys = np.linspace(fis[1] + 0.012, fis[1] + 0.025, 40)
    hits = np.array([h for h in (front_hit(V, F, mid[0], yy) for yy in ys) if h is not None])
    L["brow_middle"] = hits[np.argmax(hits[:, 2])]
    L["brow_outer"] = front_hit(V, F, ex[0] + 0.004, ex[1] + 0.012)
    if L["brow_outer"] is None:
        L["brow_outer"] = snap(V, F, ex + [0.004, 0.012, 0.0])[0]
    ch = L["cheilion"]
    L["crista_philtri"] = front_hit(V, F, 0.25 * ch[0], ls[1] + 0.001)
    L["frontotemporale"] = front_hit(V, F, 0.83 * L["zygion"][0], gl[1] + 0.025)
    for k, p in L.items():
        q = snap(V, F, p)[0]
        lm[k + "_l"] = q
        lm[k + "_r"] = q * np.array([-1.0, 1.0, 1.0])
    for k in MIDLINE:
        lm[k] = np.asarray(lm[k], dtype=float)
        lm[k][0] = 0.0
    return {k: np.asarray(lm[k], dtype=float) for k in NAMES}


def render_preview(V, F, lm, path):
    from autobones.render import render_views, save_png

    names = list(lm)
    P = np.array([lm[k] for k in names])
    short = [k.replace("palpebrale_", "p").replace("superius", "sup").replace("inferius", "inf")
             .replace("labiale_", "l").replace("_l", "L").replace("_r", "R") for k in names]
    front = render_views(V, F, views=("front",), size=(900, 900), points=P, point_labels=short)
    # from the subject's left only the midline and left points are labelled (the right ones
    # project onto them)
    keep = [i for i, k in enumerate(names) if not k.endswith("_r")]
    side = render_views(V, F, views=("side",), size=(900, 900), points=P[keep],
                        point_labels=[short[i] for i in keep])
    img = np.concatenate([front, side], axis=1)
    save_png(path, img)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mesh", default=MESH)
    ap.add_argument("--out", default=OUT)
    ap.add_argument("--picture", default=PICTURE)
    args = ap.parse_args(argv)
    V, F = load_mesh(args.mesh)
    lm = place(V, F)
    validate_landmarks(lm, V, F, min_count=44, source=args.out, max_off_surface=0.001)
    write_landmarks(args.out, lm, mesh_name=os.path.basename(args.mesh))
    if args.picture:
        render_preview(V, F, lm, args.picture)
    return 0


if __name__ == "__main__":
    sys.exit(main())
