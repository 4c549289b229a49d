"""Benchmark ``autobones.place`` from 5k to 500k vertices against libigl's bounded biharmonic weights.

Run by hand, not by the tests::

    python benchmarks/place.py                       # 5k, 20k, 50k, 134k, 500k at dense
    python benchmarks/place.py --quick               # 5k and 20k only (smoke check)
    python benchmarks/place.py --sizes 5000,134000 --density medium --profile /tmp/prof

It measures the targets of the performance issue (134k
vertices at ``dense`` in <= 5 s and <= 1 GB on a 2-core machine, near-linear
growth to 500k) and prints whether each is met.

Meshes: one real head, ``../shared/data/misc/LeePerrySmith.obj`` (8,838
vertices, closed, genus 0). Smaller sizes are quadric-decimated with
``fast_simplification``; larger ones are Loop-subdivided
(``trimesh.remesh.subdivide_loop``) until they have at least the target, then
decimated to it. A closed genus-0 mesh has 2n - 4 triangles, so asking for that
many faces gives exactly n vertices. Meshes are built once, before any timing,
and passed to ``autobones.place((V, F), density=...)`` as arrays.

Each run happens in a fresh worker process (this script with ``--worker``):

- stage times are ``Rig.timings`` (load, orient, segment, facial, weights);
  "total" is the wall time of the ``place`` call, "CPU" its CPU time
  (``time.process_time``, all threads): on a loaded machine wall time grows
  with other people's jobs, CPU time much less;
- peak memory is the worker's own peak resident set size, ``VmHWM`` of
  ``/proc/self/status``, read when ``place`` returns. It includes the
  interpreter, numpy/scipy and the input arrays; the peak before ``place`` is
  printed as well. (Not ``getrusage(RUSAGE_SELF or RUSAGE_CHILDREN).ru_maxrss``:
  Linux carries it across fork + exec, so every worker would report at least the
  parent's RSS, which holds the 500k mesh. Not tracemalloc: it does not see
  memory that C extensions such as SuperLU allocate.)
- a run is killed when it passes ``--timeout`` seconds or ``--mem-limit`` GB
  of RSS (the parent watches ``/proc/<pid>/status``); the stages it finished
  are still reported, from the library's log.

Baseline, same run, same bones: the skeleton of each ``place`` result is
weighted again with ``igl.bbw`` (bounded biharmonic weights, Jacobson et al.
2011) on the same surface mesh, one point handle per bone at the vertex nearest
to the bone's head, fixed to 1 for its bone and 0 for the others; rows are then
normalised to sum to one. Only the ``igl.bbw`` call and that normalisation are
timed, and only up to ``--bbw-max`` vertices (BBW's active-set QP grows fast).

Ratios: "t/v ratio" is the time per vertex over the time per vertex of the
smallest size of the same run (1.0 = linear); "weights/BBW" is autobones'
weights stage over BBW's time on the same mesh and bones. On a shared, noisy
machine each size is repeated (``--repeat``, runs shorter than 10 s only) and
the fastest run is kept.
"""
from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
SOURCE = DATA / "misc" / "LeePerrySmith.obj"
STAGES = ("load", "orient", "segment", "facial", "weights")
SIZES = (5000, 20000, 50000, 134000, 500000)
QUICK = (5000, 20000)
TARGET_N, TARGET_S, TARGET_BYTES = 134000, 5.0, 1e9
LINEAR_EXPONENT = 1.2  # "near-linear": time grows at most like n**1.2 between the two largest sizes
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

    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("log: %(message)s"))
    logger = logging.getLogger("autobones")
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)

    if not default_head_present():
        from autobones.io.mesh import load_mesh

        ref = stand_in_reference(*load_mesh(SOURCE))
        autobones.orient.default_reference = lambda: ref
    mesh = np.load(args.mesh)
    V, F = mesh["V"], mesh["F"]
    before = rss_mb()
    profiler = None
    if args.profile:
        import cProfile

        profiler = cProfile.Profile()
        profiler.enable()
    t, c = time.perf_counter(), time.process_time()
    rig = autobones.place((V, F), density=args.density)
    total, cpu = time.perf_counter() - t, time.process_time() - c
    if profiler is not None:
        profiler.disable()
        profiler.dump_stats(args.profile)
    peak = rss_mb()
    np.savez(args.bones, heads=rig.skeleton.heads)
    print(RESULT + json.dumps({"timings": rig.timings, "total": total, "cpu": cpu, "rss_before": before, "rss_peak": peak,
                               "n_bones": len(rig.skeleton)}), flush=True)


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


# ---------------------------------------------------------------- table

def fmt(x, spec=".2f", missing="-"):
    return missing if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, spec)


def print_table(rows, density):
    head = ["vertices", "faces", "mesh", "runs", *STAGES, "total s", "CPU s", "peak RSS MB", "RSS before", "t/v ratio",
            "BBW s", "weights/BBW", "BBW RSS MB"]
    base = next((r for r in rows if r.get("total")), None)
    lines = []
    for r in rows:
        st = r.get("timings", {})
        ratio = None
        if r.get("total") and base:
            ratio = (r["total"] / r["n"]) / (base["total"] / base["n"])
        w_bbw = st.get("weights") / r["bbw"] if r.get("bbw") and st.get("weights") is not None else None
        total = fmt(r.get("total")) if r["status"] == "ok" else f"{r['status']}"
        lines.append([f"{r['n']:,}", f"{r['faces']:,}", r["how"], str(r.get("runs", 1)),
                      *[fmt(st.get(s)) for s in STAGES], total, fmt(r.get("cpu")),
                      fmt(r.get("rss_peak"), ".0f") if r.get("rss_peak") else f">{r.get('hwm', 0):.0f}" if r.get("hwm") else "-",
                      fmt(r.get("rss_before"), ".0f"), fmt(ratio), fmt(r.get("bbw")) if r.get("bbw_status", "ok") == "ok"
                      else r["bbw_status"], fmt(w_bbw, ".3f"), fmt(r.get("bbw_rss"), ".0f")])
    print(f"\nautobones.place(density={density!r}); wall seconds (CPU s: CPU time of the place call, "
          f"all threads; less sensitive to other load); t/v ratio = wall time per vertex / that of the "
          f"{rows[0]['n']:,}-vertex run\n")
    print("| " + " | ".join(head) + " |")
    print("|" + "|".join("---:" if i not in (2,) else "---" for i in range(len(head))) + "|")
    for line in lines:
        print("| " + " | ".join(line) + " |")


def print_targets(rows, density):
    by_n = {r["n"]: r for r in rows}
    print("\nTargets (issue): 134k vertices at dense in <= 5 s and <= 1 GB on 2 cores; near-linear to 500k")
    r = by_n.get(TARGET_N)
    if r is None:
        print(f"  134k: not in this run (--sizes has no {TARGET_N})")
    else:
        note = "" if density == "dense" else f" (measured at {density!r}, the target is for 'dense')"
        if r.get("total") is not None:
            print(f"  134k time   : {r['total']:.2f} s vs <= {TARGET_S:.0f} s -> "
                  f"{'MET' if r['total'] <= TARGET_S else 'NOT MET'} ({r['total'] / TARGET_S:.1f}x the target){note}")
        else:
            print(f"  134k time   : {r['status']} -> NOT MET{note}")
        peak = r.get("rss_peak") or r.get("hwm")
        if peak:
            print(f"  134k memory : {peak:.0f} MB peak RSS vs <= {TARGET_BYTES / 1e6:.0f} MB -> "
                  f"{'MET' if peak * 1e6 <= TARGET_BYTES else 'NOT MET'}{note}")
    done = [r for r in rows if r.get("total")]
    if len(done) >= 2:
        for a, b in zip(done, done[1:]):
            grow, size = b["total"] / a["total"], b["n"] / a["n"]
            print(f"  growth {a['n']:>7,} -> {b['n']:>7,}: time x{grow:.2f} for vertices x{size:.2f} "
                  f"(exponent {math.log(grow) / math.log(size):.2f}; linear x{size:.2f}, quadratic x{size ** 2:.1f})")
    big = by_n.get(500000)
    if big is not None and r is not None:
        if big.get("total") and r.get("total"):
            p = math.log(big["total"] / r["total"]) / math.log(500000 / TARGET_N)
            print(f"  near-linear 134k -> 500k: exponent {p:.2f} vs <= {LINEAR_EXPONENT} -> "
                  f"{'MET' if p <= LINEAR_EXPONENT else 'NOT MET'}")
        else:
            print(f"  near-linear 134k -> 500k: 500k run {big['status']} -> NOT MET")


def print_profile(path, top=15):
    import pstats

    print(f"\nprofile {path} (top {top} by own time)")
    pstats.Stats(str(path)).sort_stats("tottime").print_stats(top)


# ---------------------------------------------------------------- main

def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default=",".join(map(str, SIZES)), help="vertex counts, comma separated")
    ap.add_argument("--density", default="dense", help="sparse, medium, dense or a bone count")
    ap.add_argument("--quick", action="store_true", help="only 5k and 20k (smoke check)")
    ap.add_argument("--repeat", type=int, default=3, help="runs per size when a run takes < 10 s; fastest kept")
    ap.add_argument("--bbw-max", type=int, default=20000, help="largest vertex count weighted with igl.bbw")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds before a run is killed")
    ap.add_argument("--bbw-timeout", type=float, default=180.0, help="seconds before a BBW run is killed")
    ap.add_argument("--mem-limit", type=float, default=16.0, help="GB of RSS before a run is killed")
    ap.add_argument("--profile", metavar="DIR", help="cProfile each place run into DIR/place_<n>.pstats")
    ap.add_argument("--worker", choices=["place", "bbw"], help=argparse.SUPPRESS)
    ap.add_argument("--mesh", help=argparse.SUPPRESS)
    ap.add_argument("--bones", help=argparse.SUPPRESS)
    ap.add_argument("--profile-out", dest="profile_out", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)

    if args.worker:
        args.profile = args.profile_out
        return worker_place(args) if args.worker == "place" else worker_bbw(args)

    sizes = list(QUICK) if args.quick else sorted(int(s.replace("_", "")) for s in args.sizes.split(","))
    from autobones.io.mesh import load_mesh
    import autobones.placement.facial_bones

    n_bones = autobones.placement.facial_bones.bone_count(args.density)
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2 ** 30
    print(f"autobones place benchmark, {datetime.datetime.now():%Y-%m-%d %H:%M}")
    print(f"machine: {os.cpu_count()} cores ({cpu}), {mem:.0f} GiB, load average {os.getloadavg()[0]:.1f}; "
          f"Python {platform.python_version()}, numpy {np.__version__}")
    repo = Path(__file__).resolve().parents[1]
    git = lambda *a: subprocess.run(["git", "-C", str(repo), *a], capture_output=True, text=True).stdout.strip()
    dirty = git("diff", "--name-only", "HEAD", "--", "autobones", "generic_rig").split()
    print(f"autobones at {git('rev-parse', '--short', 'HEAD') or '?'}"
          f"{' + uncommitted changes in ' + ', '.join(dirty) if dirty else ''}")
    print(f"source: {SOURCE.relative_to(DATA.parent.parent)}; density {args.density!r} "
          f"({n_bones} facial bones + head + neck)")
    if not default_head_present():
        print("note: generic_rig/default_head.obj is missing; orient scores orientations against a stand-in "
              "reference sample of the source head (same sample size, so the same work)")
    if args.profile:
        Path(args.profile).mkdir(parents=True, exist_ok=True)

    V0, F0 = load_mesh(SOURCE)
    rows = []
    with tempfile.TemporaryDirectory(prefix="autobones-bench-") as tmp:
        for n in sizes:
            t = time.perf_counter()
            V, F, how = make_mesh(V0, F0, n)
            mesh_path = os.path.join(tmp, f"mesh_{n}.npz")
            np.savez(mesh_path, V=V, F=F)
            print(f"[{len(V):,} vertices, {len(F):,} faces: {how}, built in {time.perf_counter() - t:.1f} s]",
                  flush=True)
            rows.append({"n": len(V), "faces": len(F), "how": how, "mesh": mesh_path,
                         "bones": os.path.join(tmp, f"bones_{n}.npz")})
        del V0, F0, V, F

        for r in rows:
            best, runs = None, 0
            while True:
                prof = os.path.join(args.profile, f"place_{r['n']}.pstats") if args.profile else None
                cmd = [sys.executable, os.path.abspath(__file__), "--worker", "place", "--mesh", r["mesh"],
                       "--bones", r["bones"], "--density", args.density] + (["--profile-out", prof] if prof else [])
                res, status, log, hwm = run_worker(cmd, args.timeout, args.mem_limit * 1000,
                                                   os.path.join(tmp, "worker.log"))
                runs += 1
                if res is None:
                    r.update(status=status, timings=stages_from_log(log), hwm=hwm, runs=runs)
                    print(f"  place {r['n']:>7,}: {status}; stages done: {r['timings']}\n{log[-2000:]}", flush=True)
                    break
                print(f"  place {r['n']:>7,} run {runs}: {res['total']:.2f} s, peak {res['rss_peak']:.0f} MB",
                      flush=True)
                if best is None or res["total"] < best["total"]:
                    best = res
                if runs >= args.repeat or res["total"] >= 10.0:
                    break
            if best is not None:
                r.update(best, status="ok", runs=runs)
            if r["status"] == "ok" and r["n"] <= args.bbw_max:
                cmd = [sys.executable, os.path.abspath(__file__), "--worker", "bbw", "--mesh", r["mesh"],
                       "--bones", r["bones"]]
                bbw_runs = 1 if args.repeat <= 1 else None
                times = []
                while True:
                    res, status, log, _ = run_worker(cmd, args.bbw_timeout, args.mem_limit * 1000,
                                                     os.path.join(tmp, "worker.log"))
                    if res is None:
                        r["bbw_status"] = status
                        print(f"  bbw   {r['n']:>7,}: {status}\n{log[-2000:]}", flush=True)
                        break
                    times.append(res["total"])
                    r.update(bbw=min(times), bbw_rss=res["rss_peak"], bbw_status="ok")
                    print(f"  bbw   {r['n']:>7,} run {len(times)}: {res['total']:.2f} s, "
                          f"peak {res['rss_peak']:.0f} MB", flush=True)
                    if len(times) >= (bbw_runs or args.repeat) or res["total"] >= 10.0:
                        break

    print_table(rows, args.density)
    print_targets(rows, args.density)
    if args.profile:
        for r in rows:
            path = Path(args.profile) / f"place_{r['n']}.pstats"
            if r["n"] >= TARGET_N and path.exists():
                print_profile(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
