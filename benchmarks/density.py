"""The same surface, four times the vertices: does ``place`` give the same rig? (issue #31)

    python benchmarks/density.py [--heads cowHead,springer] [--markdown] [--data ../shared/data]

Real scans are dense (100k-1M vertices); the zoo's heads are 0.5k-53k. A user's scan differs from a zoo head
in its tessellation as much as in its shape, and a rig must follow the shape. Each landmarked zoo head is
rigged as written and split 1-to-4 (``trimesh.remesh.subdivide``: every triangle into four at its edges'
midpoints; the surface is exactly the same, its first n vertices are the original ones). Per head:

- ``frame``: the angle between the two copies' canonical frames (degrees), ``c`` where either was said to be
  a close call (:attr:`autobones.orient.Frame.front_check`);
- ``chin``: ``place``'s menton height (canonical, head sizes) on each copy and the landmark's;
- ``joints``: how far the head and neck joints moved (head sizes);
- ``share``: the head side's weight (1 - the neck's) on the original vertices, mean and largest change;
- ``neck``: the zoo's check 3 (``zoo_checks.check_neck_base``, in the landmarks' frame) on each copy.

The closing line counts the heads whose frame turned by more than 2 degrees, whose chin moved by more than
0.02 head sizes, and whose neck verdict changed.
"""
from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parent))
import zoo  # noqa: E402
import zoo_checks as zc  # noqa: E402

from autobones import place  # noqa: E402
from autobones.io.landmarks import read_landmarks  # noqa: E402
from autobones.io.mesh import load_mesh  # noqa: E402

FRAME_MOVED = 2.0    # degrees
CHIN_MOVED = 0.02    # head sizes


def rig_of(V, F, lm):
    """(rig, neck check text, menton height, landmark menton height) of ``place`` on ``V``, ``F``."""
    rig = place(trimesh.Trimesh(V, F, process=False))
    ref = zc.landmark_frame(V, F, lm)
    up = ref["up"]
    neck = zc.check_neck_base(rig, up, np.arange(len(V)), zc.chin_height(lm, up)).text
    name = "menton" if "menton" in lm else "pogonion"
    truth = float(rig.frame.to_canonical(lm[name][None])[0, 1]) if name in lm else float("nan")
    return rig, neck, rig.other["joints"]["menton_height"], truth


def compare(name, mesh, lm_path):
    """One row (dict) for a head: the two copies' frames, chins, joints, shares and neck checks."""
    V, F = load_mesh(mesh)[:2]
    V, F = np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64)
    lm = {k: np.asarray(v, dtype=np.float64) for k, v in read_landmarks(lm_path).items()}
    Vs, Fs = trimesh.remesh.subdivide(V, F)
    t = time.perf_counter()
    a, neck_a, chin_a, truth = rig_of(V, F, lm)
    ta = time.perf_counter() - t
    b, neck_b, chin_b, _ = rig_of(Vs, Fs, lm)
    tb = time.perf_counter() - t - ta
    Ra, Rb = a.frame.rotation, b.frame.rotation
    angle = float(np.degrees(np.arccos(np.clip((np.trace(Ra.T @ Rb) - 1.0) / 2.0, -1.0, 1.0))))
    close = any((r.frame.front_check or {}).get("close") for r in (a, b))
    size = a.frame.size
    ja = dict(zip(a.skeleton.names, np.asarray(a.skeleton.heads)))
    jb = dict(zip(b.skeleton.names, np.asarray(b.skeleton.heads)))
    moved = {j: float(np.linalg.norm(ja[j] - jb[j])) / size for j in ("head", "neck")}
    Wa, Wb = np.asarray(a.weights), np.asarray(b.weights)[:len(V)]
    na, nb = a.skeleton.names.index("neck"), b.skeleton.names.index("neck")
    d_share = np.abs(Wa[:, na] - Wb[:, nb])
    return {"head": name, "n": (len(V), len(Vs)), "frame": angle, "close": close,
            "chin": (chin_a, chin_b, truth), "moved": moved, "share": (float(d_share.mean()), float(d_share.max())),
            "neck": (neck_a, neck_b), "seconds": (ta, tb)}


def fmt(x):
    return "-" if x is None else f"{x:+.3f}"


def table(rows, markdown):
    head = ["head", "vertices", "frame (deg)", "chin: as written / split / landmark", "head, neck moved",
            "share change mean / max", "neck check: as written / split", "seconds"]
    lines = []
    for r in rows:
        ca, cb, ct = r["chin"]
        lines.append([r["head"], f"{r['n'][0]:,} -> {r['n'][1]:,}", f"{r['frame']:.1f}{' c' if r['close'] else ''}",
                      f"{fmt(ca)} / {fmt(cb)} / {fmt(ct)}", f"{r['moved']['head']:.3f}, {r['moved']['neck']:.3f}",
                      f"{r['share'][0]:.3f} / {r['share'][1]:.3f}", f"{r['neck'][0]} / {r['neck'][1]}",
                      f"{r['seconds'][0]:.1f} / {r['seconds'][1]:.1f}"])
    if markdown:
        out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        out += ["| " + " | ".join(cells) + " |" for cells in lines]
    else:
        out = ["  ".join(head)] + ["  ".join(cells) for cells in lines]
    return "\n".join(out)


def chin_moved(chin):
    """Whether the two copies' chins ``chin`` (as written, split, landmark) differ: one read and not the
    other, or more than ``CHIN_MOVED`` apart."""
    a, b = chin[:2]
    return (a is None) != (b is None) or (a is not None and abs(a - b) > CHIN_MOVED)


def summary(rows):
    named = lambda heads: ", ".join(heads) or "-"  # noqa: E731
    turned = [r["head"] for r in rows if r["frame"] > FRAME_MOVED]
    chin = [r["head"] for r in rows if chin_moved(r["chin"])]
    neck = [r["head"] for r in rows if (r["neck"][0] == "ok") != (r["neck"][1] == "ok")]
    return (f"{len(rows)} heads split 1-to-4: frame turned > {FRAME_MOVED:g} deg on {len(turned)} ({named(turned)}); "
            f"chin moved > {CHIN_MOVED:g} on {len(chin)} ({named(chin)}); "
            f"neck verdict changed on {len(neck)} ({named(neck)})")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, default=zoo.DATA)
    ap.add_argument("--heads", help="comma-separated head names (default: every landmarked zoo head)")
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args(argv)
    logging.disable(logging.WARNING)   # close calls are read from the frames, not the log
    heads = {n: v for n, v in zoo.heads_in(args.data).items() if v[1] is not None}
    if args.heads:
        heads = {n: heads[n] for n in args.heads.split(",")}
    rows = []
    for name, (mesh, lm) in heads.items():
        rows.append(compare(name, mesh, lm))
        print(f"{name}: done", file=sys.stderr, flush=True)
    print(table(rows, args.markdown))
    print()
    print(summary(rows))


if __name__ == "__main__":
    main()
