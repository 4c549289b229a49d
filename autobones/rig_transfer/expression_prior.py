"""The expression a target head wears, as weights of a linear expression space on the source skin.

A scan is often not neutral: an open jaw, a smile, a pucker. The landmarks' thin-plate spline carries
the neutral generic skin smoothly onto it, and between the landmarks the smooth warp and the fit's
shape term (which keeps the source's own edges) pull the skin back toward a neutral face: the lips
and cheeks slide (benchmarks/correspondence.py ``--families``). Model-based face fitting solves this
by fitting the expression coefficients of a linear blendshape model together with its identity
coefficients (Blanz & Vetter 1999; Li, Bolkart, Black, Li & Romero 2017, FLAME, by landmarks and
scan-to-mesh distance). Here the expression space is a set of displacement fields on the source skin
(ICT-FaceKit's expressions, Li et al. 2020) and, optionally, identity modes of the same skin (ICT's
20 principal components, one standard deviation each), solved together so that a face's own shape
is not taken for an expression::

    w*, a* = argmin  mean_i (n_i . (T(v_i + E_i w + I_i a) - c_i) / rho)^2 + strength ||w||^2 + s_id ||a||^2
             0 <= w <= 1, |a| <= 3

- ``v_i + E_i w + I_i a``: source vertex ``i`` wearing the expression ``w`` (k weights) and the identity
  ``a`` (j weights); the landmarks move with their triangles;
- ``T``: the thin-plate spline from the posed source landmarks to the target's, so the warp absorbs
  whatever the landmarks say and the weights are decided by the surface *between* them;
- ``c_i``, ``n_i``: the nearest target vertex and its normal (point to plane), matches whose normals
  differ by more than 60 degrees or that lie beyond 5 times the median distance dropped (as the fit);
- ``rho``: the target landmarks' RMS radius, so the cost has no unit.

The identity alone is solved first; the expression is kept only when it removes :data:`MIN_GAIN` of
what the identity alone leaves, on a head the identity alone fits within :data:`MAX_MISFIT` (a bunny is
no human face to wear a smile). Bounded Gauss-Newton with the matches refreshed each round, on at
most :data:`SAMPLE` vertices; the Jacobian to first order through the spline (its landmark weights and
derivative at each sample point, :meth:`autobones.geometry.tps.ThinPlateSpline.cardinal` and
``jacobian``); each step a bounded least squares (``scipy.optimize.lsq_linear``) on the k rows of its
normal equations' Cholesky factor, halved until the cost drops.

``transfer`` solves it on the ARKit set's skin (:func:`shape_set_expression`: a real face, with its
identity modes) and the generic skin wears the weights found, through the same ARKit shapes carried
onto it (``expressions=`` of :func:`autobones.rig_transfer.correspondence.fit_surface`); the generic's
own skin would take its difference from a real face for an expression.
"""
from __future__ import annotations

import numpy as np
from scipy.linalg import solve_triangular
from scipy.optimize import lsq_linear
from scipy.spatial import cKDTree

from ..errors import AutobonesError
from ..geometry.closest import closest_points
from ..geometry.landmark_warp import nearest_landmark
from ..geometry.normals import vertex_normals
from ..geometry.rotations import similarity
from ..geometry.topology import mesh_parts
from ..geometry.tps import ThinPlateSpline

# at most this many source vertices in the solve (every j-th of the candidates: deterministic)
SAMPLE = 1500
# weight of ||w||^2 against the mean squared point-to-plane residual in units of the landmark radius
STRENGTH = 2e-5
ROUNDS = 4
MAX_ANGLE = 60.0
# the weights are kept only when they lower the cost without an expression (the identity alone,
# refreshed matches) by this share, and only on a head the identity alone fits within MAX_MISFIT
# (RMS point-to-plane residual, landmark radii). Measured (benchmarks/README.md, "The expression-aware
# fit"): ICT's expressions in the space gain 0.8-0.97; left out of it a pucker 0.50-0.62, an open jaw
# 0.30-0.53, a smile 0.18-0.43; neutral heads 0.02-0.33 (ICT's identities) and 0.07-0.26 (james, Lee
# Perry-Smith, the menpo3d template, SMPL). At 0.4 the SMPL woman wore a smile (an earlier solver,
# gain 0.47) and lost two zoo cells: a neutral head stays neutral first. Heads the human modes do not
# fit (misfit 0.14-0.18: a bunny, an armadillo, a chess knight) are never given a human expression
MIN_GAIN = 0.5
MAX_MISFIT = 0.1
# identity modes (``identity=``): weight of ||alpha||^2 (modes scaled to one standard deviation) and
# the bound on each weight
IDENTITY_STRENGTH = 2e-6
ID_BOUND = 3.0


# shapes that are not an expression of the skin of their own: gaze and pupils turn the eyeballs,
# mouthClose is jawOpen's corrective (alone it folds the mesh), tongueOut has no skin
NOT_SKIN = ("eyeLook", "PupilDilate", "mouthClose", "tongueOut")


def space_from_deltas(deltas, n):
    """The expression space of named displacement fields ``deltas`` (name -> (n, 3), e.g. an ARKit
    :class:`autobones.arkit.shapes.ShapeSet`'s): ``{"names", "basis" (k, n, 3)}`` without the
    :data:`NOT_SKIN` shapes and shapes that do not move; None when nothing is left."""
    names = [k for k in deltas if not k.startswith(NOT_SKIN) and np.abs(deltas[k]).max() > 0]
    if not names:
        return None
    return {"names": names, "basis": np.stack([np.asarray(deltas[k], dtype=np.float64).reshape(n, 3)
                                               for k in names])}


def weights_by_name(names, given):
    """(k,) weights in [0, 1] of the space's ``names`` from ``given`` ({name: weight}); names it lacks weigh 0."""
    return np.array([float(np.clip(given.get(n, 0.0), 0.0, 1.0)) for n in names])


def check_space(expressions, n):
    """The expression space ``{"names": [k], "basis": (k, n, 3)}`` checked against a source of ``n``
    vertices; returns names (list), basis (k, n, 3) float64."""
    try:
        names, basis = list(expressions["names"]), np.asarray(expressions["basis"], dtype=np.float64)
    except (KeyError, TypeError) as e:
        raise AutobonesError("expressions must be a dict with 'names' and 'basis' (k, n, 3)") from e
    if basis.ndim != 3 or basis.shape[1:] != (n, 3) or len(names) != len(basis):
        raise AutobonesError(f"expressions: basis must be ({len(names)}, {n}, 3) for this source, got {basis.shape}")
    if not np.isfinite(basis).all():
        raise AutobonesError("expressions: basis contains NaN or infinite values")
    return names, basis


def pose(V, basis, w):
    """``V`` (n, 3) wearing the weights ``w`` (k,) of ``basis`` (k, n, 3): ``V + sum_k w_k basis_k``."""
    return V + np.tensordot(np.asarray(w, dtype=np.float64), basis, axes=1)


def _sample(V_src, F_src, P, basis):
    """Source vertices of the solve: on the largest part (the skin), moved by the space or within the
    landmarks' RMS radius of a landmark; every j-th of them, at most :data:`SAMPLE`."""
    part = mesh_parts(len(V_src), F_src)
    skin = part == np.argmax(np.bincount(part))
    motion = np.linalg.norm(basis, axis=2).max(axis=0)
    d, r = nearest_landmark(P, V_src)
    near = d < r
    idx = np.flatnonzero(skin & ((motion > 0.02 * motion.max()) | near))
    return idx[::max(1, -(-len(idx) // SAMPLE))]


class _Residuals:
    """Point-to-plane residuals (m,) of the sample warped with the parameters ``theta`` (columns of
    ``basis``): ``warp``, ``matches`` (refreshed targets) and ``cost`` (mean square plus the penalty)."""

    def __init__(self, V_src, F_src, P, Q, V_tgt, F_tgt, basis, penalty):
        self.V_src, self.F_src, self.Q, self.basis, self.penalty = V_src, F_src, Q, basis, penalty
        self.idx = idx = _sample(V_src, F_src, P, basis)
        _, lface, lbary, _ = closest_points(P, V_src, F_src)
        E = np.concatenate([basis[:, idx], np.einsum("lj,kljd->kld", lbary, basis[:, F_src[lface]])], axis=1)
        self.E = np.ascontiguousarray(E.reshape(len(E), -1))   # (k, 3 (m + L)): one product per warp
        self.base = np.concatenate([V_src[idx], P])
        self.m = len(idx)
        self.V_tgt, self.N_tgt, self.tree = V_tgt, vertex_normals(V_tgt, F_tgt), cKDTree(V_tgt)
        self.rho = np.sqrt(((Q - Q.mean(axis=0)) ** 2).sum(axis=1).mean())

    def warp(self, theta):
        Y = self.base + (theta @ self.E).reshape(-1, 3)
        return ThinPlateSpline().fit(Y[self.m:], self.Q).transform(Y[:self.m])

    def matches(self, theta):
        X = self.warp(theta)
        j = self.tree.query(X)[1]
        c, nrm = self.V_tgt[j], self.N_tgt[j]
        d = np.abs(np.einsum("ij,ij->i", X - c, nrm))
        # the source normals turned by the sample's best rotation onto its warp (the face's warp is
        # close to a similarity): enough to reject a match facing the other way
        turn = similarity(self.V_src[self.idx], X)[1]
        normals = vertex_normals(pose(self.V_src, self.basis, theta), self.F_src)[self.idx] @ turn.T
        keep = (d <= 5.0 * np.median(d) + 1e-12) & (np.einsum("ij,ij->i", normals, nrm) >= np.cos(np.radians(MAX_ANGLE)))
        return c, nrm, keep

    def __call__(self, theta, c, nrm, keep):
        return np.where(keep, np.einsum("ij,ij->i", self.warp(theta) - c, nrm), 0.0) / self.rho

    def jacobian(self, theta, target):
        """(m, k): the residuals' derivatives at ``theta`` with the matches ``target`` held. First order in
        both moves: a sample point moved by ``e_i`` and the landmarks by ``e_L`` warps to
        ``X_i + (e_i - S_i e_L) J_i`` (``S``: the spline's weights of each landmark at the point,
        ``J_i``: its derivative there), since the refitted spline still takes each moved landmark to
        its target. One spline's weights per round instead of a refit per column (0.8 s of a 3 s
        transfer before)."""
        c, nrm, keep = target
        Y = self.base + (theta @ self.E).reshape(-1, 3)
        tps = ThinPlateSpline().fit(Y[self.m:], self.Q)
        S = tps.cardinal(Y[:self.m])                                            # (m, L)
        v = np.einsum("iab,ib->ia", tps.jacobian(Y[:self.m]), nrm)               # J_i n_i
        E = self.E.reshape(len(self.E), -1, 3)
        D = E[:, :self.m] - np.einsum("il,klj->kij", S, E[:, self.m:])           # (k, m, 3)
        return np.where(keep[:, None], np.einsum("kij,ij->ik", D, v), 0.0) / self.rho

    def cost(self, theta, target=None):
        r = self(theta, *(self.matches(theta) if target is None else target))
        return float(np.mean(r ** 2) + self.penalty @ theta ** 2)


def _gauss_newton(res, free, lo, hi, rounds, theta=None):
    """Bounded Gauss-Newton on the columns ``free`` (bool (k,)) of ``res`` from ``theta`` (default 0);
    returns theta (k,) and the cost at the start (its own matches)."""
    theta = np.zeros(len(free)) if theta is None else theta.copy()
    cols = np.flatnonzero(free)
    pen = res.penalty[cols]
    first = None
    for _ in range(rounds):
        target = res.matches(theta)
        r0 = res(theta, *target)
        now = res.cost(theta, target)
        first = now if first is None else first
        J = res.jacobian(theta, target)[:, cols]
        # min ||J d + r0||^2 / m + sum pen (theta + d)^2 within the bounds, as len(cols) rows
        # (R^T R = J^T J / m + diag(pen)): the same bounded problem without the m sample rows, which
        # BVLS would otherwise factor many times over
        R = np.linalg.cholesky(J.T @ J / res.m + np.diag(pen)).T
        rhs = solve_triangular(R, -(J.T @ r0) / res.m - pen * theta[cols], trans="T")
        step = lsq_linear(R, rhs, bounds=(lo[cols] - theta[cols], hi[cols] - theta[cols]), method="bvls").x
        for _ in range(5):   # halved while the cost (same matches) does not drop: far from linear at 1
            trial = theta.copy()
            trial[cols] = np.clip(theta[cols] + step, lo[cols], hi[cols])
            if res.cost(trial, target) < now:
                theta = trial
                break
            step = 0.5 * step
    return theta, first


def fit_expression(V_src, F_src, P, Q, V_tgt, F_tgt, expressions, identity=None, strength=STRENGTH,
                   identity_strength=IDENTITY_STRENGTH, rounds=ROUNDS, details=None):
    """The weights of the expression the target wears (module doc).

    Parameters
    ----------
    V_src, F_src : (n, 3) float, (m, 3) int
        The source skin (source frame and units), as the fit will warp it (a jaw prior already applied).
    P, Q : (L, 3) float
        Source landmarks (on or near the source skin) and the target's, row for row, each in its frame.
    V_tgt, F_tgt : (n_t, 3) float, (m_t, 3) int
        The target mesh (its own frame and units).
    expressions : dict
        ``names`` (k,) and ``basis`` (k, n, 3): displacements of the source vertices at weight 1, source units.
    identity : (j, n, 3) float, optional
        Identity modes of the source skin (a morphable model's principal components scaled to one
        standard deviation, source units): solved with the expression (weights within +-3, penalty
        ``identity_strength * ||alpha||^2``) so that the head's own shape is not taken for an
        expression; the expression is kept only when it lowers the cost of the identity alone by
        :data:`MIN_GAIN`.
    strength, identity_strength : float
        Weights of ``||w||^2`` and ``||alpha||^2`` (dimensionless, see the module doc).
    rounds : int
        Gauss-Newton rounds (matches refreshed each).
    details : dict, optional
        Filled with ``weights`` ({name: weight} of the weights over 0.05, largest first; empty when
        the head is taken as neutral) and ``gain`` (the share of the cost without an expression that
        the weights remove; under :data:`MIN_GAIN` they are dropped).

    Returns
    -------
    w : (k,) float64 in [0, 1]
    """
    names, basis = check_space(expressions, len(V_src))
    k = len(names)
    V_src, P, Q = (np.asarray(a, dtype=np.float64) for a in (V_src, P, Q))
    j = 0
    if identity is not None:
        identity = np.asarray(identity, dtype=np.float64)
        j = len(identity)
        basis = np.concatenate([basis, identity])
    res = _Residuals(V_src, F_src, P, Q, V_tgt, F_tgt, basis, np.r_[np.full(k, strength), np.full(j, identity_strength)])
    lo, hi = np.r_[np.zeros(k), np.full(j, -ID_BOUND)], np.r_[np.ones(k), np.full(j, ID_BOUND)]
    start = None
    if j:   # the identity alone first: its cost is what an expression has to improve on, and the start
        start, _ = _gauss_newton(res, np.r_[np.zeros(k, dtype=bool), np.ones(j, dtype=bool)], lo, hi, rounds)
    theta, neutral = _gauss_newton(res, np.ones(k + j, dtype=bool), lo, hi, rounds, start)
    gain = 1.0 - res.cost(theta) / neutral if neutral > 0 else 0.0
    misfit = float(np.sqrt(max(neutral, 0.0)))
    w = theta[:k] if gain >= MIN_GAIN and misfit <= MAX_MISFIT else np.zeros(k)
    if details is not None:
        order = np.argsort(-w, kind="stable")
        details.update(weights={names[i]: round(float(w[i]), 3) for i in order if w[i] > 0.05},
                       gain=round(float(gain), 3), misfit=round(misfit, 4),
                       identity=round(float(np.sqrt(np.mean(theta[k:] ** 2))) if j else 0.0, 3))
    return w


def shape_set_expression(shapes, V_tgt, F_tgt, landmarks, identity=None, min_landmarks=10):
    """The expression a head seems to wear, solved on a shape set's own skin (:func:`fit_expression`).

    Parameters
    ----------
    shapes : ShapeSet
        ``vertices``, ``faces``, ``landmarks`` and ``deltas`` (:class:`autobones.arkit.shapes.ShapeSet`;
        the packaged one is ICT-FaceKit's ARKit set: a real face, so what the warp leaves between the
        landmarks of a human head is mostly its expression, not its identity).
    V_tgt, F_tgt : (n_t, 3) float, (m_t, 3) int
        The head, its own frame and units.
    landmarks : dict str -> (3,) float
        The head's landmarks, same frame.
    identity : (j, n_s, 3) float, optional
        Identity modes of the set's skin (:func:`fit_expression`).

    Returns
    -------
    weights : dict str -> float
        Every skin expression of the set and its weight in [0, 1] (all 0: neutral); empty when the
        head shares fewer than ``min_landmarks`` landmarks with the set.
    details : dict
        As :func:`fit_expression`'s.
    """
    shared = [n for n in shapes.landmarks if n in landmarks]
    space = space_from_deltas(shapes.deltas, len(shapes.vertices))
    if len(shared) < min_landmarks or space is None:
        why = (f"{len(shared)} landmarks shared with the shape set, {min_landmarks} needed" if space is not None
               else "the shape set has no skin expression")
        return {}, {"weights": {}, "gain": 0.0, "note": why}
    P = np.array([shapes.landmarks[n] for n in shared], dtype=np.float64)
    Q = np.array([landmarks[n] for n in shared], dtype=np.float64)
    details = {}
    w = fit_expression(shapes.vertices, shapes.faces, P, Q, V_tgt, F_tgt, space, identity, details=details)
    return dict(zip(space["names"], (float(x) for x in w))), details
