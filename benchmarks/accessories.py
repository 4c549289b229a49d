"""The frame of a head wearing hair or a hat, missing its crown, or cracked (issue #31 check 1, off the
zoo's copies).

    python benchmarks/accessories.py [--heads LeePerrySmith,james | --heads all] [--data ../shared/data]

Heads arrive with hair modelled as a separate part (game and film heads, sculpts) and scans arrive with
the top of the skull missing (hair not captured). Per head (the humans of ``../shared/data``: the SMPL
man and woman, ICT identity000, James, Lee Perry-Smith, Demosthenes), copies made in the frame
``detect_frame`` finds on the bare head (the reference: the copies' frames are compared with it):

- ``shell``: an open copy of the scalp (every face within ``cover`` 0.25 / 0.35 / 0.45 of the height from
  the top, and the back of the head's upper half) lifted 0.015 / 0.03 head sizes along the normals;
- ``volume``: the same closed, down to 0.003 head sizes off the scalp;
- ``crown``: every face with a vertex within 0.1 / 0.2 / 0.3 head sizes of the top removed;
- ``hat``: a separate ball of 0.15 / 0.3 head sizes set on the crown;
- ``split``: half the triangles (at random) split in four without their neighbours (T-junction cracks);

each turned by two random rotations (scipy seeds 7, 8). A copy is right when its front and up are both
within 30 degrees of the bare head's (turned with it). Prints one row per head and the failing copies.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).resolve().parent))
import zoo  # noqa: E402

from autobones.geometry.normals import vertex_normals  # noqa: E402
from autobones.io.mesh import load_mesh  # noqa: E402
from autobones.orient import detect_frame  # noqa: E402

HEADS = ("human_man", "human_woman", "identity000", "james", "LeePerrySmith", "demosthenes-low-res")
COVERS, LIFTS, CROWNS, SEEDS = (0.25, 0.35, 0.45), (0.015, 0.03), (0.1, 0.2, 0.3), (7, 8)
HATS = (0.15, 0.3)
KINDS = ("shell", "volume", "crown", "hat", "split")


def with_hair(V, F, frame, cover, lift, closed=False):
    """``(V, F)`` with hair: a separate copy of the scalp (every face within ``cover`` of the height from
    the top, and the back of the head's upper half) lifted ``lift`` head sizes along the normals, in
    the input frame; an open shell, or ``closed``: a volume down to 0.003 head sizes off the scalp."""
    C = frame.to_canonical(V)
    N = vertex_normals(C, F)
    y, z = C[:, 1], C[:, 2]
    scalp = (y > y.max() - cover * np.ptp(y)) | ((z < z.min() + 0.25) & (y > y.min() + 0.5 * np.ptp(y)))
    used, S = np.unique(F[scalp[F].all(axis=1)], return_inverse=True)
    S, k = S.reshape(-1, 3), len(used)
    H, HF = C[used] + lift * N[used], S
    if closed:
        E = np.concatenate([S[:, [0, 1]], S[:, [1, 2]], S[:, [2, 0]]])
        key = np.sort(E, axis=1) @ [k, 1]
        rim = E[np.isin(key, np.flatnonzero(np.bincount(key) == 1))]    # edges of one face: the shell's rim
        walls = np.vstack([np.c_[rim[:, 1], rim[:, 0], rim[:, 1] + k], np.c_[rim[:, 1] + k, rim[:, 0], rim[:, 0] + k]])
        H, HF = np.vstack([H, C[used] + 0.003 * N[used]]), np.vstack([S, S[:, ::-1] + k, walls])
    return np.vstack([V, frame.from_canonical(H)]), np.vstack([F, HF + len(V)])


def without_crown(V, F, frame, reach):
    """``(V, F)`` without every face that has a vertex within ``reach`` head sizes of the top."""
    C = frame.to_canonical(V)
    inside = np.linalg.norm(C - C[np.argmax(C[:, 1])], axis=1) < reach
    return V, F[~inside[F].any(axis=1)]


def with_hat(V, F, frame, radius):
    """``(V, F)`` with a separate ball of ``radius`` head sizes set on the crown (its centre 0.8 radius
    above the top)."""
    import trimesh

    C = frame.to_canonical(V)
    ball = trimesh.creation.icosphere(subdivisions=3, radius=radius)
    hat = np.asarray(ball.vertices) + C[np.argmax(C[:, 1])] + [0.0, 0.8 * radius, 0.0]
    return np.vstack([V, frame.from_canonical(hat)]), np.vstack([F, np.asarray(ball.faces) + len(V)])


def half_split(V, F, seed=0):
    """``(V, F)`` with half the triangles (chosen at random) split in four without their neighbours: a
    T-junction along every seam, a crack a face's edge long."""
    pick = np.random.default_rng(seed).random(len(F)) < 0.5
    S, n = F[pick], len(V)
    k = len(S)
    mids = [(V[S[:, i]] + V[S[:, (i + 1) % 3]]) / 2 for i in range(3)]   # per triangle, never shared
    m01, m12, m20 = (n + j * k + np.arange(k) for j in range(3))
    split = np.vstack([np.c_[S[:, 0], m01, m20], np.c_[m01, S[:, 1], m12], np.c_[m20, m12, S[:, 2]],
                       np.c_[m01, m12, m20]])
    return np.vstack([V, *mids]), np.vstack([F[~pick], split])


def copies(V, F, frame):
    """(label, V, F) of every copy of a head (module docstring), before turning."""
    for closed, kind in ((False, "shell"), (True, "volume")):
        for cover in COVERS:
            for lift in LIFTS:
                yield (f"{kind} {cover:g}/{lift:g}", *with_hair(V, F, frame, cover, lift, closed))
    for reach in CROWNS:
        yield (f"crown {reach:g}", *without_crown(V, F, frame, reach))
    for radius in HATS:
        yield (f"hat {radius:g}", *with_hat(V, F, frame, radius))
    yield ("split", *half_split(V, F))


def measure(V, F, kinds=KINDS):
    """{kind: (right, total)} and the failing copies' labels with their angles, for one head."""
    bare = detect_frame(V, F)
    counts, fails = {}, []
    for label, Vc, Fc in copies(V, F, bare):
        kind = label.split()[0]
        if kind not in kinds:
            continue
        for seed in SEEDS:
            Q = Rotation.random(random_state=seed).as_matrix()
            back = detect_frame(Vc @ Q.T, Fc).rotation @ Q
            up, front = (float(np.degrees(np.arccos(np.clip(back[i] @ bare.rotation[i], -1, 1)))) for i in (1, 2))
            right, total = counts.get(kind, (0, 0))
            counts[kind] = (right + (up < 30 and front < 30), total + 1)
            if not (up < 30 and front < 30):
                fails.append(f"{label} seed {seed}: up {up:.0f}°, front {front:.0f}°")
    return counts, fails


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--heads", default=",".join(HEADS), help="comma-separated head names (zoo.py's), or all")
    ap.add_argument("--kinds", default=",".join(KINDS), help="comma-separated copies to make (default: all)")
    ap.add_argument("--data", type=Path, default=zoo.DATA)
    args = ap.parse_args(argv)
    kinds = tuple(args.kinds.split(","))
    known = zoo.heads_in(args.data)
    t = time.perf_counter()
    print("| head | hair shell right | hair volume right | crown missing right | hat right | split right | failing copies |")
    print("|---|---|---|---|---|---|---|")
    totals = {}
    for name in (sorted(known) if args.heads == "all" else args.heads.split(",")):
        counts, fails = measure(*load_mesh(known[name][0]), kinds)
        for kind, (r, n) in counts.items():
            totals[kind] = (totals.get(kind, (0, 0))[0] + r, totals.get(kind, (0, 0))[1] + n)
        cells = " | ".join(f"{counts[k][0]}/{counts[k][1]}" if k in counts else "-" for k in KINDS)
        print(f"| {name} | {cells} | {'; '.join(fails) or '-'} |", flush=True)
    print("\n" + ", ".join(f"{k}: {r}/{n} right" for k, (r, n) in totals.items()) + f"; {time.perf_counter() - t:.0f} s")


if __name__ == "__main__":
    main()
