"""Implicit-modelling primitives: signed distance fields and smooth blends.

Every field function takes points ``p`` as an ``(N, 3)`` float array in
metres and returns an ``(N,)`` float array in metres, negative inside.  The
distances are approximate (exact on the surface, not far from it), which is
all a marching-cubes zero level set needs.  The smooth blends are the
quadratic polynomial smooth minimum of signed-distance modelling.
"""

from __future__ import annotations

import numpy as np


def smin(a, b, k):
    """Smooth union of fields ``a`` and ``b`` (same shape); blend radius ``k`` (m)."""
    if k <= 0:
        return np.minimum(a, b)
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return b + (a - b) * h - k * h * (1.0 - h)


def smax(a, b, k):
    """Smooth intersection; ``smax(f, -g, k)`` carves ``g`` out of ``f``."""
    return -smin(-a, -b, k)


def rot_x(deg):
    """(3, 3) rotation about +X by ``deg`` degrees."""
    t = np.radians(deg)
    c, s = np.cos(t), np.sin(t)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(deg):
    """(3, 3) rotation about +Y by ``deg`` degrees."""
    t = np.radians(deg)
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def ellipsoid(p, c, r, R=None):
    """Approximate signed distance to an ellipsoid.

    ``c`` (3,) centre and ``r`` (3,) radii in metres; ``R`` (3, 3) optional
    rotation of the ellipsoid's local axes into world (local = (p - c) @ R).
    k0 (k0 - 1) / k1 is a first-order estimate: exact on the surface.
    """
    q = p - np.asarray(c, float)
    if R is not None:
        q = q @ np.asarray(R, float)
    r = np.asarray(r, float)
    k0 = np.sqrt(((q / r) ** 2).sum(-1))
    k1 = np.sqrt(((q / (r * r)) ** 2).sum(-1))
    return k0 * (k0 - 1.0) / np.maximum(k1, 1e-12)


def capsule(p, a, b, ra, rb=None):
    """Distance to a round cone from ``a`` (radius ``ra``) to ``b`` (``rb``, default ``ra``)."""
    if rb is None:
        rb = ra
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    ab = b - a
    t = np.clip(((p - a) @ ab) / (ab @ ab), 0.0, 1.0)
    d = np.linalg.norm(p - (a + t[:, None] * ab), axis=-1)
    return d - (ra + (rb - ra) * t)


def polyline_tube(p, pts, r):
    """Distance to a tube around the polyline ``pts`` (K, 3).

    ``r`` is a scalar or a (K,) per-vertex radius, interpolated along segments.
    """
    pts = np.asarray(pts, float)
    r = np.broadcast_to(np.asarray(r, float), (len(pts),))
    best = np.full(len(p), np.inf)
    for i in range(len(pts) - 1):
        a, b = pts[i], pts[i + 1]
        ab = b - a
        t = np.clip(((p - a) @ ab) / (ab @ ab), 0.0, 1.0)
        d = np.linalg.norm(p - (a + t[:, None] * ab), axis=-1)
        d = d - (r[i] + (r[i + 1] - r[i]) * t)
        best = np.minimum(best, d)
    return best


def local(p, lo, hi, fun, far=1.0):
    """``fun(p)`` for points inside the box [lo, hi] (3,), ``far`` elsewhere.

    Costly small features (ears, lid lines) only need evaluating near
    themselves; ``far`` must exceed every blend radius so the cut is invisible.
    """
    lo = np.asarray(lo, float)
    hi = np.asarray(hi, float)
    m = np.all((p >= lo) & (p <= hi), axis=1)
    out = np.full(len(p), far)
    if m.any():
        out[m] = fun(p[m])
    return out


def smoothstep(e0, e1, x):
    """Cubic Hermite step from 0 at ``e0`` to 1 at ``e1`` (elementwise)."""
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3 - 2 * t)
