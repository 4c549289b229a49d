"""The sparse solver change, measured: ``place`` and ``transfer`` with the old and the new solver, same run.

Run by hand, not by the tests::

    python benchmarks/solver.py               # ICT identity000 (26.7k vertices) and its Loop subdivisions (105k, 419k)
    python benchmarks/solver.py --quick       # 26.7k only

Every symmetric positive definite system in autobones (bone heat, attribute inpainting, heat
diffusion of the generic rig's fields, the expression model's smoothing) now goes through
``autobones.geometry.laplacian.factor_spd``: SuperLU in symmetric mode with a minimum-degree
ordering of A + Aᵀ (``MMD_AT_PLUS_A``), factored once per matrix. Before, those systems were
factored by SuperLU with its default COLAMD column ordering, and the heat diffusion of the rig
builder by ``spsolve`` (COLAMD, one factorisation per call). The correspondence fit already used
the symmetric ordering and is left as it is in both runs.

"old" here replaces ``factor_spd`` in every module that uses it (except the correspondence fit)
by ``splu(A, permc_spec="COLAMD").solve``; "new" is the code as it is. The same meshes, bones and
landmarks go through both, alternately, ``--repeat`` times; the fastest of each is kept. Printed:
the weights stage of ``place`` (``Rig.timings``), the whole ``place`` and ``transfer`` calls, the
ratio old / new, and the largest difference between the two results (skin weights; transferred
fields) to show the orderings agree to round-off.

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
from scipy.sparse import csc_matrix
from scipy.sparse.linalg import splu

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def colamd_factor(A, use_cholmod=None):
    """The old factorisation: SuperLU with its default COLAMD ordering."""
    return splu(csc_matrix(A), permc_spec="COLAMD").solve


def patched_modules():
    """Every loaded autobones module that calls ``factor_spd`` (the correspondence fit excluded)."""
    return [m for name, m in sorted(sys.modules.items())
            if name.startswith("autobones") and getattr(m, "factor_spd", None) is not None
            and not name.endswith("correspondence")]


class Solver:
    """Context manager: run with the old (COLAMD) or the new factorisation."""

    def __init__(self, which):
        self.which, self.saved = which, []

    def __enter__(self):
        if self.which == "old":
            for m in patched_modules():
                self.saved.append((m, m.factor_spd))
                m.factor_spd = colamd_factor
        return self

    def __exit__(self, *exc):
        for m, f in self.saved:
            m.factor_spd = f


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
            C = closest_points(np.array([lm[n] for n in names]), V, F)[0]
            lm = dict(zip(names, C))
        out.append((f"ICT identity000{' loop x%d' % k if k else ''}", V, F, dict(lm)))
    return out


def run(fn, which, repeat):
    best, result = None, None
    for _ in range(repeat):
        with Solver(which):
            t = time.perf_counter()
            result = fn()
            dt = time.perf_counter() - t
        best = dt if best is None else min(best, dt)
    return best, result


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="the 26.7k head only")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--no-transfer", action="store_true")
    args = ap.parse_args(argv)

    import autobones

    rows = []
    for label, V, F, lm in meshes(0 if args.quick else 2):
        n = len(V)
        place_fn = lambda: autobones.place((V, F), density="dense")  # noqa: E731
        (t_old, r_old), (t_new, r_new) = run(place_fn, "old", args.repeat), run(place_fn, "new", args.repeat)
        w_old, w_new = r_old.timings["weights"], r_new.timings["weights"]
        diff = float(np.abs(r_old.weights - r_new.weights).max())
        rows.append((label, n, "place dense: weights stage", w_old, w_new, diff))
        rows.append((label, n, "place dense: whole call", t_old, t_new, diff))
        print(f"  {label}: place done", file=sys.stderr, flush=True)
        if args.no_transfer:
            continue
        tr_fn = lambda: autobones.transfer((V, F), landmarks=lm)  # noqa: E731
        (t_old, r_old), (t_new, r_new) = run(tr_fn, "old", args.repeat), run(tr_fn, "new", args.repeat)
        diff = max(float(np.abs(np.asarray(r_old.fields[k], float) - np.asarray(r_new.fields[k], float)).max())
                   for k in r_old.fields)
        diff = max(diff, float(np.abs(r_old.weights - r_new.weights).max()))
        rows.append((label, n, "transfer: whole call", t_old, t_new, diff))
        print(f"  {label}: transfer done", file=sys.stderr, flush=True)

    print("\n| mesh | vertices | what | old (COLAMD) s | new (symmetric MMD) s | old / new | max difference |")
    print("|---|---|---|---|---|---|---|")
    for label, n, what, a, b, d in rows:
        print(f"| {label} | {n:,} | {what} | {a:.2f} | {b:.2f} | {a / b:.2f}x | {d:.1e} |")


if __name__ == "__main__":
    main()
