"""ARKit shapes on heads the shape set was not built on: deformation transfer against copying (issue #15).

Run by hand, not by the tests::

    python benchmarks/arkit.py                       # 4 identities (~3 min on 2 cores)
    python benchmarks/arkit.py --identities 3 7      # these ICT identities
    python benchmarks/arkit.py --no-remesh           # keep ICT's triangulation (an easier case)
    python benchmarks/arkit.py --one-surface         # skin only, taken as a one-surface scan (lids closed by
                                                     # autobones.arkit.lids, as transfer --arkit does on scans)
    python benchmarks/arkit.py --time                # what the 52 shapes add to transfer on a 27k-vertex head
    python benchmarks/arkit.py --lips                # how jawOpen and a few mouth shapes move the lips, with
                                                     # and without the lip line set free, on the shared heads

Heads: ICT-FaceKit identities (``../shared/data/ict/ict_facekit_shapes.npz``; the shape set's
base is ICT's neutral head, which no identity is), each **remeshed** (one Loop subdivision,
then ``fast_simplification`` back to ICT's triangle count: no vertex or triangle is ICT's)
and at its own scale (centimetres). Its 27 landmarks are ICT's neutral landmarks carried by
their barycentric coordinates onto the identity, then to the closest remeshed point.

Truth: ICT is linear: identity k with expression E is ``neutral + identity_k + E``; at a
remeshed vertex the truth displacement is ``E`` interpolated at its closest point on the
identity, in the part the remeshed part came from (``browInnerUp`` and ``cheekPuff`` are ICT's two
halves summed). "all" includes the eyeballs, teeth and mouth socket, which the packaged skin-only
set does not carry: they move rigidly with the skin nearest them (``DeformationTransfer.transform``).

Score per shape: explained fraction ``1 - ||error|| / ||true displacement||`` over the skin
(the largest connected part) and over all vertices; for deformation transfer
(:class:`autobones.arkit.deformation_transfer.DeformationTransfer`) and the copy baseline
(:func:`autobones.arkit.copy_baseline.copy_displacements`), both through one dense
correspondence of the packaged ICT skin onto the head. Mean and worst over the 51 shapes ICT
has (``tongueOut`` is absent). Time: the correspondence, then the deformation transfer of
all shapes (mapping, one factorisation, the solve); 2 cores shared with other work.

Lids: per head and side, the fraction of the lid gap ``eyeBlinkLeft`` / ``eyeBlinkRight`` close
(:func:`autobones.arkit.lids.gap_closure`: between the skin vertices nearest the palpebrale
landmarks, between the landmarks' own points, and the latter's vertical part), for the truth,
deformation transfer and the copy.

Folds (:mod:`autobones.arkit.folds`): the transfer is scored without and with the opt-in fold repair
(``DT skin`` / ``DT all`` are without it, as ``transfer --arkit`` makes them), with the triangles each shape
turns over at weight 1 before and after it (``mouthClose`` on top of ``jawOpen``) and the time it adds.
``--fold-heads`` instead runs ``autobones.transfer`` and ``arkit_targets(rig, repair_folds=True)`` on the shared heads (james,
menpo3d's template, LeePerrySmith and demosthenes with detected landmarks, ICT identity002, the goat
and the robot) and prints the sidecar's fold counts per head and shape, before and after the repair::

    python benchmarks/arkit.py --fold-heads
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from autobones.arkit.copy_baseline import copy_displacements  # noqa: E402
from autobones.geometry.rotations import similarity  # noqa: E402
from autobones.arkit.folds import unfold_shapes  # noqa: E402
from autobones.arkit.lid_meet import meet_lids  # noqa: E402
from autobones.arkit.lids import eye_sides, gap_closure  # noqa: E402
from autobones.arkit.names import ict_names  # noqa: E402
from autobones.arkit.shapes import load_shapes  # noqa: E402
from autobones.arkit.targets import CORRESPONDENCE, arkit_targets, deformation_targets  # noqa: E402
from autobones.geometry.closest import closest_points  # noqa: E402
from autobones.geometry.topology import mesh_parts  # noqa: E402
from autobones.io.obj import read_obj  # noqa: E402
from autobones.orient import frame_from_landmarks  # noqa: E402
from autobones.rig_transfer.correspondence import dense_correspondence  # noqa: E402

ICT = os.path.join(ROOT, "..", "shared", "data", "ict")


def remesh(V, F):
    """One Loop subdivision, then quadric decimation back to ``len(F)`` triangles."""
    import fast_simplification
    import trimesh

    Vs, Fs = trimesh.remesh.subdivide_loop(V, F, iterations=1)
    Vr, Fr = fast_simplification.simplify(Vs, Fs, target_reduction=1.0 - len(F) / len(Fs))
    keep = np.unique(Fr)  # drop unreferenced vertices
    remap = -np.ones(len(Vr), dtype=np.int64)
    remap[keep] = np.arange(len(keep))
    return np.asarray(Vr, dtype=np.float64)[keep], remap[Fr]


def carry(P, V, F, part, Pq_part=None):
    """Closest points of ``P`` on (V, F) (same part when given): (faces, barycentric)."""
    face_labels = part[F[:, 0]]
    _, face, bary, _ = closest_points(P, V, F, labels=Pq_part, face_labels=face_labels if Pq_part is not None else None)
    return face, bary


def score(X, T, mask):
    return 1.0 - np.linalg.norm(X[mask] - T[mask]) / max(np.linalg.norm(T[mask]), 1e-300)


def remeshed_identity(Vi, F, part, lm, do_remesh=True, one_surface=False):
    """An ICT identity ``Vi`` (n, 3) on ICT's triangles ``F`` (parts ``part``, landmarks ``lm``) as a
    head nobody triangulated for it: remeshed (:func:`remesh`), optionally its skin alone (a scan
    has no eyeballs, teeth or socket), its landmarks moved to the closest remeshed point, and each
    remeshed vertex's place on the identity (ICT face ``tf``, barycentric ``tb``) in the ICT part its
    remeshed part came from (the part most of its vertices are closest to): the truth of an ICT
    displacement field is interpolated there. Returns (Vt, Ft, landmarks, tf, tb)."""
    Vt, Ft = remesh(Vi, F) if do_remesh else (Vi, F)
    if one_surface:  # the skin alone, no eyeballs, teeth or socket: as a scan would be
        tpart = mesh_parts(len(Vt), Ft)
        keep = tpart == np.argmax(np.bincount(tpart))
        remap = -np.ones(len(Vt), dtype=np.int64)
        remap[keep] = np.arange(keep.sum())
        Vt, Ft = Vt[keep], remap[Ft[keep[Ft[:, 0]]]]
    tpart = mesh_parts(len(Vt), Ft)
    f0, _ = carry(Vt, Vi, F, part)
    votes = np.zeros((tpart.max() + 1, part.max() + 1))
    np.add.at(votes, (tpart, part[F[f0, 0]]), 1)
    tf, tb = carry(Vt, Vi, F, part, np.argmax(votes, axis=1)[tpart])
    _, lfv, lbv, _ = closest_points(np.array(list(lm.values())), Vt, Ft)
    lm_t = {n: (Vt[Ft[f]] * b[:, None]).sum(axis=0) for n, f, b in zip(lm, lfv, lbv)}
    return Vt, Ft, lm_t, tf, tb


def run_identity(k, S, z, neutral, F, part, lm_neutral, do_remesh=True, one_surface=False, close_lids=True, meet=True):
    Vi = neutral + z[f"identity/identity{k:03d}"].astype(np.float64)
    # landmarks: ICT's neutral landmarks at their barycentric place on the identity
    lf, lb = carry(np.array(list(lm_neutral.values())), neutral, F, part)
    lm = {n: (Vi[F[f]] * b[:, None]).sum(axis=0) for n, f, b in zip(lm_neutral, lf, lb)}
    Vt, Ft, lm_t, tf, tb = remeshed_identity(Vi, F, part, lm, do_remesh, one_surface)
    tpart = mesh_parts(len(Vt), Ft)
    tskin = tpart == np.argmax(np.bincount(tpart))
    names = S.names
    T = np.stack([np.einsum("vcd,vc->vd", sum(z[f"expression/{i}"].astype(np.float64) for i in ict_names(n))[F[tf]],
                            tb) for n in names])
    D = np.stack([S.deltas[n] for n in names])
    t0 = time.perf_counter()
    P = dense_correspondence(S.vertices, S.faces, Vt, Ft, S.landmarks, lm_t, **CORRESPONDENCE)[0]
    t_corr = time.perf_counter() - t0
    t0 = time.perf_counter()
    timings = {}
    frame = frame_from_landmarks(Vt, Ft, lm_t)  # as transfer --arkit: the lip line is looked for on every head
    X = deformation_targets(S, D, P, Vt, Ft, lm_t, frame if one_surface else None, timings=timings,
                            close_lids=close_lids, frame=frame)
    if meet:  # the blinks' lid margins brought together, as arkit_targets does (no eyeballs given here)
        X = np.stack([v for v in meet_lids(Vt, Ft, lm_t, dict(zip(names, X)))[0].values()])
    t_dt = time.perf_counter() - t0
    t0 = time.perf_counter()
    X0 = X  # before the fold repair; X: with it (arkit_targets repairs)
    X, folds = unfold_shapes(Vt, Ft, X0, names)
    t_fold = time.perf_counter() - t0
    shared = [n for n in S.landmarks if n in lm_t]
    s, R = similarity(np.array([S.landmarks[n] for n in shared]), np.array([lm_t[n] for n in shared]))
    C = copy_displacements(S.faces, D, P, Vt, s, R)
    every = np.ones(len(Vt), dtype=bool)
    rows = {n: (score(X0[j], T[j], tskin), score(C[j], T[j], tskin), score(X0[j], T[j], every), score(C[j], T[j], every),
                score(X[j], T[j], tskin), score(X[j], T[j], every))
            for j, n in enumerate(names)}
    up = frame_from_landmarks(Vt, Ft, lm_t).rotation[1]
    lids = {}
    for side in eye_sides(lm_t):
        j = names.index("eyeBlinkLeft" if side == "l" else "eyeBlinkRight")
        lids[side] = {m: gap_closure(Vt, Ft, A[j], lm_t, side, up) for m, A in (("truth", T), ("DT", X), ("copy", C))}
    return {"identity": k, "vertices": len(Vt), "triangles": len(Ft), "correspond_s": t_corr, "transfer_s": t_dt,
            "dt_timings": timings, "rows": rows, "lids": lids, "fold_s": t_fold,
            "folds": {n: (r["before"], r["after"]) for n, r in folds.items()}}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--identities", type=int, nargs="+", default=[3, 7, 11, 15])
    ap.add_argument("--no-remesh", action="store_true")
    ap.add_argument("--one-surface", action="store_true",
                    help="keep only each head's skin and take it as a one-surface scan (eye surface free, lids closed)")
    ap.add_argument("--no-lids", action="store_true", help="with --one-surface: only set the eye surface free")
    ap.add_argument("--no-meet", action="store_true",
                    help="the blinks as the transfer carries them, their lid margins not brought together")
    ap.add_argument("--json", help="also write the numbers here")
    ap.add_argument("--time", action="store_true",
                    help="what the 52 shapes add to transfer on a 27k-vertex head, and arkit_targets' stages")
    ap.add_argument("--lips", action="store_true",
                    help="how jawOpen and a few mouth shapes move the lips on the shared heads, with and without "
                         "the lip line set free")
    ap.add_argument("--fold-heads", action="store_true",
                    help="fold counts of transfer --arkit on the shared heads, goat and robot, before/after the repair")
    args = ap.parse_args(argv)
    if args.fold_heads:
        return fold_heads()
    if args.lips:
        return lips()
    if args.time:
        return timing()
    S = load_shapes()
    neutral, F = read_obj(os.path.join(ICT, "generic_neutral_mesh.obj"))
    part = mesh_parts(len(neutral), F)
    with open(os.path.join(ICT, "generic_neutral_mesh.landmarks.json")) as fh:
        lm_neutral = {n: np.asarray(v, dtype=np.float64) for n, v in json.load(fh)["landmarks"].items()}
    z = dict(np.load(os.path.join(ICT, "ict_facekit_shapes.npz")))
    results = []
    for k in args.identities:
        r = run_identity(k, S, z, neutral, F, part, lm_neutral, do_remesh=not args.no_remesh,
                         one_surface=args.one_surface, close_lids=not args.no_lids, meet=not args.no_meet)
        results.append(r)
        A = np.array(list(r["rows"].values()))
        print(f"identity{k:03d}: {r['vertices']} vertices, {r['triangles']} triangles; correspondence "
              f"{r['correspond_s']:.1f} s, deformation transfer of {len(r['rows'])} shapes {r['transfer_s']:.1f} s "
              f"({', '.join(f'{a} {b:.2f}' for a, b in r['dt_timings'].items())}); skin: DT mean {A[:, 0].mean():.1%} "
              f"worst {A[:, 0].min():.1%}, copy mean {A[:, 1].mean():.1%} worst {A[:, 1].min():.1%}", flush=True)
    names = list(results[0]["rows"])
    M = np.array([[r["rows"][n] for n in names] for r in results])  # (ids, shapes, 4)
    per = M.mean(axis=0)
    print()
    print("| shape | DT skin | copy skin | DT all | copy all |")
    print("|---|---|---|---|---|")
    for j in np.argsort(per[:, 0]):
        print(f"| {names[j]} | {per[j, 0]:.1%} | {per[j, 1]:.1%} | {per[j, 2]:.1%} | {per[j, 3]:.1%} |")
    print()
    print(f"| over {len(results)} remeshed identities x {len(names)} shapes "
          "| DT skin | copy skin | DT all | copy all |")
    print("|---|---|---|---|---|")
    print("| mean | " + " | ".join(f"{M[:, :, c].mean():.1%}" for c in range(4)) + " |")
    repaired = (f"DT skin {M[:, :, 4].mean():.1%} / worst {M[:, :, 4].mean(axis=0).min():.1%}, "
              f"DT all {M[:, :, 5].mean():.1%}")
    print("| worst shape (mean over identities) | " + " | ".join(f"{per[:, c].min():.1%}" for c in range(4)) + " |")
    print("| worst shape on any identity | " + " | ".join(f"{M[:, :, c].min():.1%}" for c in range(4)) + " |")
    print()
    print("Lid gap closed by eyeBlinkLeft / eyeBlinkRight (nearest vertices / landmark points / vertical / "
          "upper margin to the lower):")
    print()
    print("| head | side | truth | DT | copy |")
    print("|---|---|---|---|---|")
    for r in results:
        for side, c in r["lids"].items():
            print(f"| identity{r['identity']:03d} | {side} | " + " | ".join(
                " / ".join(f"{c[m][w]:.0%}" for w in ("vertices", "points", "vertical", "margins")) for m in ("truth", "DT", "copy"))
                + " |")
    print(f"\nwith the fold repair: {repaired}; without: DT skin {M[:, :, 0].mean():.1%} / worst "
          f"{per[:, 0].min():.1%}, DT all {M[:, :, 2].mean():.1%}; repair time median "
          f"{np.median([r['fold_s'] for r in results]):.2f} s")
    print()
    print("Triangles turned over at weight 1 (mouthClose on top of jawOpen), before -> after the repair:")
    print()
    print("| shape | " + " | ".join(f"identity{r['identity']:03d}" for r in results) + " |")
    print("|---|" + "---|" * len(results))
    for n in names:
        if any(r["folds"][n][0] for r in results):
            print(f"| {n} | " + " | ".join(f"{r['folds'][n][0]} -> {r['folds'][n][1]}" for r in results) + " |")
    ts = [r["transfer_s"] for r in results]
    print(f"\ntime, all {len(names)} shapes by deformation transfer: median {np.median(ts):.1f} s "
          f"(min {min(ts):.1f}, max {max(ts):.1f}) on ~{results[0]['vertices']}-vertex heads; "
          f"correspondence {np.median([r['correspond_s'] for r in results]):.1f} s")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=1, default=float)


FOLD_HEADS = {  # name: (mesh, landmarks; None: detected by autobones.transfer)
    "james": ("menpo3d/james.obj", "menpo3d/james.landmarks.json"),
    "template": ("menpo3d/template.ply", "menpo3d/template.landmarks.json"),
    "LeePerrySmith": ("misc/LeePerrySmith.obj", None),
    "demosthenes": ("misc/demosthenes-low-res.obj", None),
    "identity002": ("ict/identity002.obj", "ict/identity002.landmarks.json"),
    "goat": ("misc/goathead.obj", "tests/landmarks/goathead.landmarks.json"),
    "robot": ("misc/robot_head_neutral.obj", "tests/landmarks/robot_head_neutral.landmarks.json"),
}


def fold_heads():
    """transfer --arkit on each of :data:`FOLD_HEADS`: the sidecar's folds per shape, before -> after."""
    import autobones

    data = os.path.join(ROOT, "..", "shared", "data")
    recs = {}
    for head, (mesh, lm) in FOLD_HEADS.items():
        lm = None if lm is None else os.path.join(ROOT if lm.startswith("tests/") else data, lm)
        t = time.perf_counter()
        rig = autobones.transfer(os.path.join(data, mesh), lm)
        recs[head] = arkit_targets(rig, repair_folds=True)[1]["folds"]  # before: as transfer --arkit makes them
        print(f"{head}: {len(rig.vertices)} vertices, transfer --arkit {time.perf_counter() - t:.1f} s", flush=True)
    names = [n for n in next(iter(recs.values()))["before_repair"]
             if any(r["before_repair"][n] or r["after_repair"][n] for r in recs.values())]
    print()
    print("| shape | " + " | ".join(recs) + " |")
    print("|---|" + "---|" * len(recs))
    for n in names:
        print(f"| {n} | " + " | ".join(f"{r['before_repair'][n]} -> {r['after_repair'][n]}" for r in recs.values()) + " |")
    print("| all shapes | " + " | ".join(f"{sum(r['before_repair'].values())} -> {sum(r['after_repair'].values())}"
                                        for r in recs.values()) + " |")


def timing(runs=3):
    """The time the 52 shapes add on a 27k-vertex head (ICT identity002 with its landmarks): ``transfer``
    and ``transfer(arkit=True)`` alternately ``runs`` times (the latter fits the shape set's
    correspondence in a second thread beside its own fit), and ``arkit_targets`` alone on the rig with
    its stage timings (its correspondence then in the same thread)."""
    import autobones
    from autobones.io.landmarks import read_landmarks
    from autobones.io.mesh import load_mesh

    V, F = load_mesh(os.path.join(ICT, "identity002.obj"))
    lm = read_landmarks(os.path.join(ICT, "identity002.landmarks.json"))
    autobones.transfer((V, F), lm, arkit=True)  # warm: the rig, the shape set and the jaw prior loaded once
    plain, both, alone = [], [], []
    for _ in range(runs):
        t = time.perf_counter()
        rig = autobones.transfer((V, F), lm)
        plain.append(time.perf_counter() - t)
        t = time.perf_counter()
        autobones.transfer((V, F), lm, arkit=True)
        both.append(time.perf_counter() - t)
        tim = {}
        t = time.perf_counter()
        arkit_targets(rig, timings=tim)
        alone.append((time.perf_counter() - t, tim))
    added = [b - a for a, b in zip(plain, both)]
    print(f"identity002 ({len(V)} vertices), {runs} runs: transfer {np.median(plain):.2f} s "
          f"({min(plain):.2f}-{max(plain):.2f}), transfer --arkit {np.median(both):.2f} s "
          f"({min(both):.2f}-{max(both):.2f}): the shapes add {np.median(added):.2f} s ({min(added):.2f}-{max(added):.2f})")
    for total, tim in alone:
        print(f"arkit_targets alone {total:.2f} s: " + ", ".join(f"{k} {v:.2f}" for k, v in tim.items()))


LIP_SHAPES = ("jawOpen", "mouthFunnel", "mouthLowerDownLeft", "mouthShrugUpper")


def lips():
    """transfer --arkit on each of :data:`FOLD_HEADS` with and without the lip line set free
    (:func:`autobones.arkit.fissures.mouth_fissure`): how jawOpen and a few mouth shapes move the
    upper and lower lip, beside ICT's own shapes on its own skin, and the folds left."""
    import autobones
    from autobones.arkit.fissures import lip_motion, mouth_fissure

    data = os.path.join(ROOT, "..", "shared", "data")
    S = load_shapes()
    up_src = frame_from_landmarks(S.vertices, S.faces, S.landmarks).rotation[1]
    print("| head | lip-line triangles | shape | upper | lower | opening | folds left (all shapes) |")
    print("|---|---:|---|---|---|---|---|")
    for n in LIP_SHAPES:
        u, lo, o = lip_motion(S.vertices, S.landmarks, S.deltas[n], up_src)
        print(f"| ICT's own | - | {n} | {u:.3f} | {lo:.3f} | {o:.3f} | - |")
    for head, (mesh, lm) in FOLD_HEADS.items():
        lm = None if lm is None else os.path.join(ROOT if lm.startswith("tests/") else data, lm)
        rig = autobones.transfer(os.path.join(data, mesh), lm)
        if not all(k in rig.landmarks for k in ("stomion", "labiale_superius", "labiale_inferius",
                                                 "cheilion_l", "cheilion_r")):
            print(f"| {head} | - | (no lip landmarks) | | | | |")
            continue
        V = np.asarray(rig.vertices)
        count = int(mouth_fissure(V, rig.faces, rig.landmarks, rig.frame).sum())
        runs = {}
        for free in (False, True):
            X, rec = arkit_targets(rig, free_lips=free)
            runs[free] = (X, sum(rec["folds"]["after_repair"].values()))
        for n in LIP_SHAPES:
            cells = [lip_motion(V, rig.landmarks, runs[free][0][n], rig.frame.rotation[1]) for free in (False, True)]
            print(f"| {head} | {count} | {n} | " + " | ".join(
                f"{a[k]:.3f} -> {b[k]:.3f}" for a, b in [cells] for k in range(3)) +
                  f" | {runs[False][1]} -> {runs[True][1]} |", flush=True)


if __name__ == "__main__":
    main()
