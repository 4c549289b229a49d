"""Batch throughput: meshes per minute with --jobs 1 and --jobs 2 on the same folder, and the Dask overhead.

    python benchmarks/batch.py [--copies 4] [--density sparse] [--no-dask]

The folder holds the small shared heads of ../shared/data (robots, goat, fsaverage, Fran,
MediaPipe face, decimated Lee Perry-Smith and James), ``--copies`` times each (moved, so
no two files are the same). Every engine rigs it into a fresh output folder through
:func:`autobones.batch.run_batch`, the code behind ``autobones batch``; wall time includes
starting the worker processes. The Dask run uses a ``LocalCluster`` of 2 worker processes
with 1 thread each, started before the clock runs, and its outputs are compared byte for
byte with the local run's.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
DATA = ROOT.parent / "shared" / "data"

SHARED = ["misc/robot_head_neutral.obj", "misc/robot_head_Angry.obj", "misc/robot_head_Sad.obj",
          "misc/robot_head_Surprised.obj", "misc/goathead.obj", "misc/fsaverage_head.obj", "misc/fran_cut.obj",
          "mediapipe/canonical_face_model.obj"]
DECIMATED = [("misc/LeePerrySmith.obj", 0.7), ("menpo3d/james.obj", 0.6)]


def make_folder(root, copies):
    import fast_simplification
    import trimesh

    from autobones.io.mesh import load_mesh

    meshes = [load_mesh(DATA / rel) + (Path(rel).stem,) for rel in SHARED]
    for rel, r in DECIMATED:
        V, F = load_mesh(DATA / rel)
        V, F = fast_simplification.simplify(V.astype(np.float32), F.astype(np.int32), target_reduction=r)
        meshes.append((V.astype(np.float64), F, f"{Path(rel).stem}_dec"))
    n = 0
    for c in range(copies):
        for V, F, stem in meshes:
            out = Path(root) / f"copy{c}" / f"{stem}.ply"
            out.parent.mkdir(parents=True, exist_ok=True)
            trimesh.Trimesh(V + 10.0 * c, F, process=False).export(out)
            n += 1
    return n


def timed(label, heads, out, options, **engine):
    from autobones.batch import run_batch

    t = time.perf_counter()
    rep = run_batch(heads, out, options, **engine)
    dt = time.perf_counter() - t
    n = rep["counts"]["ok"]
    assert rep["counts"]["failed"] == 0, [f["error"] for f in rep["files"] if f["error"]]
    busy = sum(f["seconds"] or 0.0 for f in rep["files"])
    print(f"{label:<28} {n:4d} meshes {dt:7.1f} s {60 * n / dt:8.1f} meshes/min   "
          f"(per-file work {busy:.1f} s, {busy / dt:.2f} files in flight on average; load {os.getloadavg()[0]:.1f})")
    return dt


def same_outputs(a, b):
    def files(d):
        return {p.relative_to(d): p.read_bytes() for p in Path(d).rglob("*") if p.is_file()
                and p.name != "batch_report.json"}

    return files(a) == files(b)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--copies", type=int, default=4, help="copies of the 10 heads (default 4: 40 meshes)")
    ap.add_argument("--density", default="sparse")
    ap.add_argument("--no-dask", action="store_true")
    args = ap.parse_args()

    from autobones.batch import make_options

    options = make_options(density=args.density)
    with tempfile.TemporaryDirectory(prefix="autobones-bench-") as tmp:
        heads = Path(tmp) / "heads"
        n = make_folder(heads, args.copies)
        print(f"{n} meshes, density {args.density}, {os.cpu_count()} cores")
        t1 = timed("local --jobs 1", heads, Path(tmp) / "j1", options, jobs=1)
        t2 = timed("local --jobs 2", heads, Path(tmp) / "j2", options, jobs=2)
        print(f"speed-up --jobs 2 / --jobs 1: {t1 / t2:.2f}x (target >= 1.8x)")
        assert same_outputs(Path(tmp) / "j1", Path(tmp) / "j2"), "jobs 1 and jobs 2 outputs differ"
        if args.no_dask:
            return
        from distributed import LocalCluster

        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
            td = timed("dask LocalCluster 2 workers", heads, Path(tmp) / "dask", options,
                       scheduler=cluster.scheduler_address)
        print(f"Dask overhead vs --jobs 2: {100 * (td / t2 - 1):+.0f} % wall "
              f"({(td - t2) / n * 1000:+.0f} ms per mesh)")
        print("dask outputs identical to local:", same_outputs(Path(tmp) / "j2", Path(tmp) / "dask"))


if __name__ == "__main__":
    main()
