"""Wire deformers (seed 000 §4.2, "Wires"; Singh and Fiume 1998, simplified).

A wire deformer is a base wire B and a deforming wire D of equal parameter range,
a dropoff distance d0 and the dropoff function f(x) = (1 - x^2)^2 on [0, 1]. A
skin point P within d0 of the base wire, whose closest base-wire parameter is u,
moves by

    f(|P - B(u)| / d0) * (D(u) - B(u)).

The wires are linear curves through their control vertices (000 found linear
wires as good as cubic NURBS and cheaper), so D(u) - B(u) is the linear
interpolation of the control-vertex displacements at u, and the whole deformation
is a fixed sparse matrix applied to those displacements: the closest parameters
and dropoff weights depend on the base wire only and are computed once.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..errors import AutobonesError


def dropoff(x):
    """000's dropoff f(x) = (1 - x^2)^2 for x in [0, 1], 0 beyond; ``x`` any shape."""
    x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    return (1.0 - x * x) ** 2


def closest_on_polyline(P, C):
    """Closest points of a linear curve to points.

    Parameters
    ----------
    P : (n, 3) float
        Query points.
    C : (k, 3) float
        Control vertices of the polyline (k >= 2), same frame and units.

    Returns
    -------
    dist : (n,) float
        Distance from each point to the polyline.
    seg : (n,) int
        Index of the closest segment (between C[seg] and C[seg + 1]).
    t : (n,) float
        Position on that segment in [0, 1].
    """
    P = np.asarray(P, dtype=np.float64)
    A, B = C[:-1], C[1:]
    AB = B - A
    ab2 = np.maximum((AB * AB).sum(axis=1), 1e-300)
    # (n, s) projections; s is small (a handful of segments per wire)
    t = np.clip(np.einsum("nsj,sj->ns", P[:, None, :] - A[None], AB) / ab2, 0.0, 1.0)
    Q = A[None] + t[..., None] * AB[None]
    d2 = ((P[:, None, :] - Q) ** 2).sum(axis=2)
    seg = np.argmin(d2, axis=1)
    rows = np.arange(len(P))
    return np.sqrt(d2[rows, seg]), seg, t[rows, seg]


def wire_weights(V, base, d0, gate=None, tree=None):
    """The sparse matrix of one wire deformer.

    Parameters
    ----------
    V : (n, 3) float
        Skin points (any frame and unit).
    base : (k, 3) float
        Base wire control vertices, same frame and units.
    d0 : float
        Dropoff distance, same units.
    gate : (n,) float, optional
        Per-point factor in [0, 1] multiplied into the dropoff (0 cuts a point
        out of this wire, e.g. across the mouth line); default 1.
    tree : scipy.spatial.cKDTree of V, optional
        Reused when several wires deform the same points.

    Returns
    -------
    scipy.sparse.csr_matrix (n, k)
        ``W @ (D - B)`` is the (n, 3) displacement of the skin for a deforming
        wire D with control vertices of the same count.
    """
    base = np.asarray(base, dtype=np.float64)
    if base.ndim != 2 or base.shape[1] != 3 or len(base) < 2:
        raise AutobonesError(f"wire: the base wire needs (k >= 2, 3) control vertices, got {base.shape}")
    if not d0 > 0:
        raise AutobonesError(f"wire: the dropoff distance must be positive, got {d0}")
    n, k = len(V), len(base)
    tree = tree or cKDTree(V)
    # candidates: within d0 of some point of the wire (balls around sample points of each segment)
    seg_len = np.linalg.norm(np.diff(base, axis=0), axis=1)
    samples = [base[:1]]
    for a, b, L in zip(base[:-1], base[1:], seg_len):
        m = max(1, int(np.ceil(L / d0)))
        samples.append(a + np.linspace(0.0, 1.0, m + 1)[1:, None] * (b - a))
    S = np.concatenate(samples)
    step = max(float(seg_len.max() / max(1, np.ceil(seg_len.max() / d0))), 0.0)
    near = tree.query_ball_point(S, d0 + 0.5 * step + 1e-12)
    idx = np.unique(np.concatenate([np.asarray(i, dtype=np.int64) for i in near])) if len(near) else np.zeros(0, int)
    if len(idx) == 0:
        return sp.csr_matrix((n, k))
    dist, seg, t = closest_on_polyline(V[idx], base)
    f = dropoff(dist / d0)
    if gate is not None:
        f = f * np.asarray(gate, dtype=np.float64)[idx]
    keep = f > 0
    idx, seg, t, f = idx[keep], seg[keep], t[keep], f[keep]
    rows = np.concatenate([idx, idx])
    cols = np.concatenate([seg, seg + 1])
    vals = np.concatenate([f * (1.0 - t), f * t])
    return sp.csr_matrix((vals, (rows, cols)), shape=(n, k))


class WireDeformer:
    """One wire deformer, scikit-learn style: configure, ``fit`` on the base wire, ``deform``.

    Parameters
    ----------
    dropoff_distance : float
        d0, in the units of the points.

    Attributes
    ----------
    weights_ : scipy.sparse.csr_matrix (n, k)
        Dropoff weight of every skin point on every control vertex.
    base_ : (k, 3) float
        The base wire.

    Example
    -------
    >>> w = WireDeformer(0.5).fit(V, base)
    >>> V2 = V + w.displacement(base + [0.0, 0.1, 0.0])
    """

    def __init__(self, dropoff_distance):
        self.dropoff_distance = dropoff_distance

    def fit(self, V, base, gate=None):
        self.base_ = np.asarray(base, dtype=np.float64)
        self.weights_ = wire_weights(np.asarray(V, dtype=np.float64), self.base_, float(self.dropoff_distance), gate)
        return self

    def displacement(self, deformed):
        """(n, 3) skin displacement for the deforming wire ``deformed`` (k, 3)."""
        deformed = np.asarray(deformed, dtype=np.float64)
        if deformed.shape != self.base_.shape:
            raise AutobonesError(f"wire: the deforming wire has shape {deformed.shape}, the base wire {self.base_.shape}")
        return self.weights_ @ (deformed - self.base_)
