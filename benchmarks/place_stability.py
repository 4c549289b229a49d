"""Does `place` give the same rig for the same head written otherwise?

    python benchmarks/place_stability.py [--heads NAME,...] [--noise 1e-6] [--draws 3] [--markdown]

Every head of ``../shared/data`` (the zoo, misc, menpo3d's James, ICT identity000), rigged by ``autobones.place``
(density medium) as read and in three rewritings a user's tools make without meaning to change the head:

- *vertices renumbered*: the vertices in a random order, the triangles' corners renumbered with them (a
  converter, a welded STL);
- *triangles reordered*: the triangles in a random order;
- *noise*: every coordinate moved by Gaussian noise of ``--noise`` head sizes (a re-export's rounding:
  an OBJ written with 6 decimals of a 0.2 m head is 2.5e-6), ``--draws`` draws.

Reported, in head sizes: the largest move of a bone to its counterpart (bones matched one to one by least
total distance, so two bones that swap names are not counted as moved), and for the noise the frame's turn
(degrees). 0 means the same rig to round-off. Each figure is the worst over the draws.
"""
from __future__ import annotations

import argparse
import contextlib
import glob
import io
import os
import sys
import time

import numpy as np
from scipy.optimize import linear_sum_assignment

import autobones
from autobones.io.mesh import load_mesh
from autobones.landmarks.orientation import turn_degrees

DATA = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data")


def heads():
    """Paths of the shared heads, by name."""
    files = sorted(glob.glob(os.path.join(DATA, "zoo", "*.obj")) + glob.glob(os.path.join(DATA, "zoo", "*.off"))
                   + glob.glob(os.path.join(DATA, "misc", "*.obj")))
    files += [os.path.join(DATA, "menpo3d", "james.obj"), os.path.join(DATA, "ict", "identity000.obj")]
    return {os.path.splitext(os.path.basename(f))[0]: f for f in files if os.path.exists(f)}


def rig(V, F):
    with contextlib.redirect_stderr(io.StringIO()):  # the close-call and repair notes are not measured here
        return autobones.place((V, F), density="medium")


def bone_move(a, b, size):
    """Largest distance between the bones of rigs ``a`` and ``b`` matched one to one, in head sizes."""
    A, B = np.asarray(a.skeleton.heads), np.asarray(b.skeleton.heads)
    D = np.linalg.norm(A[:, None] - B[None], axis=2)
    i, j = linear_sum_assignment(D)
    return float(D[i, j].max()) / size


def measure(path, noise, draws):
    V, F = load_mesh(path)
    size = float(np.ptp(V, axis=0).max())
    base = rig(V, F)
    row = {"vertices": len(V), "renumbered": 0.0, "reordered": 0.0, "noise": 0.0, "turn": 0.0}
    for k in range(draws):
        rng = np.random.default_rng(100 + k)
        p = rng.permutation(len(V))
        row["renumbered"] = max(row["renumbered"], bone_move(base, rig(V[p], np.argsort(p)[F]), size))
        row["reordered"] = max(row["reordered"], bone_move(base, rig(V, F[rng.permutation(len(F))]), size))
        noisy = rig(V + rng.normal(size=V.shape) * noise * size, F)
        row["noise"] = max(row["noise"], bone_move(base, noisy, size))
        row["turn"] = max(row["turn"], turn_degrees(base.frame.rotation, noisy.frame.rotation))
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--heads", help="comma-separated names (default: every shared head)")
    ap.add_argument("--noise", type=float, default=1e-6, help="noise, head sizes (default 1e-6)")
    ap.add_argument("--draws", type=int, default=3, help="random rewritings of each kind (default 3)")
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args(argv)
    found = heads()
    names = args.heads.split(",") if args.heads else sorted(found, key=str.lower)
    missing = [n for n in names if n not in found]
    if missing:
        sys.exit(f"place_stability.py: no shared head named {', '.join(missing)} (in {DATA})")
    print(f"| head | vertices | vertices renumbered | triangles reordered | noise {args.noise:g} "
          "| frame turn, noise (deg) | s |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    worst = {"renumbered": [], "reordered": [], "noise": []}
    for name in names:
        t = time.perf_counter()
        r = measure(found[name], args.noise, args.draws)
        for k in worst:
            worst[k].append(r[k])
        print(f"| {name} | {r['vertices']:,} | {r['renumbered']:.4f} | {r['reordered']:.4f} | {r['noise']:.4f} | "
              f"{r['turn']:.2g} | {time.perf_counter() - t:.0f} |", flush=True)
    same = {k: sum(v < 1e-6 for v in worst[k]) for k in worst}
    print(f"\nbones moved (head sizes, worst of {args.draws} draws); the same rig (under 1e-6) on "
          f"{same['renumbered']}/{len(names)} heads renumbered, {same['reordered']}/{len(names)} reordered, "
          f"{same['noise']}/{len(names)} with noise")


if __name__ == "__main__":
    main()
