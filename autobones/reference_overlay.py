"""How well a head, stood as (up, front), overlays the reference head: the score that chooses
between up and front candidates, and the search that settles the angle between two of them.

Goes beyond the papers we implement (they take upright heads). Everything is computed in the
candidate's own frame (the sample turned onto it, centred and scaled to unit RMS radius), so a head
turned or scaled in its file gives the same scores for the same candidates turned with it.
"""
from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache

import numpy as np
from scipy.spatial import cKDTree

from .geometry.rotations import similarity
from .geometry.sample import sample_surface

SAMPLE_COUNT = 3000


def overlay_scores(P, candidates, ref):
    """:func:`overlay_score` of each (up, front) candidate against ``ref`` (or ``ref[i]``, a list).
    Independent ICPs whose time is in the k-d tree queries, which release the GIL: threads give the
    same scores in about half the time on two cores."""
    with ThreadPoolExecutor(max_workers=min(len(candidates), os.cpu_count() or 1)) as pool:
        refs = ref if isinstance(ref, list) else [ref] * len(candidates)
        return list(pool.map(lambda c: overlay_score(P, c[0][0], c[0][1], c[1]), zip(candidates, refs)))


def best_part_scores(P, candidates, parts):
    """For each (up, front) candidate, :func:`overlay_score` against the better of its reference parts
    (``parts[i]``, a tuple of canonical samples): the scores and the part each was scored on."""
    every = [overlay_scores(P, candidates, [p[k] for p in parts]) for k in range(len(parts[0]))]
    best = [int(np.argmin(s)) for s in zip(*every)]
    return [float(min(s)) for s in zip(*every)], [p[k] for p, k in zip(parts, best)]


def refine_angle(P, normal, up, front, ref, half=15.0, evaluations=8):
    """(up, front) turned about the symmetry ``normal`` by the angle within +-``half`` degrees
    that overlays the reference best (the overlay held at that turn: a golden-section search on a
    score that is smooth in the angle), for candidates spaced ``2 * half`` degrees apart."""
    def turned(t):
        c, s = np.cos(np.radians(t)), np.sin(np.radians(t))
        side = np.cross(normal, up) * np.sign(np.cross(normal, up) @ front)
        return c * up + s * side, c * front - s * up

    def score(t):
        u, f = turned(t)
        return overlay_score(P, u, f, ref, max_turn=0.0)

    g = (np.sqrt(5.0) - 1.0) / 2.0
    a, b = -half, half
    x1, x2 = b - g * (b - a), a + g * (b - a)
    f1, f2 = score(x1), score(x2)
    for _ in range(evaluations - 2):
        if f1 <= f2:
            b, x2, f2 = x2, x1, f1
            x1 = b - g * (b - a)
            f1 = score(x1)
        else:
            a, x1, f1 = x1, x2, f2
            x2 = a + g * (b - a)
            f2 = score(x2)
    return turned(x1 if f1 <= f2 else x2)


def top_part(Q):
    """The cranium and face of a +Y-up point set, centred and scaled to unit RMS radius,
    whether the mesh ends at the neck, the shoulders or a bust base: the top slice as tall as
    1.2 head widths, the head width measured on the cap above the widest part."""
    y = Q[:, 1]
    band = 0.3 * np.ptp(y)
    for _ in range(2):  # settle the width on the head, not on shoulders
        width = np.ptp(Q[y >= y.max() - band, 0])
        band = 0.6 * width
    top = Q[y >= y.max() - 1.2 * width]
    # a lone spike above the head leaves a slice of almost nothing: then the whole set is the head
    Q = top if width > 0 and len(top) >= 0.03 * len(Q) else Q
    Q = Q - Q.mean(axis=0)
    return Q / max(np.sqrt((Q ** 2).sum(axis=1).mean()), 1e-300)


def overlay_score(P, up, front, ref, iterations=30, max_turn=35.0):
    """Trimmed two-way distance between the head oriented as (up, front) and the reference,
    after a similarity ICP that may turn the head by at most ``max_turn`` degrees (a tilted
    or turned head still matches; a head facing the other way cannot turn round)."""
    R = np.vstack([np.cross(up, front), up, front])
    Q = top_part(P @ R.T)
    ref = top_part(ref)
    ref_tree = cKDTree(ref)
    rot, s, t = np.eye(3), 1.0, np.zeros(3)
    last = None
    for _ in range(iterations):
        X = s * Q @ rot.T + t
        dist, j = ref_tree.query(X)
        keep = dist <= np.quantile(dist, 0.8)
        if last is not None and np.array_equal(j, last[0]) and np.array_equal(keep, last[1]):
            break  # the same matches give the same similarity: a fixed point, every later step equal
        last = (j, keep)
        A, B = Q[keep], ref[j[keep]]
        Am, Bm = A.mean(axis=0), B.mean(axis=0)
        scale, new_rot = similarity(A, B)   # B ~ s rot A + t in least squares
        if np.degrees(np.arccos(np.clip((np.trace(new_rot) - 1) / 2, -1, 1))) <= max_turn:
            rot = new_rot
        s = float(np.clip(scale, 0.5, 2.0))
        t = Bm - s * Am @ rot.T
    X = s * Q @ rot.T + t
    d1, _ = ref_tree.query(X)
    d2, _ = cKDTree(X).query(ref)
    trim = lambda d: float(np.sort(d)[: int(0.8 * len(d))].mean())
    return trim(d1) + trim(d2)


@lru_cache(maxsize=1)
def default_reference():
    """Canonical sample of the built-in default head (cached; read-only)."""
    from .generic_rig import default_head_path
    from .io.mesh import load_mesh

    V, F = load_mesh(default_head_path())
    P, _, _ = sample_surface(V, F, SAMPLE_COUNT, seed=1)
    P = P - P.mean(axis=0)
    P /= np.sqrt((P ** 2).sum(axis=1).mean())
    P.setflags(write=False)
    return P
