"""Does a head turn take the whole lower face with it? The head's share at the jaw's landmarks (#31, #32).

    python benchmarks/head_turn.py                       # every landmarked shared head, 4 copies each
    python benchmarks/head_turn.py --heads human_woman,cowHead --variants as-is,dec5k --markdown

A rigger turning a rig's head expects the mandible to turn with the skull whole and the neck to bend
below it. This reads, on ``place`` ("P") and ``transfer`` ("T") rigs, the share of the head bone and its
children (the jaw, the eyes, the facial bones) at the vertex nearest each of the jaw's landmarks:

- ``chin``: the lowest of the menton, the pogonion and the labiale inferius (the chin and lower lip);
- ``angle``: the lower of the two gonions (the mandible's angle). Where the head's file has no gonions,
  ``T`` reads them where the generic rig's gonions landed (its dense correspondence); ``P`` has none.

Below 1 the landmark is left partly behind on a head turn; the jaw then folds along its border (``angle``)
or the lower face shears (``chin``). Heads and copies are ``zoo.py``'s (``--variants``: as-is, a random
rotation, x1000, decimated to 5k). The zoo's check 3 holds the other end: the neck base stays still.
The summary counts the copies whose share is at least ``GOOD`` (0.75) and prints the lowest.
``strained``: on the first copy, the share of the edges stretched or crushed by more than 20 % when the
head turns 30 degrees (a fold along the jaw, a seam under it: a band of such edges; the rest of a turn's
strain is the neck's own twist, spread over it).
"""
from __future__ import annotations

import argparse
import logging
import sys
import time
import zlib
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parent))
import zoo_checks as zc  # noqa: E402
from zoo import DATA, heads_in  # noqa: E402

import autobones  # noqa: E402
from autobones.io.landmarks import read_landmarks  # noqa: E402
from autobones.io.mesh import load_mesh  # noqa: E402
from autobones.rig_transfer.neck import anatomical_axes  # noqa: E402
from autobones.rig_transfer.pipeline import load_generic  # noqa: E402
from autobones.rig_transfer.under_skin import ride  # noqa: E402

VARIANTS = ("as-is", "rot1", "x1000", "dec5k")
CHIN = ("menton", "pogonion", "labiale_inferius")
ANGLE = ("gonion_l", "gonion_r")
GOOD = 0.75
STRAIN, STRAIN_TURN = 0.2, 30.0   # an edge stretched or crushed by more than 20 % on a 30 degree turn


def head_side(rig):
    """(n,) the share of the head bone and its descendants in each vertex's weights."""
    return rig.weights[:, zc.family(rig.skeleton, "head")].sum(axis=1)


def shares(rig, lm, angle):
    """(chin, angle): the least head share at the vertex nearest each of the chin's landmarks ``lm`` has,
    and at the ``angle`` points ((k, 3) or None); None where there are none."""
    s, tree = head_side(rig), cKDTree(rig.vertices)
    chin = [lm[n] for n in CHIN if n in lm]
    read = lambda P: None if P is None or not len(P) else float(s[tree.query(np.asarray(P))[1]].min())  # noqa: E731
    return read(chin), read(angle)


def strained(rig, degrees=STRAIN_TURN):
    """Share of the edges whose length changes by more than ``STRAIN`` on a ``degrees`` turn of the head
    bone (and its children) about the up of the rig's landmarks' anatomical frame (its own without
    landmarks) through the head joint, linear blend skinning (``Rig.turn_bones``): a fold or a seam is a
    band of such edges."""
    axes = anatomical_axes(rig.vertices, rig.faces, rig.landmarks, rig.frame.rotation) if rig.landmarks else None
    V, X = np.asarray(rig.vertices, dtype=np.float64), rig.turn_bones(head_deg=(0.0, degrees, 0.0), axes=axes)
    F = rig.faces
    E = np.unique(np.sort(np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1), axis=0)
    before = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    after = np.linalg.norm(X[E[:, 0]] - X[E[:, 1]], axis=1)
    ok = before > 1e-9 * float(np.ptp(V))
    return float(np.mean(np.abs(after[ok] / before[ok] - 1.0) > STRAIN))


def carried_angle(generic, details):
    """(2, 3) the generic rig's gonions where its correspondence (``details``) put them on the head."""
    return ride(np.array([generic.landmarks[n] for n in ANGLE]), generic.vertices, generic.faces,
                details["correspondence"])


def run_copy(var, generic):
    """{"P": (chin, angle, angle source), "T": ...} for one copy of a head."""
    given = np.array([var.lm[n] for n in ANGLE if n in var.lm]) if var.lm else None
    given = given if given is not None and len(given) else None
    out = {}
    rig = autobones.place((var.V, var.F), density="medium")
    out["P"] = (*shares(rig, var.lm, given), "file" if given is not None else "-", strained(rig))
    details = {}
    rig = autobones.transfer((var.V, var.F), var.lm, details=details)
    angle = given if given is not None else carried_angle(generic, details)
    out["T"] = (*shares(rig, var.lm, angle), "file" if given is not None else "fit", strained(rig))
    return out


def fmt(v):
    return "-" if v is None else f"{v:.2f}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DATA)
    ap.add_argument("--heads", help="comma-separated head names (default: every landmarked head)")
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args(argv)
    logging.disable(logging.WARNING)
    heads = {n: h for n, h in heads_in(args.data).items() if h[1] is not None}
    if args.heads:
        heads = {n: heads[n] for n in args.heads.split(",")}
    variants = args.variants.split(",")
    generic = load_generic()
    sep = " | " if args.markdown else "  "
    print(sep.join(["head", "copies", "P chin", "P angle", "T chin", "T angle", "T angle from", "P strained",
                    "T strained"]))
    if args.markdown:
        print("|".join(["---"] * 9))
    tally, t0 = {k: [] for k in ("P chin", "P angle", "T chin", "T angle")}, time.perf_counter()
    for name, (mesh, lm_path) in heads.items():
        V, F = load_mesh(mesh)
        lm = {n: np.asarray(p, dtype=np.float64) for n, p in read_landmarks(lm_path).items()}
        rows = []
        for vname in variants:
            var = zc.make_variant(vname, V, F, lm, zlib.crc32(name.encode()))
            if var is not None:
                rows.append(run_copy(var, generic))
        cells = []
        for kind, k in (("P", 0), ("P", 1), ("T", 0), ("T", 1)):
            vals = [r[kind][k] for r in rows if r[kind][k] is not None]
            tally[f"{kind} {'chin' if k == 0 else 'angle'}"] += vals
            cells.append(fmt(min(vals)) if vals else "-")
        strain = [f"{rows[0][k][3]:.2%}" if rows else "-" for k in ("P", "T")]   # the as-is copy
        line = [name, str(len(rows)), *cells, rows[0]["T"][2] if rows else "-", *strain]
        print(("| " + sep.join(line) + " |") if args.markdown else sep.join(line), flush=True)
    print()
    for key, vals in tally.items():
        if vals:
            good = sum(v >= GOOD for v in vals)
            print(f"{key}: {good}/{len(vals)} copies >= {GOOD} (lowest {min(vals):.2f}, median {np.median(vals):.2f})")
    print(f"{len(heads)} heads x {len(variants)} variants; {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
