"""Benchmark the transferred rig's separate teeth: does each ride the jaw or the skull whole, and the
right one (``autobones.rig_transfer.mouth_parts``)?

    python benchmarks/teeth.py [--variants as-is,rot1,x1000,mirror,remesh,dec5k,jitter] [--heads ...]
    python benchmarks/teeth.py --place [--variants ...]    # place's eyeballs and teeth, one row each?

Heads: ICT's generic neutral and identities 000-002 (``../shared/data/ict``, 32 separate teeth, a
mouth bag, eyeballs, lashes), with their landmark files, in the zoo's copies (``zoo_checks.make_variant``:
turned, scaled, mirrored, remeshed, decimated to 5k vertices, landmarks jittered by 1 % of ex-ex).
Truth: ICT's own ``jawOpen`` (``jawOpen.obj`` less the generic neutral, per vertex; ICT's model is
linear, so the same offsets are each identity's): a separate part inside the mouth whose vertices
move by more than a tenth of the largest motion rides the jaw (1), else the skull (0). A copy's
vertices take the truth of the original's nearest vertex (mapped back). Reported, before (the
repair's field alone, ``carried_mouth_parts`` and ``rigid_mouth_parts`` switched off) and after, over the small separate parts
within reach of the stomion (``expressions.definitions.MODEL_DEFAULTS['mouth_parts']``):

- ``parts``: how many; ``whole``: the share whose jaw weight is one value (spread <= 1e-9);
- ``right``: the share whose mean jaw weight lies within 0.1 of the truth;
- ``|w - truth|``: the mean over their vertices;
- ``bag``: the large separate parts inside the mouth (ICT's mouth bag), skinned by the rig's weights with the
  jaw turned about the rig's jaw joint to fit jawOpen on the lower teeth: the mean distance from jawOpen, %
  of its largest motion; ``largest jaw step``: over every edge off the lip line (the zoo's check 2: <= 0.3).

``--place``: ``place`` at each density on the same copies, before (``rigid_weights`` switched off) and after:
the largest spread of a small closed part's weights (largest difference of a vertex's row from the part's
mean), over the eyeballs and over the teeth (``geometry.rigid_parts.closed_small_parts``).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from unittest import mock

import numpy as np
from scipy.spatial import cKDTree

import autobones
from autobones.geometry.topology import mesh_parts
from autobones.io.landmarks import read_landmarks
from autobones.io.mesh import load_mesh
from autobones.rig_transfer import pipeline
from autobones.rig_transfer.jaw import lip_line_edges
from autobones.rig_transfer.mouth_parts import carried_mouth_parts, rigid_mouth_parts

ROOT = Path(__file__).resolve().parents[1]
ICT = ROOT.parent / "shared" / "data" / "ict"
sys.path.insert(0, str(ROOT / "benchmarks"))
import zoo_checks  # noqa: E402

HEADS = ("generic_neutral_mesh", "identity000", "identity001", "identity002")
VARIANTS = "as-is,rot1,x1000,mirror,remesh,dec5k,jitter"


def truth_offsets():
    """(n, 3) float: ICT's jawOpen offset per vertex (mesh units, cm)."""
    return load_mesh(ICT / "jawOpen.obj")[0] - load_mesh(ICT / "generic_neutral_mesh.obj")[0]


def bag_error(rig, var, V0, D0, jaw):
    """(mean skinned-motion error on the large inner parts, % of the largest jawOpen motion; largest jaw
    step off the lip line): the jaw turned about the rig's jaw joint to fit jawOpen on the teeth it moves."""
    V, F, lm = var.V, var.F, var.lm
    sk = rig.skeleton
    near = cKDTree(V0).query(var.back(V))[1]
    D = var.s * D0[near] @ var.R.T
    size = np.linalg.norm(D, axis=1)
    teeth = rigid_mouth_parts(V, F, rig.weights, sk.names, sk.heads, rig.frame, lm)[1]
    inner = carried_mouth_parts(V, F, rig.weights, sk.names, sk.heads, rig.frame, lm)[1]
    large = np.setdiff1d(inner, teeth)
    c = sk.heads[sk.names.index("jaw")]
    lower = teeth[size[teeth] > 0.1 * size.max()]
    P, Q = V[lower] - c, V[lower] + D[lower] - c
    U, _, Vt = np.linalg.svd(P.T @ Q)
    R = Vt.T @ np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))]) @ U.T
    t = (Q - P @ R.T).mean(axis=0)
    u = (V - c) @ R.T + t + c - V
    err = np.linalg.norm(jaw[:, None] * u - D, axis=1)[large]
    E, on_line = lip_line_edges(V, F, lm)
    return 100.0 * float(err.mean()) / size.max(), float(np.abs(jaw[E[:, 0]] - jaw[E[:, 1]])[~on_line].max())


def score(rig, var, V0, motion, before):
    """(parts, whole, right, mean |w - truth|) for rig weights after / before (``before`` (n,) jaw)."""
    V, F, lm = var.V, var.F, var.lm
    sk = rig.skeleton
    rows = rigid_mouth_parts(V, F, rig.weights, sk.names, sk.heads, rig.frame, lm)[1]
    part = mesh_parts(len(V), F)
    near = cKDTree(V0).query(var.back(V))[1]
    moves = motion[near] > 0.1 * motion.max()
    out = {}
    for tag, jaw in (("before", before), ("after", rig.weights[:, sk.names.index("jaw")])):
        whole, right, err = [], [], []
        for p in np.unique(part[rows]):
            r = part == p
            t = float(moves[r].mean() > 0.5)
            whole.append(np.ptp(jaw[r]) <= 1e-9)
            right.append(abs(jaw[r].mean() - t) <= 0.1)
            err.append(np.abs(jaw[r] - t))
        n = len(whole)
        out[tag] = (n, np.mean(whole) if n else np.nan, np.mean(right) if n else np.nan,
                    float(np.concatenate(err).mean()) if n else np.nan)
    return out


def place_spreads(variants, heads):
    """Print the ``--place`` table."""
    from autobones.geometry import rigid_parts
    from autobones.placement import pipeline as placing

    print("| head | variant | density | eyeballs before -> after | teeth before -> after | s |")
    print("|---|---|---|---|---|---:|")
    for name in heads:
        V0, F0 = load_mesh(ICT / f"{name}.obj")[:2]
        lm0 = {k: np.asarray(v, dtype=np.float64) for k, v in read_landmarks(ICT / f"{name}.landmarks.json").items()}
        for vname in variants:
            var = zoo_checks.make_variant(vname, V0, F0, lm0, seed=0)
            if var is None or vname == "jitter":
                continue
            parts = rigid_parts.closed_small_parts(var.V, var.F)
            lm = var.lm
            ex = np.linalg.norm(lm["exocanthion_l"] - lm["exocanthion_r"])
            eye_at = [0.5 * (lm[f"exocanthion_{s}"] + lm[f"endocanthion_{s}"]) for s in "lr"]
            near_eye = [min(np.linalg.norm(var.V[r].mean(axis=0) - e) for e in eye_at) < 0.3 * ex for r in parts]
            eyes = [r for r, e in zip(parts, near_eye) if e]
            teeth = [r for r, e in zip(parts, near_eye) if not e]
            for density in ("sparse", "medium", "dense"):
                got = []
                for off in (True, False):
                    with mock.patch.object(placing, "rigid_weights", lambda W, *a, **k: np.array(W)) if off \
                            else mock.patch.object(placing, "rigid_weights", placing.rigid_weights):
                        t = time.perf_counter()
                        W = autobones.place((var.V, var.F), density=density).weights
                        s = time.perf_counter() - t
                    got.append([max((np.abs(W[r] - W[r].mean(axis=0)).max() for r in group), default=np.nan)
                                for group in (eyes, teeth)])
                (e0, t0), (e1, t1) = got
                print(f"| {name} | {vname} | {density} | {e0:.2f} -> {e1:.2f} ({len(eyes)}) | {t0:.2f} -> {t1:.2f} "
                      f"({len(teeth)}) | {s:.1f} |", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--variants", default=VARIANTS)
    ap.add_argument("--heads", default=",".join(HEADS))
    ap.add_argument("--place", action="store_true", help="place's eyeballs and teeth instead")
    args = ap.parse_args(argv)
    if args.place:
        return place_spreads(args.variants.split(","), args.heads.split(","))
    D0 = truth_offsets()
    motion = np.linalg.norm(D0, axis=1)
    print("| head | variant | vertices | teeth | whole before -> after | right before -> after "
          "| mean abs(w - truth) before -> after | bag motion error % before -> after | largest jaw step | s |")
    print("|---|---|---:|---:|---|---|---|---|---|---:|")
    t0 = time.perf_counter()
    for name in args.heads.split(","):
        V0, F0 = load_mesh(ICT / f"{name}.obj")[:2]
        lm0 = {k: np.asarray(v, dtype=np.float64) for k, v in read_landmarks(ICT / f"{name}.landmarks.json").items()}
        for vname in args.variants.split(","):
            var = zoo_checks.make_variant(vname, V0, F0, lm0, seed=0)
            if var is None:
                continue
            off = lambda V, F, W, *a, **k: (np.array(W), None)  # noqa: E731
            with mock.patch.object(pipeline, "rigid_mouth_parts", off), \
                    mock.patch.object(pipeline, "carried_mouth_parts", off):
                rig0 = autobones.transfer((var.V, var.F), var.lm)
            t = time.perf_counter()
            rig = autobones.transfer((var.V, var.F), var.lm)
            s = time.perf_counter() - t
            got = score(rig, var, V0, motion, rig0.weights[:, rig0.skeleton.names.index("jaw")])
            (n, w0, r0, e0), (_, w1, r1, e1) = got["before"], got["after"]
            (b0, j0), (b1, j1) = (bag_error(r, var, V0, D0, r.weights[:, r.skeleton.names.index("jaw")])
                                  for r in (rig0, rig))
            print(f"| {name} | {vname} | {len(var.V):,} | {n} | {w0:.0%} -> {w1:.0%} | {r0:.0%} -> {r1:.0%} "
                  f"| {e0:.3f} -> {e1:.3f} | {b0:.1f} -> {b1:.1f} | {j0:.2f} -> {j1:.2f} | {s:.1f} |", flush=True)
    print(f"\n{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
