"""Which sparse factorisation for the symmetric positive definite systems: measured on real scans.

Run by hand, not by the tests::

    python benchmarks/solver.py                 # ICT identity000 (26.7k vertices) and its Loop subdivisions (105k, 420k)
    python benchmarks/solver.py --quick         # 26.7k and 105k only
    python benchmarks/solver.py --no-calls      # the systems only, not whole place / transfer calls

Every SPD system in autobones (bone heat, attribute inpainting, heat diffusion of the rig builder,
the expression model's smoothing, the correspondence fit) goes through
``autobones.geometry.laplacian.factor_spd``, which factors once and solves every right-hand side.
Two SuperLU orderings are compared here, and CHOLMOD when scikit-sparse (the ``[cholmod]`` extra)
is installed:

- ``colamd``: SuperLU's default column ordering (what ``factor_spd`` uses);
- ``mmd_symmetric``: minimum degree on A + Aᵀ, symmetric mode, no pivoting (what the correspondence
  fit uses on its coarse copy, and what was proposed for every system).

1. **Systems**: the bone-heat matrix ``L + diag(M h)`` of the whole mesh (intrinsic Laplacian,
   ``h`` about what ``place`` uses), welded as ``place`` welds it and unwelded (the structure of
   systems built on raw meshes, whose seams leave parts touching without sharing vertices),
   factored and solved for 34 right-hand sides (``dense``'s bone count); best of ``--repeat``;
   factor seconds, solve seconds, fill (nonzeros of the factors).
2. **Whole calls**: ``place(density="dense")`` and ``transfer`` with every ``factor_spd`` caller
   switched to one SuperLU ordering (CHOLMOD off; the correspondence fit keeps its own), alternately, best of
   ``--repeat``; the largest difference between the two results shows they agree to round-off.

Meshes are real scans, not smooth synthetic ones: the ICT-FaceKit identity000 head (26,719
vertices, 56 parts: skin, eyes, teeth, gums), and the same head Loop-subdivided once and twice
(trimesh), its landmarks moved to the closest point of the subdivided surface.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def meshes(levels):
    """[(label, V, F, landmarks)] for ICT identity000 and its Loop subdivisions."""
    import trimesh

    from autobones.geometry.closest import closest_points
    from autobones.io.landmarks import read_landmarks
    from autobones.io.mesh import load_mesh

    V, F = load_mesh(DATA / "ict" / "identity000.obj")
    lm = read_landmarks(DATA / "ict" / "identity000.landmarks.json")
    out = []
    for k in range(levels + 1):
        if k:
            V, F = trimesh.remesh.subdivide_loop(V, F, iterations=1)
            V, F = np.ascontiguousarray(V, dtype=np.float64), np.ascontiguousarray(F, dtype=np.int64)
            names = sorted(lm)
            lm = dict(zip(names, closest_points(np.array([lm[n] for n in names]), V, F)[0]))
        out.append((f"ICT identity000{' loop x%d' % k if k else ''}", V, F, dict(lm)))
    return out


def bone_heat_system(V, F, welded):
    """The bone-heat matrix ``L + diag(M h)`` of the whole mesh in head sizes, welded as ``place``
    welds it (or not: the structure of the systems built on raw, unwelded meshes)."""
    from autobones.geometry.laplacian import laplacian
    from autobones.geometry.topology import weld

    V = V / np.ptp(V, axis=0).max()
    if welded:
        V, F, _ = weld(V, F, 1e-6)
        used = np.zeros(len(V), dtype=bool)
        used[F.ravel()] = True
        V, F = V[used], (np.cumsum(used) - 1)[F]
    L, M = laplacian(V, F)
    return (L + sp.diags(50.0 * M.diagonal())).tocsc()


def system_rows(label, V, F, repeat, methods, welded, slow):
    """Factor and solve the bone-heat system of the whole mesh with each method."""
    from scipy.sparse.linalg import splu

    from autobones.geometry.laplacian import ORDERINGS

    A = bone_heat_system(V, F, welded)
    b = np.random.default_rng(0).random((A.shape[0], 34))
    label = f"{label} ({'welded' if welded else 'unwelded'})"
    rows = []
    for method in methods:
        if method == "mmd_symmetric" and not welded and A.shape[0] > 200_000 and not slow:
            rows.append((label, A.shape[0], method + " (skipped: minutes; --slow)", np.nan, np.nan, 0, np.nan))
            continue
        best = None
        for _ in range(repeat):
            t0 = time.perf_counter()
            if method == "cholmod":
                from sksparse.cholmod import cholesky

                factor = cholesky(A)
                fill = factor.L().nnz
                solve = factor
            else:
                lu = splu(A, **ORDERINGS[method])
                fill = lu.L.nnz + lu.U.nnz
                solve = lu.solve
            t1 = time.perf_counter()
            x = solve(b)
            t2 = time.perf_counter()
            run = (t1 - t0, t2 - t1, fill, float(np.abs(A @ x - b).max()))
            best = run if best is None or run[0] + run[1] < best[0] + best[1] else best
        rows.append((label, A.shape[0], method) + best)
        print(f"  {label}: {method} {best[0]:.2f} s + {best[1]:.2f} s", file=sys.stderr, flush=True)
    return rows


class Ordering:
    """Context manager: every loaded module's ``factor_spd`` (but the correspondence fit's) with one ordering."""

    def __init__(self, ordering):
        self.ordering, self.saved = ordering, []

    def __enter__(self):
        import autobones.geometry.laplacian as lap

        def factor(A, ordering="colamd", use_cholmod=None):
            return lap.factor_spd(A, ordering=self.ordering, use_cholmod=False)

        for name, module in sorted(sys.modules.items()):
            if (name.startswith("autobones") and not name.endswith("laplacian")
                    and not name.endswith("correspondence") and hasattr(module, "factor_spd")):
                self.saved.append((module, module.factor_spd))
                module.factor_spd = factor
        return self

    def __exit__(self, *exc):
        for module, f in self.saved:
            module.factor_spd = f


def call_rows(label, V, F, lm, repeat):
    import autobones

    rows = []
    for what, fn in (("place dense", lambda: autobones.place((V, F), density="dense")),
                     ("transfer", lambda: autobones.transfer((V, F), landmarks=lm))):
        best, result = {}, {}
        for _ in range(repeat):
            for ordering in ("colamd", "mmd_symmetric"):
                with Ordering(ordering):
                    t0 = time.perf_counter()
                    result[ordering] = fn()
                    dt = time.perf_counter() - t0
                best[ordering] = min(dt, best.get(ordering, np.inf))
        a, b = result["colamd"], result["mmd_symmetric"]
        diff = float(np.abs(a.weights - b.weights).max())
        for k in a.fields:
            diff = max(diff, float(np.abs(np.asarray(a.fields[k], float) - np.asarray(b.fields[k], float)).max()))
        rows.append((label, len(V), what, best["colamd"], best["mmd_symmetric"], diff))
        print(f"  {label}: {what} done", file=sys.stderr, flush=True)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="26.7k and 105k vertices only")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--no-calls", action="store_true", help="the systems only")
    ap.add_argument("--slow", action="store_true", help="also mmd_symmetric on the unwelded 420k system")
    args = ap.parse_args(argv)
    methods = ["colamd", "mmd_symmetric"]
    try:
        import sksparse.cholmod  # noqa: F401  (only whether it is there)

        methods.append("cholmod")
    except ImportError:
        pass

    systems, calls = [], []
    for label, V, F, lm in meshes(1 if args.quick else 2):
        for welded in (True, False):
            systems += system_rows(label, V, F, args.repeat, methods, welded, args.slow)
        if not args.no_calls:
            calls += call_rows(label, V, F, lm, args.repeat)

    print("\n| mesh | vertices | method | factor s | solve 34 rhs s | total s | fill (nnz, M) | max residual |")
    print("|---|---:|---|---:|---:|---:|---:|---:|")
    for label, n, method, tf, ts, fill, res in systems:
        print(f"| {label} | {n:,} | {method} | {tf:.2f} | {ts:.2f} | {tf + ts:.2f} | {fill / 1e6:.1f} | {res:.0e} |")
    if calls:
        print("\n| mesh | vertices | call | colamd s | mmd_symmetric s | mmd / colamd | max difference |")
        print("|---|---:|---|---:|---:|---:|---:|")
        for label, n, what, a, b, d in calls:
            print(f"| {label} | {n:,} | {what} | {a:.2f} | {b:.2f} | {b / a:.2f}x | {d:.1e} |")


if __name__ == "__main__":
    main()
