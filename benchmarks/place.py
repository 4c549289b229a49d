"""Benchmark ``autobones place`` on real scans and their Loop subdivisions, up to a million vertices.

Run by hand, not by the tests::

    python benchmarks/place.py                      # --set scans,large: every row below (about 25 min)
    python benchmarks/place.py --set scans          # the shared scans at their own resolution and Loop x1
    python benchmarks/place.py --set large          # 134k and 535k scan, 850k scan, 1M synthetic
    python benchmarks/place.py --set synthetic      # LeePerrySmith decimated/subdivided to 5k, 134k, 500k
    python benchmarks/place.py --set large --profile /tmp/prof --repeat 1

Meshes (built once before any timing; written as OBJ so "load" is a real file read):

- ``scans``: the shared heads at their own resolution (LeePerrySmith, demosthenes, james, the menpo3d
  template, ICT identity000 with its eyes, teeth and 56 parts) and each Loop-subdivided once
  (``trimesh.remesh.subdivide_loop``), never decimated after, so the scanner's irregular
  triangulation stays;
- ``large``: demosthenes (a statue photoscan) Loop-subdivided twice (133,887 vertices) and three
  times (535,277), the template twice (850,062), and LeePerrySmith subdivided four times and
  decimated to 1,000,000 (synthetic: smoother and better ordered than a scan);
- ``synthetic``: the earlier rows, LeePerrySmith decimated or subdivided + decimated to 5k/134k/500k.

Each run is a fresh worker process (``--worker``) calling ``autobones.place(path, density)``:

- stage seconds are ``Rig.timings``; "total" the wall time of the call (load included), "CPU" its CPU
  time (all threads); peak RSS is the worker's ``VmHWM`` when ``place`` returns (Python, numpy and
  the mesh included); runs shorter than 10 s are repeated (``--repeat``) and the fastest kept;
- "exact": the same call with the decimated proxy switched off
  (``autobones.placement.pipeline.PROXY_ABOVE = None``: the heat system, the inside tests and the
  closest-point queries all on the full welded mesh), up to ``--exact-max`` vertices; the table gives
  its time, and the difference of the default result from it: the largest and the mean absolute
  weight difference over all vertices and bones, the 99.9th percentile of each vertex's largest
  difference, and the largest joint displacement in head sizes;
- baselines on the same mesh and bones, where they finish: libigl's bounded biharmonic weights
  (``igl.bbw``, Jacobson et al. 2011; one point handle per bone at the vertex nearest its head) up to
  ``--bbw-max`` vertices, and Blender's bone heat ("Parent with Automatic Weights", Baran & Popovic
  2007) through ``benchmarks/blender_heat.py`` when ``blender`` is on PATH, up to ``--blender-max``;
  Blender's column gives its seconds and how many vertices it left unweighted.

Ratios: "t/v" is time per vertex over that of the smallest row of the run (1.0 = linear); "growth"
lines give the exponent p of time ~ n^p between the large rows.
"""
from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DATA = HERE.parent.parent / "shared" / "data"
SOURCE = DATA / "misc" / "LeePerrySmith.obj"
STAGES = ("load", "orient", "proxy", "segment", "facial", "weights")
SCANS = (("LeePerrySmith", "misc/LeePerrySmith.obj"), ("demosthenes", "misc/demosthenes-low-res.obj"),
         ("james", "menpo3d/james.obj"), ("template", "menpo3d/template.ply"),
         ("ICT identity000", "ict/identity000.obj"))
SETS = {
    "scans": [(name, rel, loops, None) for name, rel in SCANS for loops in (0, 1)],
    "large": [("demosthenes", "misc/demosthenes-low-res.obj", 2, None),
              ("demosthenes", "misc/demosthenes-low-res.obj", 3, None),
              ("template", "menpo3d/template.ply", 2, None),
              ("LeePerrySmith", "misc/LeePerrySmith.obj", 4, 1_000_000)],
    "synthetic": [("LeePerrySmith", "misc/LeePerrySmith.obj", None, n) for n in (5000, 134000, 500000)],
}
# (vertices about, seconds, peak GB) of the performance issue, 2 cores, dense
TARGETS = ((134_000, 4.0, 0.8), (537_000, 12.0, 1.5), (1_000_000, 25.0, 3.0))
GROWTH_EXPONENT = 1.1
RESULT = "RESULT "


# ---------------------------------------------------------------- meshes

def make_mesh(V, F, n):
    """``n``-vertex version of a closed genus-0 head -> (V, F, how it was made)."""
    import fast_simplification
    import trimesh

    if n == len(V):
        return V, F, "original"
    how = []
    k = 0
    while len(V) < n:
        V, F = trimesh.remesh.subdivide_loop(V, F, iterations=1)
        k += 1
    if k:
        how.append(f"loop x{k}")
    if len(V) > n:
        V, F = fast_simplification.simplify(V, F, target_count=2 * n - 4)
        how.append("decimated")
    return np.ascontiguousarray(V, dtype=np.float64), np.ascontiguousarray(F, dtype=np.int64), " + ".join(how)


def build(name, rel, loops, target):
    """(V, F, how) of one row: a shared head, Loop-subdivided ``loops`` times, or (``loops`` None)
    decimated/subdivided to ``target`` vertices; with both, subdivided then decimated to ``target``."""
    import fast_simplification
    import trimesh
    from autobones.io.mesh import load_mesh

    V, F = load_mesh(DATA / rel)
    if loops is None:
        return make_mesh(V, F, target)
    if loops:
        V, F = trimesh.remesh.subdivide_loop(V, F, iterations=loops)
    how = f"loop x{loops}" if loops else "own"
    if target is not None and len(V) > target:
        V, F = fast_simplification.simplify(V, F, target_reduction=1.0 - target / len(V))
        how += " + decimated"
    return np.ascontiguousarray(V, dtype=np.float64), np.ascontiguousarray(F, dtype=np.int64), how


def stand_in_reference(V, F):
    """Canonical sample of the source head, used by ``orient`` when the built-in default
    head (``generic_rig/default_head.obj``) is not there. LeePerrySmith is +Y up, +Z front."""
    from autobones.orient import SAMPLE_COUNT
    from autobones.geometry.sample import sample_surface

    P, _, _ = sample_surface(V - V.mean(axis=0), F, SAMPLE_COUNT, seed=1)
    P = P - P.mean(axis=0)
    P /= np.sqrt((P ** 2).sum(axis=1).mean())
    P.setflags(write=False)
    return P


def default_head_present():
    from autobones.generic_rig import default_head_path

    return os.path.isfile(default_head_path())


# ---------------------------------------------------------------- workers (one run per process)

def rss_mb():
    """Peak RSS of this process so far (VmHWM), MB (1e6 bytes).

    Not ``getrusage(RUSAGE_SELF).ru_maxrss``: Linux carries that across fork + exec,
    so a worker would report at least the parent's RSS when it was started."""
    text = Path("/proc/self/status").read_text()
    return int(re.search(r"^VmHWM:\s+(\d+) kB", text, re.M).group(1)) * 1024 / 1e6


def worker_place(args):
    import logging

    import autobones
    import autobones.orient
    import autobones.placement.pipeline

    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("log: %(message)s"))
    logger = logging.getLogger("autobones")
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)
    if args.exact:
        autobones.placement.pipeline.PROXY_ABOVE = None
    if not default_head_present():
        from autobones.io.mesh import load_mesh

        ref = stand_in_reference(*load_mesh(SOURCE))
        autobones.orient.default_reference = lambda: ref
    before = rss_mb()
    profiler = None
    if args.profile:
        import cProfile

        profiler = cProfile.Profile()
        profiler.enable()
    t, c = time.perf_counter(), time.process_time()
    rig = autobones.place(args.mesh, density=args.density)
    total, cpu = time.perf_counter() - t, time.process_time() - c
    if profiler is not None:
        profiler.disable()
        profiler.dump_stats(args.profile)
    peak = rss_mb()
    sk = rig.skeleton
    out = dict(heads=sk.heads, tails=sk.tails, parents=np.asarray(sk.parents, dtype=np.int64),
               names=np.array(sk.names), size=rig.frame.size)
    if args.keep_weights:
        out["weights"] = rig.weights
    np.savez(args.bones, **out)
    print(RESULT + json.dumps({"timings": rig.timings, "total": total, "cpu": cpu, "rss_before": before,
                               "rss_peak": peak, "n_bones": len(sk)}), flush=True)


def bbw_handles(V, heads):
    """One handle vertex per bone: the nearest vertex to its head not taken by an earlier bone."""
    from scipy.spatial import cKDTree

    tree = cKDTree(V)
    k = min(len(V), len(heads) + 1)
    _, near = tree.query(heads, k=k)
    b, taken = [], set()
    for row in near:
        j = next(int(j) for j in row if int(j) not in taken)
        taken.add(j)
        b.append(j)
    return np.array(b, dtype=np.int64)


def worker_bbw(args):
    import igl

    mesh = np.load(args.mesh)
    V, F = mesh["V"], mesh["F"]
    heads = np.load(args.bones)["heads"]
    b = bbw_handles(V, heads)
    bc = np.eye(len(b))
    before = rss_mb()
    t, c = time.perf_counter(), time.process_time()
    W = igl.bbw(V, F, b, bc, partition_unity=False, max_iter=100)
    W = W / np.maximum(W.sum(axis=1, keepdims=True), 1e-300)
    total, cpu = time.perf_counter() - t, time.process_time() - c
    print(RESULT + json.dumps({"total": total, "cpu": cpu, "rss_before": before, "rss_peak": rss_mb(),
                               "n_bones": len(b), "min_weight": float(W.min())}), flush=True)


def run_blender(mesh_npz, bones_npz, out_dir, timeout):
    """Blender's bone heat on the mesh and bones -> (seconds or None, status, unweighted vertices)."""
    m, b = np.load(mesh_npz), np.load(bones_npz)
    job = os.path.join(out_dir, "blender_in.npz")
    np.savez(job, V=m["V"], F=m["F"], heads=b["heads"], tails=b["tails"], parents=b["parents"], names=b["names"])
    report = os.path.join(out_dir, "blender_report.json")
    env = dict(os.environ, PATH="/usr/bin:" + os.environ.get("PATH", ""))
    cmd = ["blender", "-b", "--factory-startup", "--python-exit-code", "1", "-P", str(HERE / "blender_heat.py"),
           "--", job, report]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return None, f"killed > {timeout:.0f} s", None
    if proc.returncode != 0 or not os.path.exists(report):
        return None, f"failed (exit {proc.returncode})", None
    rep = json.loads(Path(report).read_text())
    failed = "failed to find solution" in (proc.stdout + proc.stderr)
    return rep["seconds"], "failed to find solution" if failed else "ok", rep["unweighted_vertices"]


# ---------------------------------------------------------------- parent: run and watch a worker

def proc_rss_mb(pid):
    """(VmRSS, VmHWM) of a live process in MB, or (None, None)."""
    try:
        text = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return None, None
    vals = {k: int(v) * 1024 / 1e6 for k, v in re.findall(r"^(VmRSS|VmHWM):\s+(\d+) kB", text, re.M)}
    return vals.get("VmRSS"), vals.get("VmHWM")


def run_worker(cmd, timeout, mem_limit_mb, log_path):
    """Run ``cmd``; kill it past ``timeout`` s or ``mem_limit_mb``. -> (result dict or None, status, log text, hwm)."""
    with open(log_path, "w+") as err:
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=err, text=True)
        start, status, hwm = time.perf_counter(), "ok", 0.0
        while proc.poll() is None:
            rss, h = proc_rss_mb(proc.pid)
            hwm = max(hwm, h or 0.0)
            if rss is not None and rss > mem_limit_mb:
                status = f"killed > {mem_limit_mb / 1000:.0f} GB"
            elif time.perf_counter() - start > timeout:
                status = f"killed > {timeout:.0f} s"
            if status != "ok":
                proc.kill()
                proc.wait()
                break
            time.sleep(0.2)
        out = proc.stdout.read()
        proc.stdout.close()
        err.seek(0)
        log = err.read()
    result = None
    for line in out.splitlines():
        if line.startswith(RESULT):
            result = json.loads(line[len(RESULT):])
    if result is None and status == "ok":
        status = f"failed (exit {proc.returncode})"
    return result, status, log, hwm


def stages_from_log(log):
    return {m.group(1): float(m.group(2))
            for m in re.finditer(r"^log: (\w+)\s+([\d.]+) s$", log, re.M) if m.group(1) in STAGES}


def best_of(cmd, args, tmp, label):
    """Run a place worker up to ``--repeat`` times (once when a run takes >= 10 s): the fastest result."""
    best, runs = None, 0
    while True:
        res, status, log, hwm = run_worker(cmd, args.timeout, args.mem_limit * 1000, os.path.join(tmp, "worker.log"))
        runs += 1
        if res is None:
            print(f"  {label}: {status}; stages done: {stages_from_log(log)}\n{log[-2000:]}", flush=True)
            return {"status": status, "timings": stages_from_log(log), "hwm": hwm, "runs": runs}
        print(f"  {label} run {runs}: {res['total']:.2f} s, peak {res['rss_peak']:.0f} MB", flush=True)
        if best is None or res["total"] < best["total"]:
            best = res
        if runs >= args.repeat or res["total"] >= 10.0:
            return dict(best, status="ok", runs=runs)


def compare(default_npz, exact_npz):
    """Weight and joint differences of the default result from the exact one."""
    a, b = np.load(default_npz), np.load(exact_npz)
    d = np.abs(a["weights"] - b["weights"])
    joints = np.linalg.norm(a["heads"] - b["heads"], axis=1).max() / float(b["size"])
    return {"dw_max": float(d.max()), "dw_mean": float(d.mean()),
            "dw_p999": float(np.quantile(d.max(axis=1), 0.999)), "joint": float(joints)}


# ---------------------------------------------------------------- table

def fmt(x, spec=".2f", missing="-"):
    return missing if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, spec)


def print_table(rows, density):
    head = ["mesh", "how", "vertices", "runs", *STAGES, "total s", "CPU s", "peak MB", "t/v",
            "exact s", "exact weights s", "speed-up", "max dW", "mean dW", "p99.9 dW", "joint d",
            "BBW s", "Blender s (unweighted)"]
    base = next((r for r in sorted(rows, key=lambda r: r["n"]) if r.get("total")), None)
    print(f"\nautobones.place(path, density={density!r}); wall seconds; t/v = time per vertex over that of the "
          f"smallest row; exact = the proxy switched off; dW = |default - exact| weights; joint d = largest "
          f"joint difference in head sizes\n")
    print("| " + " | ".join(head) + " |")
    print("|" + "|".join("---" if i < 2 else "---:" for i in range(len(head))) + "|")
    for r in rows:
        st, ex, c = r.get("timings", {}), r.get("exact") or {}, r.get("cmp") or {}
        ratio = (r["total"] / r["n"]) / (base["total"] / base["n"]) if r.get("total") and base else None
        peak = fmt(r.get("rss_peak"), ".0f") if r.get("rss_peak") else (f">{r['hwm']:.0f}" if r.get("hwm") else "-")
        total = fmt(r.get("total")) if r.get("status") == "ok" else r.get("status", "-")
        speed = ex["total"] / r["total"] if ex.get("total") and r.get("total") else None
        blender = "-"
        if r.get("blender_status"):
            blender = (fmt(r.get("blender")) + f" ({r['blender_unweighted']:,})" if r.get("blender") is not None
                       else r["blender_status"])
            if r["blender_status"] not in ("ok",) and r.get("blender") is not None:
                blender += f" {r['blender_status']}"
        print("| " + " | ".join([
            r["name"], r["how"], f"{r['n']:,}", str(r.get("runs", "-")), *[fmt(st.get(s)) for s in STAGES], total,
            fmt(r.get("cpu")), peak, fmt(ratio), fmt(ex.get("total")) if ex.get("status", "ok") == "ok" else ex["status"],
            fmt(ex.get("timings", {}).get("weights")), fmt(speed, ".1f"), fmt(c.get("dw_max"), ".3f"),
            fmt(c.get("dw_mean"), ".1e"), fmt(c.get("dw_p999"), ".3f"), fmt(c.get("joint"), ".1e"),
            fmt(r.get("bbw")) if r.get("bbw_status", "ok") == "ok" else r["bbw_status"], blender]) + " |")


def print_targets(rows):
    done = sorted((r for r in rows if r.get("total")), key=lambda r: r["n"])
    print("\nTargets (performance issue; 2 cores, dense):")
    for n, secs, gb in TARGETS:
        near = [r for r in done if abs(r["n"] - n) / n < 0.2]
        for r in near:
            peak = (r.get("rss_peak") or 0) / 1000
            ok = r["total"] <= secs and peak <= gb
            print(f"  {r['name']} {r['how']} ({r['n']:,}): {r['total']:.2f} s (<= {secs:.0f}), {peak:.2f} GB "
                  f"(<= {gb}) -> {'MET' if ok else 'NOT MET'}")
    large = [r for r in done if r["n"] >= 100_000]
    if len(large) >= 2:
        a, b = large[0], large[-1]
        p = math.log(b["total"] / a["total"]) / math.log(b["n"] / a["n"])
        print(f"  growth {a['n']:,} -> {b['n']:,}: exponent {p:.2f} (<= {GROWTH_EXPONENT}) -> "
              f"{'MET' if p <= GROWTH_EXPONENT else 'NOT MET'}")
        for a, b in zip(large, large[1:]):
            if b["n"] > a["n"]:
                p = math.log(b["total"] / a["total"]) / math.log(b["n"] / a["n"])
                print(f"    {a['n']:>9,} -> {b['n']:>9,}: time x{b['total'] / a['total']:.2f} for vertices "
                      f"x{b['n'] / a['n']:.2f} (exponent {p:.2f})")


# ---------------------------------------------------------------- main

def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--set", default="scans,large", help="comma-separated: scans, large, synthetic")
    ap.add_argument("--density", default="dense", help="sparse, medium, dense or a bone count")
    ap.add_argument("--repeat", type=int, default=3, help="runs per row when a run takes < 10 s; fastest kept")
    ap.add_argument("--exact-max", type=int, default=250_000, help="largest vertex count also run without the proxy")
    ap.add_argument("--bbw-max", type=int, default=10_000, help="largest vertex count weighted with igl.bbw")
    ap.add_argument("--blender-max", type=int, default=600_000, help="largest vertex count given to Blender")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds before a run is killed")
    ap.add_argument("--bbw-timeout", type=float, default=180.0, help="seconds before a BBW run is killed")
    ap.add_argument("--blender-timeout", type=float, default=300.0, help="seconds before a Blender run is killed")
    ap.add_argument("--mem-limit", type=float, default=16.0, help="GB of RSS before a run is killed")
    ap.add_argument("--profile", metavar="DIR", help="cProfile each default place run into DIR/place_<n>.pstats")
    ap.add_argument("--worker", choices=["place", "bbw"], help=argparse.SUPPRESS)
    ap.add_argument("--mesh", help=argparse.SUPPRESS)
    ap.add_argument("--bones", help=argparse.SUPPRESS)
    ap.add_argument("--exact", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--keep-weights", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--profile-out", dest="profile_out", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)

    if args.worker:
        args.profile = args.profile_out
        return worker_place(args) if args.worker == "place" else worker_bbw(args)

    from autobones.io.obj import write_obj

    specs = [spec for name in args.set.split(",") for spec in SETS[name.strip()]]
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2 ** 30
    print(f"autobones place benchmark, {datetime.datetime.now():%Y-%m-%d %H:%M}")
    print(f"machine: {os.cpu_count()} cores ({cpu}), {mem:.0f} GiB, load average {os.getloadavg()[0]:.1f}; "
          f"Python {platform.python_version()}, numpy {np.__version__}")
    git = lambda *a: subprocess.run(["git", "-C", str(HERE.parent), *a], capture_output=True, text=True).stdout.strip()
    dirty = git("diff", "--name-only", "HEAD", "--", "autobones", "generic_rig").split()
    print(f"autobones at {git('rev-parse', '--short', 'HEAD') or '?'}"
          f"{' + uncommitted changes in ' + ', '.join(dirty) if dirty else ''}; sets {args.set}; density {args.density}")
    blender = shutil.which("blender", path="/usr/bin:" + os.environ.get("PATH", ""))
    if not blender:
        print("note: blender is not installed: no Blender column")
    if args.profile:
        Path(args.profile).mkdir(parents=True, exist_ok=True)

    rows = []
    with tempfile.TemporaryDirectory(prefix="autobones-bench-") as tmp:
        for i, (name, rel, loops, target) in enumerate(specs):
            t = time.perf_counter()
            V, F, how = build(name, rel, loops, target)
            stem = os.path.join(tmp, f"mesh_{i}")
            write_obj(stem + ".obj", V, F)
            np.savez(stem + ".npz", V=V, F=F)
            print(f"[{name} {how}: {len(V):,} vertices, {len(F):,} faces, built in {time.perf_counter() - t:.1f} s]",
                  flush=True)
            rows.append({"name": name, "how": how, "n": len(V), "faces": len(F), "stem": stem})
            del V, F

        for r in rows:
            label = f"{r['name']} {r['how']} {r['n']:,}"
            base = [sys.executable, os.path.abspath(__file__), "--worker", "place", "--mesh", r["stem"] + ".obj",
                    "--density", args.density]
            exact = r["n"] <= args.exact_max
            prof = ["--profile-out", os.path.join(args.profile, f"place_{r['n']}.pstats")] if args.profile else []
            r.update(best_of(base + ["--bones", r["stem"] + "_bones.npz"] + (["--keep-weights"] if exact else []) + prof,
                             args, tmp, "place " + label))
            if r["status"] != "ok":
                continue
            if exact:
                r["exact"] = best_of(base + ["--bones", r["stem"] + "_exact.npz", "--exact", "--keep-weights"],
                                     args, tmp, "exact " + label)
                if r["exact"]["status"] == "ok":
                    r["cmp"] = compare(r["stem"] + "_bones.npz", r["stem"] + "_exact.npz")
                    print(f"  difference from exact: {r['cmp']}", flush=True)
            if r["n"] <= args.bbw_max:
                cmd = [sys.executable, os.path.abspath(__file__), "--worker", "bbw", "--mesh", r["stem"] + ".npz",
                       "--bones", r["stem"] + "_bones.npz"]
                res, status, log, _ = run_worker(cmd, args.bbw_timeout, args.mem_limit * 1000,
                                                 os.path.join(tmp, "worker.log"))
                r["bbw_status"] = status
                if res is not None:
                    r["bbw"] = res["total"]
                print(f"  bbw {label}: {status} {fmt(r.get('bbw'))} s", flush=True)
            if blender and r["n"] <= args.blender_max:
                secs, status, unweighted = run_blender(r["stem"] + ".npz", r["stem"] + "_bones.npz", tmp,
                                                       args.blender_timeout)
                r.update(blender=secs, blender_status=status, blender_unweighted=unweighted)
                print(f"  blender {label}: {status} {fmt(secs)} s, unweighted {unweighted}", flush=True)

    print_table(rows, args.density)
    print_targets(rows)
    if args.profile:
        print_profile(next(Path(args.profile).glob("*.pstats")))
    return 0


def print_profile(path, top=15):
    import pstats

    print(f"\nprofile {path} (top {top} by own time)")
    pstats.Stats(str(path)).sort_stats("tottime").print_stats(top)


if __name__ == "__main__":
    sys.exit(main())
