"""Benchmark ``autobones.transfer``: time per stage and accuracy on ICT pairs.

    python benchmarks/transfer.py            # all 12 ordered ICT pairs, 27 and 10 landmarks
    python benchmarks/transfer.py --quick    # two pairs
    python benchmarks/transfer.py --scans    # time on dense scans: transfer and automatic landmarks

For each ordered pair (A, B) of the ICT same-topology heads (neutral and three
identities; vertex i of one is the true partner of vertex i of another), a
labelled rig is made on A (its skeleton from ``autobones.place``, and three
fields: a smooth scalar, 12 region labels, the place skin weights) and carried
onto B by the full ``transfer`` pipeline, with all 27 shared landmarks and with
10 of them. Reported, in % of B's outer-eye-corner distance (ex-ex):

- correspondence error: generic vertex i's point on B vs B's vertex i, mean and
  95th percentile, all vertices and the skin (largest part);
- field error: the scalar carried to B's vertices vs its true value (% of its
  range), and the fraction of region labels right;
- time per stage (load, landmarks = orientation + checks, correspond,
  skeleton, attributes) and the total, for the ~27k-vertex heads.

Also the built-in generic rig onto each ICT identity (time only: no ground truth).
Timings are wall-clock on a shared machine; read ratios between rows, not absolutes.

``--scans``: the built-in generic rig onto real scans and their Loop subdivisions (never decimated
after): ICT identity000 (26,719 vertices) and Loop x1 (105,569), the menpo3d template (53,349) and
Loop x1 (212,809), with their published landmarks moved to the subdivided surface by closest point,
and the demosthenes statue scan Loop x2 (133,887, a bust; the performance issue's 134k scan), whose
landmarks are found automatically first. Per head: ``autobones.transfer`` seconds per stage (median of
3 runs below 10 s), and automatic landmarks in seconds (frame + detection, as ``detect_landmarks`` does)
with the detector model loaded once beforehand, median of 3.
"""
from __future__ import annotations

import argparse
import itertools
import json
import platform
import time
from pathlib import Path

import numpy as np

import autobones
from autobones.geometry.topology import mesh_parts
from autobones.io.mesh import load_mesh
from autobones.labelled_rig import LabelledRig

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "ict"
HEADS = ["generic_neutral_mesh", "identity000", "identity001", "identity002"]
TEN = ["brow_outer_l", "brow_outer_r", "exocanthion_l", "exocanthion_r", "nasion", "pronasale", "subnasale",
       "cheilion_l", "cheilion_r", "menton"]


def load(name):
    V, F = load_mesh(DATA / f"{name}.obj")
    lm = {k: np.array(v) for k, v in json.load(open(DATA / f"{name}.landmarks.json"))["landmarks"].items()}
    return V, F, lm


def rig_on(name):
    from sklearn.cluster import KMeans

    V, F, lm = load(name)
    placed = autobones.place((V, F), density="sparse")
    fields = {"scalar": np.sin(V[:, 1] / 8) + 0.5 * np.cos(V[:, 0] / 6) + V[:, 2] / 20,
              "region": KMeans(12, n_init=2, random_state=0).fit_predict(V).astype(np.int64)}
    return LabelledRig(vertices=V, faces=F, landmarks=lm, skeleton=placed.skeleton, weights=placed.weights,
                       fields=fields, labels={"region": [f"r{i}" for i in range(12)]})


def scans():
    """Time ``transfer`` and ``detect_landmarks`` on dense scans (module doc, ``--scans``)."""
    import trimesh

    from autobones.geometry.closest import closest_points

    shared = DATA.parent
    rows = [("ICT identity000", "ict/identity000.obj", 0), ("ICT identity000", "ict/identity000.obj", 1),
            ("menpo3d template", "menpo3d/template.ply", 0), ("menpo3d template", "menpo3d/template.ply", 1),
            ("demosthenes", "misc/demosthenes-low-res.obj", 2)]
    print(f"{'head':18s} {'how':8s} {'vertices':>9s} {'load':>5s} {'lmk':>5s} {'corr':>5s} {'skel':>5s} "
          f"{'attr':>5s} {'total s':>7s} {'landmarks s':>11s}")
    from autobones.landmarks.detect import LandmarkDetector
    from autobones.landmarks.mediapipe import MediaPipeFaceMesh
    from autobones.orient import detect_frame

    detector = LandmarkDetector(detector=MediaPipeFaceMesh())  # one model, loaded by the first call
    detector.detect(*load_mesh(shared / "menpo3d/james.obj"))
    for label, rel, loops in rows:
        V, F = load_mesh(shared / rel)
        lm_file = (shared / rel).with_suffix(".landmarks.json")
        lm = ({k: np.array(v) for k, v in json.load(open(lm_file))["landmarks"].items()}
              if lm_file.exists() else None)
        if loops:
            V, F = trimesh.remesh.subdivide_loop(V, F, iterations=loops)
            V, F = np.ascontiguousarray(V, dtype=np.float64), np.ascontiguousarray(F, dtype=np.int64)
        if lm is not None:  # onto the subdivided surface
            names = list(lm)
            P = closest_points(np.array([lm[n] for n in names]), V, F)[0]
            lm = dict(zip(names, P))
        detect = []
        for _ in range(3):
            t = time.perf_counter()
            found = detector.detect(V, F, frame=detect_frame(V, F))  # as detect_landmarks, model loaded
            detect.append(time.perf_counter() - t)
        lm = lm if lm is not None else dict(found)
        runs = []
        for _ in range(3):
            t = time.perf_counter()
            rig = autobones.transfer((V, F), lm)
            runs.append((time.perf_counter() - t, rig.timings))
            if runs[-1][0] > 10:
                break
        total, tm = sorted(runs, key=lambda r: r[0])[len(runs) // 2]
        print(f"{label:18s} {('loop x%d' % loops) if loops else 'own':8s} {len(V):9,d} {tm['load']:5.2f} "
              f"{tm['landmarks']:5.2f} {tm['correspond']:5.2f} {tm['skeleton']:5.2f} {tm['attributes']:5.2f} "
              f"{total:7.2f} {np.median(detect):11.2f}", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--scans", action="store_true", help="time on dense scans only (transfer, landmarks)")
    args = ap.parse_args(argv)
    print(f"# machine: {platform.processor() or platform.machine()}, {__import__('os').cpu_count()} cores, "
          f"load average {__import__('os').getloadavg()[0]:.1f}")
    if args.scans:
        return scans()
    pairs = list(itertools.permutations(HEADS, 2))
    if args.quick:
        pairs = [("identity000", "identity001"), ("identity001", "identity002")]
    rigs = {}
    head = (f"{'source -> target':34s} {'lm':>3s} {'mean%':>6s} {'p95%':>6s} {'skin':>6s} {'skin95':>6s} "
            f"{'field%':>6s} {'labels':>6s} {'corr s':>6s} {'attr s':>6s} {'total s':>7s}")
    print(head)
    rows = []
    for a, b in pairs:
        if a not in rigs:
            rigs[a] = rig_on(a)
        Vb, Fb, lmb = load(b)
        skin = mesh_parts(len(Vb), Fb)
        skin = skin == np.bincount(skin).argmax()
        unit = np.linalg.norm(lmb["exocanthion_l"] - lmb["exocanthion_r"])
        for names in (sorted(lmb), TEN):
            details = {}
            t = time.perf_counter()
            rig = autobones.transfer((Vb, Fb), {n: lmb[n] for n in names}, rig=rigs[a], details=details)
            total = time.perf_counter() - t
            err = np.linalg.norm(details["correspondence"] - Vb, axis=1) / unit * 100
            truth = rigs[a].fields
            field = np.abs(rig.fields["scalar"] - truth["scalar"]) / np.ptp(truth["scalar"]) * 100
            labels = (rig.fields["region"] == truth["region"]).mean() * 100
            row = (f"{a[:15]:>15s} -> {b[:15]:15s} {len(names):3d} {err.mean():6.2f} {np.quantile(err, 0.95):6.2f} "
                   f"{err[skin].mean():6.2f} {np.quantile(err[skin], 0.95):6.2f} {field.mean():6.2f} {labels:6.1f} "
                   f"{rig.timings['correspond']:6.2f} {rig.timings['attributes']:6.2f} {total:7.2f}")
            print(row, flush=True)
            rows.append((len(names), err.mean(), np.quantile(err, 0.95), total))
    for k in (27, 10):
        sel = [r for r in rows if r[0] == k]
        print(f"{'pooled mean over pairs':34s} {k:3d} {np.mean([r[1] for r in sel]):6.2f} "
              f"{np.mean([r[2] for r in sel]):6.2f} {'':41s} {np.median([r[3] for r in sel]):7.2f} (median)")
    print("\n# built-in generic rig -> ICT heads (27 landmarks): seconds per stage")
    for b in HEADS:
        Vb, Fb, lmb = load(b)
        rig = autobones.transfer((Vb, Fb), lmb)
        stages = " ".join(f"{k}={v:.2f}" for k, v in rig.timings.items() if not k.startswith("fit_"))
        print(f"{b:22s} {len(Vb):6d} vertices  {stages}  total={sum(v for k, v in rig.timings.items() if not k.startswith('fit_')):.2f}")


if __name__ == "__main__":
    main()
