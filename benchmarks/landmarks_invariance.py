"""The invariance part of ``benchmarks/landmarks.py``: ICT neutral rotated and scaled through
``autobones.detect_landmarks``, its landmarks mapped back and compared with the plain run; and a head in
millimetres facing -X against its published landmarks."""
from __future__ import annotations

import itertools
import time

import numpy as np

import autobones
from autobones.errors import AutobonesError
from autobones.io.landmarks import read_landmarks
from autobones.io.mesh import load_mesh

from landmarks_accuracy import errors, fmt_names
from landmarks_heads import DATA, HEADS


def small(x):
    """A percentage, with an exponent when it rounds to zero."""
    return f"{x:.3f}" if x == 0 or x >= 5e-4 else f"{x:.1e}"


def proper_rotations():
    """The 24 axis-aligned rotations (signed permutation matrices with det +1), identity first."""
    out = []
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1, -1), repeat=3):
            R = np.zeros((3, 3))
            R[range(3), perm] = signs
            if np.linalg.det(R) > 0:
                out.append(R)
    out.sort(key=lambda R: -np.trace(R))
    return out


def axis_name(R, canonical):
    """Input axis that canonical direction ``canonical`` (ICT frame) points along after ``R``."""
    v = R @ np.asarray(canonical, dtype=np.float64)
    i = int(np.argmax(np.abs(v)))
    return ("+" if v[i] > 0 else "-") + "xyz"[i]


def print_invariance(quick):
    """The axis-aligned rotations' table, the arbitrary rotations' line and the millimetre head's line."""
    V0, F0 = load_mesh(DATA / HEADS["ict neutral"][0])
    ref = autobones.detect_landmarks((V0, F0))
    unit = np.linalg.norm(read_landmarks(DATA / HEADS["ict neutral"][1])["exocanthion_l"]
                          - read_landmarks(DATA / HEADS["ict neutral"][1])["exocanthion_r"])
    axis_rotations(V0, F0, ref, unit, quick)
    arbitrary_rotations(V0, F0, ref, unit, quick)
    millimetre_head()


def axis_rotations(V0, F0, ref, unit, quick):
    """The 24 axis-aligned rotations (4 if ``quick``) x1000: one row each, then the summary line."""
    rots = proper_rotations()
    if quick:
        rots = [rots[i] for i in (0, 5, 11, 17)]
    print(f"\n## Invariance: ICT neutral rotated (24 proper axis-aligned rotations{' - quick: 4' if quick else ''}) "
          f"and scaled x1000, mapped back, vs the unrotated unit-scale run (% of ex-ex)\n")
    print("| # | up | front | found up | found front | names | mean % | max % (name) | dropped | flagged | s |")
    print("|---:|---|---|---|---|---:|---:|---|---|---|---:|")
    diffs, bad = [], 0
    for i, R in enumerate(rots):
        V = 1000.0 * V0 @ R.T
        t0 = time.perf_counter()
        try:
            lm = autobones.detect_landmarks((V, F0))
        except AutobonesError as exc:
            print(f"| {i + 1} | {axis_name(R, (0, 1, 0))} | {axis_name(R, (0, 0, 1))} | - | - | 0 | - | "
                  f"failed: {str(exc)[:50]} | | | |")
            bad += 1
            continue
        secs = time.perf_counter() - t0
        back = {n: (np.asarray(p) / 1000.0) @ R for n, p in lm.items()}
        d = {n: 100 * float(np.linalg.norm(back[n] - ref[n])) / unit for n in ref if n in back}
        diffs += list(d.values())
        worst = max(d, key=d.get)
        same = set(ref) == set(lm)
        bad += not same or d[worst] > 1.0
        print(f"| {i + 1} | {axis_name(R, (0, 1, 0))} | {axis_name(R, (0, 0, 1))} | {lm.frame.up} | "
              f"{lm.frame.front} | {len(d)}{'' if same else ' (differs)'} | {small(np.mean(list(d.values())))} | "
              f"{small(d[worst])} ({worst}) | {fmt_names(lm.dropped)} | {fmt_names(lm.flagged)} | {secs:.2f} |",
              flush=True)
    if diffs:
        print(f"\nover {len(rots)} orientations: mean difference {small(np.mean(diffs))} %, "
              f"max {small(np.max(diffs))} % "
              f"of ex-ex; orientations with a different name set or a difference > 1 %: {bad}")


def arbitrary_rotations(V0, F0, ref, unit, quick):
    """Not asked by the issue: rotations off the axes, where the frame finder's estimate (not a
    permutation of the same numbers) decides what the pictures show."""
    from scipy.spatial.transform import Rotation

    turns = Rotation.random(2 if quick else 4, random_state=0).as_matrix()
    print("\narbitrary rotations (scipy Rotation.random, seed 0), x1000: ", end="")
    out = []
    for R in turns:
        try:
            lm = autobones.detect_landmarks((1000.0 * V0 @ R.T, F0))
        except AutobonesError as exc:
            out.append(f"failed ({str(exc)[:40]})")
            continue
        back = {n: (np.asarray(p) / 1000.0) @ R for n, p in lm.items()}
        d = {n: 100 * float(np.linalg.norm(back[n] - ref[n])) / unit for n in ref if n in back}
        worst = max(d, key=d.get)
        out.append(f"{np.mean(list(d.values())):.2f} % mean, {d[worst]:.2f} % max ({worst}), {len(d)} names, "
                   f"{len(lm.flagged)} flagged")
    print("; ".join(out))


def millimetre_head():
    """ICT identity001 in millimetres facing -X: must come back with no flag and no drop."""
    Vi, Fi = load_mesh(DATA / HEADS["ict identity001"][0])
    Ti = read_landmarks(DATA / HEADS["ict identity001"][1])
    R = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])     # +Z (face) -> -X
    Vm = 10.0 * Vi @ R.T                                                    # centimetres -> millimetres
    Tm = {n: 10.0 * R @ p for n, p in Ti.items()}
    t0 = time.perf_counter()
    lm = autobones.detect_landmarks((Vm, Fi))
    secs = time.perf_counter() - t0
    e = errors(lm, Tm)
    worst = max(e, key=e.get)
    ok = not lm.flagged and not lm.dropped and lm.frame.front == "-x"
    print(f"\nICT identity001 in millimetres facing -X: found up {lm.frame.up}, front {lm.frame.front}; "
          f"{len(lm)} names, dropped {fmt_names(lm.dropped)}, flagged {fmt_names(lm.flagged)}; unit (ex-ex) "
          f"{lm.unit:.1f} mm; error vs published {np.mean(list(e.values())):.2f} % mean, {e[worst]:.2f} % max "
          f"({worst}); {secs:.2f} s -> {'OK' if ok else 'NOT OK'}")
