"""Check 1 of the zoo benchmark alone (issue #31), fast: ``detect_frame`` on every landmarked shared head,
as is, under 6 random rotations (scipy, seed 31, as ``zoo.py``) and x0.001 / x1000.

    python benchmarks/frames.py [--heads cowHead,james] [--data ../shared/data] [-j 2]

Per head: the angle of the detected front / up from the landmarks' frame (``zoo_checks.landmark_frame``)
as is and the worst over the rotated copies, how many rotated copies are more than 30° off, and the
drift: the largest angle between a copy's frame axes mapped back and the as-is frame's (degrees;
2 asin(|a - b| / 2), exact to round-off), with the worst copy. Time is the as-is ``detect_frame``.
"""
from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import zoo  # noqa: E402
import zoo_checks as zc  # noqa: E402

from autobones.io.landmarks import read_landmarks  # noqa: E402
from autobones.io.mesh import load_mesh  # noqa: E402
from autobones.orient import detect_frame  # noqa: E402

COPIES = (*(f"rot{k}" for k in range(1, zc.ROTATIONS + 1)), "x0.001", "x1000")


def off(rotation, ref):
    """Largest of the front / up angles (degrees) from the landmarks' frame ``ref``."""
    return max(zc.angle(rotation[2], ref["front"]), zc.angle(rotation[1], ref["up"]))


def drift_deg(R, R0, turn):
    """Largest angle (degrees) between an axis of the copy's frame ``R``, turned back by ``turn``, and
    the same axis of the as-is frame ``R0``: 2 asin(|a - b| / 2), exact down to round-off (an arccos
    of the dot product reads 0 below 1e-8 rad)."""
    back = np.asarray(R) @ turn
    return float(np.degrees(2 * np.arcsin(np.clip(np.linalg.norm(back - R0, axis=1).max() / 2, 0, 1))))


def measure(item):
    name, (mesh, lm_path), copies = item
    V, F = load_mesh(mesh)
    lm = read_landmarks(lm_path)
    ref = zc.landmark_frame(V, F, lm)
    t = time.perf_counter()
    R0 = detect_frame(V, F).rotation
    seconds = time.perf_counter() - t
    row = {"head": name, "as-is": off(R0, ref), "rot": [], "drift": (-1.0, "")}
    for copy in copies:
        var = zc.make_variant(copy, V, F, lm, 0)
        R = detect_frame(var.V, var.F).rotation
        if copy.startswith("rot"):
            row["rot"].append(off(R, {k: var.R @ v for k, v in ref.items()}))
        drift = drift_deg(R, R0, var.R)
        if drift > row["drift"][0]:
            row["drift"] = (drift, copy)
    row["seconds"] = seconds
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--heads", help="comma-separated head names (default: every landmarked head)")
    ap.add_argument("--data", type=Path, default=zoo.DATA)
    ap.add_argument("-j", "--jobs", type=int, default=1)
    ap.add_argument("--copies", default=",".join(COPIES), help="comma-separated copies (default: all 8)")
    args = ap.parse_args(argv)
    heads = {n: v for n, v in zoo.heads_in(args.data).items() if v[1] is not None}
    if args.heads:
        heads = {n: heads[n] for n in args.heads.split(",")}
    items = [(n, v, args.copies.split(",")) for n, v in heads.items()]
    t = time.perf_counter()
    with ProcessPoolExecutor(args.jobs) as pool:
        rows = list(pool.map(measure, items)) if args.jobs > 1 else list(map(measure, items))
    print("| head | as-is off | rotations off (worst) | rotations > 30° | drift, degrees (worst copy) | s |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        bad = sum(d > zc.FRAME_DEG for d in r["rot"])
        drift, copy = r["drift"]
        print(f"| {r['head']} | {r['as-is']:.1f}° | {max(r['rot'], default=float('nan')):.1f}° | {bad}/{len(r['rot'])} | "
              f"{drift:.1e}° ({copy or '-'}) | {r['seconds']:.2f} |")
    as_is = sum(r["as-is"] > zc.FRAME_DEG for r in rows)
    rot = sum(sum(d > zc.FRAME_DEG for d in r["rot"]) for r in rows)
    same = sum(np.radians(r["drift"][0]) <= zc.DRIFT for r in rows)
    print(f"\n{len(rows)} heads: as is > 30° off {as_is}; rotated > 30° off {rot}/{sum(len(r['rot']) for r in rows)}; "
          f"drift within 1e-6 rad on {same}/{len(rows)}; {time.perf_counter() - t:.0f} s")


if __name__ == "__main__":
    main()
