"""Tragions for shared heads that have ears but no tragion landmark: side views to pick from, then the picks.

    python tools/place_tragions.py --render james /tmp/ears     # side views of the ear with a grid
    python tools/place_tragions.py                               # writes tests/landmarks/*.tragions.json

The procedure (``tests/landmarks/README.md``, "Tragions"): each head is put in its landmarks' own frame
(``benchmarks/zoo_checks.landmark_frame``: front opisthocranion or the head's centroid -> pronasale, up
menton -> vertex or nasion, left = up x front) with its origin at the exocanthions' midpoint and ex-ex as
the unit. The left ear is rendered from the left, the grid in those units; the tragion (the notch above
the tragus, at the front of the ear where its upper edge leaves the cheek) is read off the picture as
(front, up) and stored in :data:`PICKS`. A ray from far on the left along -left through that (front, up)
hits the skin: the first hit is ``tragion_l``. ``tragion_r`` is the same (front, up) reflected through
the landmarks' midplane (``zoo_checks.mirror_plane``) and cast from the right, so the pair is symmetric in
the frame unless the skin is not. ICT's identities share one topology: the pick is made on the generic
neutral mesh, the nearest vertex of each hit is kept, and those vertex ids give every identity's tragions.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
import zoo_checks as zc  # noqa: E402

from autobones import render  # noqa: E402
from autobones.io.landmarks import read_landmarks, write_landmarks  # noqa: E402
from autobones.io.mesh import load_mesh  # noqa: E402

DATA = ROOT.parent / "shared" / "data"
OUT = ROOT / "tests" / "landmarks"
HEADS = {  # name -> (mesh, landmarks), relative to ../shared/data
    "james": ("menpo3d/james.obj", "menpo3d/james.landmarks.json"),
    "template": ("menpo3d/template.ply", "menpo3d/template.landmarks.json"),
    "generic_neutral_mesh": ("ict/generic_neutral_mesh.obj", "ict/generic_neutral_mesh.landmarks.json"),
    # no shared landmarks: autobones.detect_landmarks' 27 (MediaPipe), kept in tests/landmarks
    "LeePerrySmith": ("misc/LeePerrySmith.obj", "tests/LeePerrySmith.landmarks.json"),
}
ICT_IDENTITIES = ("identity000", "identity001", "identity002")
# (front, up) of the left tragion in ex-ex from the exocanthions' midpoint, read off the side views
PICKS = {
    # the tragus' upper edge at the front of the concha, below the crus of the helix (sharp ear)
    "generic_neutral_mesh": (-0.85, -0.23),
    # the same; the ear is smooth, the notch read from the concha's front edge
    "template": (-0.92, -0.06),
    # a noisy scan: the ear is a ridge (helix, top, at up -0.16) over a crease (lobe, up -0.60) with no
    # tragus resolved; its front edge at front -0.6, the pick 40% down the ear (about +-0.05 ex-ex)
    "james": (-0.61, -0.34),
    # a sharp ear: the tragus' top at the front of the concha's slit
    "LeePerrySmith": (-0.89, -0.10),
}


def head_frame(V, F, lm):
    """(origin, (3, 3) rows left/up/front, ex-ex) of the landmarks' frame."""
    ref = zc.landmark_frame(V, F, lm)
    origin = 0.5 * (lm["exocanthion_l"] + lm["exocanthion_r"])
    return origin, np.stack([ref["left"], ref["up"], ref["front"]]), zc.unit(lm, V), ref


def load(name):
    mesh, marks = HEADS[name]
    V, F = load_mesh(DATA / mesh)
    path = OUT / marks[len("tests/"):] if marks.startswith("tests/") else DATA / marks
    lm = {n: np.asarray(p, dtype=np.float64) for n, p in read_landmarks(path).items()}
    return V, F, lm


def render_ear(name, out, size=900, box=(-1.8, -0.3, -1.2, 0.6)):
    """Side view of the left ear: the head in frame units, a grid every 0.1 ex-ex (0.5 thicker),
    ``box`` = (front min, front max, up min, up max)."""
    V, F, lm = load(name)
    o, R, u, _ = head_frame(V, F, lm)
    C = (V - o) @ R.T / u                      # x left, y up, z front, ex-ex units
    f0, f1, u0, u1 = box
    pick = (C[:, 2] > f0 - 0.5) & (C[:, 2] < f1 + 0.5) & (C[:, 1] > u0 - 0.5) & (C[:, 1] < u1 + 0.5)
    keep = np.all(pick[F], axis=1) & np.all(C[F][:, :, 0] > 0, axis=1)   # the left half only
    used, Fk = np.unique(F[keep], return_inverse=True)
    x = C[used, 0].max()
    Vk = np.vstack([C[used], [[x, u0, f0], [x, u1, f1]]])   # two corners frame the box
    Fk = Fk.reshape(-1, 3)
    img = render.render_views(Vk, Fk, views=("side",), size=(size, size))
    cam = render.orthographic_camera(Vk, (1.0, 0.0, 0.0), size=(size, size))
    segs = []
    for k in np.arange(np.ceil(f0 * 10), np.floor(f1 * 10) + 1) / 10:
        segs.append(([x, u0, k], [x, u1, k]))
    for k in np.arange(np.ceil(u0 * 10), np.floor(u1 * 10) + 1) / 10:
        segs.append(([x, k, f0], [x, k, f1]))
    segs = np.array(segs)
    a, _ = cam.project(segs[:, 0])
    b, _ = cam.project(segs[:, 1])
    img = render.draw_segments(img, a, b, color=(120, 120, 255), width=1)
    labels = [f"{p[2]:.1f}" if p[1] == u0 else f"{p[1]:.1f}" for p in segs[:, 0]]
    px, _ = cam.project(segs[:, 0])
    img = render.draw_points(img, px, labels=labels, color=(0, 0, 200), radius=1)
    if name in PICKS:
        f, h = PICKS[name]
        px, _ = cam.project(np.array([[x, h, f]]))
        img = render.draw_points(img, px, labels=["pick"], color=(255, 0, 0), radius=5, filled=False)
    path = Path(out) / f"{name}_ear.png"
    render.save_png(path, img)
    print(path)


def first_hit(V, F, origin, direction):
    """The nearest intersection (3,) of the ray origin + t direction (t > 0) with the triangles, or None
    (Moeller-Trumbore over every triangle at once)."""
    A, B, Cc = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    e1, e2 = B - A, Cc - A
    p = np.cross(direction, e2)
    det = np.einsum("ij,ij->i", e1, p)
    ok = np.abs(det) > 1e-15
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = origin - A
    a = np.einsum("ij,ij->i", s, p) * inv
    q = np.cross(s, e1)
    b = (q @ direction) * inv
    t = np.einsum("ij,ij->i", e2, q) * inv
    hit = ok & (a >= 0) & (b >= 0) & (a + b <= 1) & (t > 0)
    if not hit.any():
        return None
    return origin + t[hit].min() * direction


def tragions(V, F, lm, pick):
    """tragion_l / _r: rays along -left (and +left, mirrored through the midplane) at the picked (front, up)."""
    o, R, u, ref = head_frame(V, F, lm)
    f, h = pick
    far = 10.0 * float(np.ptp(V, axis=0).max())
    start = o + u * (f * R[2] + h * R[1])
    left = first_hit(V, F, start + far * R[0], -R[0])
    p, n = zc.mirror_plane(lm, ref)
    mirrored = start - 2.0 * float((start - p) @ n) * n
    right = first_hit(V, F, mirrored - far * n, n)
    return {"tragion_l": left, "tragion_r": right}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--render", nargs=2, metavar=("HEAD", "DIR"))
    args = ap.parse_args(argv)
    if args.render:
        render_ear(*args.render)
        return
    for name, pick in PICKS.items():
        V, F, lm = load(name)
        tr = tragions(V, F, lm, pick)
        if name == "generic_neutral_mesh":
            ids = {k: int(np.argmin(np.linalg.norm(V - p, axis=1))) for k, p in tr.items()}
            print(f"ICT tragion vertices {ids}")
            for ident in ICT_IDENTITIES + ("generic_neutral_mesh",):
                Vi, _ = load_mesh(DATA / "ict" / f"{ident}.obj")
                write_landmarks(OUT / f"{ident}.tragions.json", {k: Vi[i] for k, i in ids.items()})
            continue
        write_landmarks(OUT / f"{name}.tragions.json", tr)
        print(name, {k: np.round(p, 4).tolist() for k, p in tr.items()})


if __name__ == "__main__":
    main()
