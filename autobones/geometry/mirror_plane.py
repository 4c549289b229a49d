"""The mirror plane of a point sample: reflective ICP, and where to start it.

Goes beyond the papers we implement (they take upright heads): a head's left-right symmetry plane is
the plane that mirrors an area-uniform sample of its surface onto itself best. Points in, a plane
``normal . x = offset`` out, in the points' own frame and units; nothing depends on the frame, so a
head turned or scaled gives the same plane turned or scaled (:func:`shape_starts`' directions are
fixed to the sample's signed principal axes).
"""
from __future__ import annotations

import numpy as np


def reflect(P, normal, offset):
    """Points ``P`` (..., 3) mirrored through the plane ``normal . x = offset`` (unit normal);
    same frame and units."""
    P = np.asarray(P, dtype=np.float64)
    return P - 2.0 * (P @ normal - offset)[..., None] * normal


def onto_plane(P, normal, offset):
    """Points ``P`` (..., 3) moved along the unit ``normal`` onto the plane ``normal . x = offset`` (the
    feet of their perpendiculars); same frame and units."""
    P = np.asarray(P, dtype=np.float64)
    return P - (P @ normal - offset)[..., None] * normal


def refine_plane(P, tree, n, d, scale, iterations=12):
    """Reflective ICP of the plane ``n . x = d`` on points ``P``; ``scale`` (their RMS radius, mesh
    units) makes the convergence test unit-free. The plane returned is the visited one with the
    lowest mirror error: trimmed ICP on a lopsided head can cycle between nearby planes (steps of
    2e-4), and stopping wherever the cycle was cut made the frame, hence the rig, depend on the
    input's unit through round-off; the best of the cycle does not."""
    best = None
    for _ in range(iterations):
        mirrored = reflect(P, n, d)
        dist, j = tree.query(mirrored)
        err = float(np.sort(dist)[: int(0.9 * len(dist))].mean())  # mirror_error of (n, d)
        if best is None or err < best[0] * (1 - 1e-9):
            best = (err, n, d)
        # a reflection is an isometry, so mutually nearest points come as pairs at equal distances:
        # a tolerance keeps both of a pair on the same side of the trim, whatever the round-off
        keep = dist <= np.quantile(dist, 0.8) * (1 + 1e-9)
        diff = (P - P[j])[keep]
        mid = 0.5 * (P + P[j])[keep]
        w, U = np.linalg.eigh(diff.T @ diff)
        n_new = U[:, -1] * np.sign(U[:, -1] @ n or 1.0)
        d_new = float(mid.mean(axis=0) @ n_new)
        if np.allclose(n_new, n, atol=1e-9) and abs(d_new - d) < 1e-12 * scale:
            break
        n, d = n_new, d_new
    return best[1], best[2]


def mirror_error(P, tree, n, d):
    dist, _ = tree.query(reflect(P, n, d))
    return float(np.sort(dist)[: int(0.9 * len(dist))].mean())


def best_plane(P, tree, planes, rms):
    """(error, normal, offset) of the plane in ``planes`` that mirrors ``P`` onto itself best; the
    first of equals, so the order of the starts decides ties."""
    best = None
    for n, d in planes:
        err = mirror_error(P, tree, n, d)
        if best is None or err < best[0] - 1e-9 * rms:
            best = (err, n, d)
    return best


def shape_starts(P, tree, lines=96, keep=4, spread=20.0):
    """Plane normals (3,) to start the symmetry ICP from, fixed to the sample itself: ``lines``
    directions spread over the sphere in the sample's principal frame (each axis signed by the
    sample's third moment along it, so the frame turns with the head), each scored by how well the
    plane through the centroid mirrors a fifth of the sample, and the ``keep`` best at least
    ``spread`` degrees apart kept. A coarse look over every direction: the 13 cube directions of
    that frame missed the cat's plane when it was turned (0.11 against its 0.05)."""
    c = P - P.mean(axis=0)
    c = c / max(float(np.abs(c).max()), 1e-300)  # unit-free: a head in 1e150 units overflowed the moments
    _, E = np.linalg.eigh(c.T @ c)
    E = E * np.where(((c @ E) ** 3).sum(axis=0) < 0, -1.0, 1.0)
    k = np.arange(lines) + 0.5  # a Fibonacci half-sphere: the lines, n and -n alike
    z = k / lines
    phi = np.pi * (1 + 5 ** 0.5) * k
    dirs = np.column_stack([np.sqrt(1 - z ** 2) * np.cos(phi), np.sqrt(1 - z ** 2) * np.sin(phi), z]) @ E.T
    sub = P[:: 5]
    centre = P.mean(axis=0)
    errors = [mirror_error(sub, tree, n, centre @ n) for n in dirs]
    starts = []
    for i in np.argsort(errors, kind="stable"):
        if all(abs(dirs[i] @ s) < np.cos(np.radians(spread)) for s in starts):
            starts.append(dirs[i])
        if len(starts) == keep:
            break
    # the reflective ICP stalls a few degrees off (ICT turned: 0.050 against its 0.033), so each
    # start is first settled by a pattern search of the same score
    return [pattern_search(lambda n: mirror_error(sub, tree, n, centre @ n), n, E) for n in starts]


def pattern_search(score, n, frame, step=6.0, smallest=0.25):
    """The unit normal near ``n`` (3,) that lowers ``score(n)``: tilt it by ``step`` degrees about
    two axes across it, keep the best tilt that scores lower, halve the step when none does. The
    tilt axes come from ``frame`` (3, 3), columns the sample's signed principal axes, not from the
    input axes: the search then takes the same steps on a turned copy of the sample."""
    best = score(n)
    while step >= smallest:
        a = np.cross(n, frame[:, int(np.argmin(np.abs(n @ frame)))])
        a /= np.linalg.norm(a)
        b = np.cross(n, a)
        t = np.tan(np.radians(step))
        trials = [(m / np.linalg.norm(m)) for m in (n + t * a, n - t * a, n + t * b, n - t * b)]
        scores = [score(m) for m in trials]
        i = int(np.argmin(scores))
        if scores[i] < best:
            n, best = trials[i], scores[i]
        else:
            step /= 2.0
    return n
