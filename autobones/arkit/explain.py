"""How much of a real expression a rig's shapes can make: the best weights and the explained fraction.

A captured expression (a neutral mesh and the same mesh posed, vertex for vertex) is a displacement
field; a rig's blendshapes (its 52 ARKit targets, its FACS AU morph targets) span a space of them.
The best weights in ARKit's range [0, 1] are found by bounded linear least squares
(:func:`scipy.optimize.lsq_linear`, the trust-region reflective method), and the explained fraction
is ``1 - |residual| / |displacement|`` over the vertices judged: 1 when the shapes make the
expression exactly, 0 when they do no better than the neutral, below 0 when worse. A capture
often carries the head's own motion too; :func:`rigid_align` takes out the rigid part first, fitted
to the vertices that move least (the skull), so the face's motion is what is scored.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import lsq_linear

from ..geometry.rotations import similarity

from ..errors import AutobonesError, counted


def rigid_align(V, V_rest, keep=0.5, iterations=5):
    """``V`` (n, 3) moved rigidly onto ``V_rest`` (n, 3) by the rotation and translation that best
    match the ``keep`` fraction of vertices that move least (refitted ``iterations`` times); same
    units. Returns the aligned (n, 3) copy."""
    V, V_rest = np.asarray(V, dtype=np.float64), np.asarray(V_rest, dtype=np.float64)
    X = V.copy()
    sel = np.arange(len(V))
    for _ in range(iterations):
        a, b = X[sel], V_rest[sel]
        ca, cb = a.mean(axis=0), b.mean(axis=0)
        R = similarity(b, a)[1]   # takes b onto a as columns, so a onto b as rows
        X = (X - ca) @ R + cb
        d = np.linalg.norm(X - V_rest, axis=1)
        sel = np.argsort(d, kind="stable")[: max(3, int(keep * len(V)))]
    return X


def explain(displacement, targets, mask=None, bounds=(0.0, 1.0)):
    """Best weights of ``targets`` for one ``displacement`` and the fraction they explain.

    Parameters
    ----------
    displacement : (n, 3) float
        The expression minus the neutral, mesh units.
    targets : dict str -> (n, 3) float
        Shape displacements at weight 1, same vertices and units.
    mask : (n,) bool, optional
        The vertices judged (e.g. the skin: the largest connected part); None: all.
    bounds : (float, float)
        Weight range (ARKit's [0, 1]; ``(0, inf)`` for non-negative least squares).

    Returns
    -------
    weights : dict str -> float
        Per target, in ``bounds`` (0 for a target that moves none of the judged vertices).
    explained : float
        ``1 - |A w - d| / |d|`` over the judged vertices (Frobenius norms).
    """
    d = np.asarray(displacement, dtype=np.float64)
    names = list(targets)
    if not names:
        raise AutobonesError("explain: no target shapes to explain the expression with")
    bad = [n for n in names if np.shape(targets[n]) != d.shape]
    if d.ndim != 2 or d.shape[1:] != (3,) or bad:
        raise AutobonesError(f"explain: the expression's displacement is {d.shape}, "
                             + (f"the target {bad[0]} {np.shape(targets[bad[0]])}" if bad else "not (n, 3)"))
    m = np.ones(len(d), dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    if m.shape != (len(d),):
        raise AutobonesError(f"explain: a mask of {m.shape} for {counted(len(d), 'vertex', 'vertices')}")
    A = np.stack([np.asarray(targets[n], dtype=np.float64)[m].ravel() for n in names], axis=1)
    b = d[m].ravel()
    norm = float(np.linalg.norm(b))
    if norm == 0.0:
        return {n: 0.0 for n in names}, 1.0
    # a target that moves nothing here (tongueOut on a head without a tongue) has no weight to find
    live = np.linalg.norm(A, axis=0) > 0
    w = np.zeros(len(names))
    if live.any():
        w[live] = np.clip(lsq_linear(A[:, live], b, bounds=bounds, method="trf", lsmr_tol="auto").x, *bounds)
    return dict(zip(names, map(float, w))), 1.0 - float(np.linalg.norm(A @ w - b)) / norm


def cosine_and_size(pred, truth, mask=None):
    """Cosine between two displacement fields (n, 3) and the size ratio |pred| / |truth|, over ``mask``."""
    m = slice(None) if mask is None else np.asarray(mask, dtype=bool)
    p, t = np.asarray(pred, dtype=np.float64)[m].ravel(), np.asarray(truth, dtype=np.float64)[m].ravel()
    nt, np_ = float(np.linalg.norm(t)), float(np.linalg.norm(p))
    if nt == 0.0 or np_ == 0.0:
        return 0.0, (np_ / nt if nt else float("inf"))
    return float(p @ t) / (np_ * nt), np_ / nt
