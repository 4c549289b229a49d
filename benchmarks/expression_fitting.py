"""The fits of benchmarks/expressions.py (not benchmarks/expression_fit.py, which is another benchmark).

Bones alone (part 3): ``LBSFit``, per-bone affine transforms for fixed skin weights, and
``fit_rigid``, its rigid variant. The full expression rig (parts 1 and 2, "ict57", "ceiling"):
``fit_rig``, a grid over jaw and lids with bounded linear least squares over the contractions
(``_solve_linear``, or ``SharedSolves`` sharing the QRs between targets), then a nonlinear
refinement; and ``rotation_ceiling``, what one joint could explain with any weight field.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.sparse as sp

class LBSFit:
    """Least-squares per-bone affine transforms for fixed skin weights.

    ``W`` is (n, b) dense or scipy.sparse; the design matrix row i is
    ``kron(W[i], [v_i, 1])`` (4b columns), built once with its normal equations.
    """

    def __init__(self, V, W):
        self.V = np.asarray(V, float)
        self.c = self.V.mean(axis=0)
        self.s = np.abs(self.V - self.c).max()
        Vh = np.c_[(self.V - self.c) / self.s, np.ones(len(V))]  # (n, 4)
        W = sp.csr_matrix(W)
        W.eliminate_zeros()
        n, b = W.shape
        rows = np.repeat(np.arange(n), np.diff(W.indptr))
        cols, vals = W.indices, W.data
        # each weight becomes 4 entries: w * [x, y, z, 1] in columns 4j..4j+3
        R = np.repeat(rows, 4)
        C = (4 * np.repeat(cols, 4) + np.tile(np.arange(4), len(cols)))
        D = (vals[:, None] * Vh[rows]).ravel()
        self.M = sp.csr_matrix((D, (R, C)), shape=(n, 4 * b))
        self.G = (self.M.T @ self.M).toarray()
        self.b = b

    def fit(self, X):
        """Fitted positions (n, 3) and the parameters P (4b, 3), scaled frame."""
        Y = (np.asarray(X, float) - self.c) / self.s
        P = scipy.linalg.lstsq(self.G, self.M.T @ Y, lapack_driver="gelsy", cond=1e-13)[0]
        return self.unscale(self.M @ P), P

    def unscale(self, Y):
        return Y * self.s + self.c

    def affines(self, P):
        """(b, 3, 3) linear parts and (b, 3) translations in the scaled frame."""
        Pb = P.reshape(self.b, 4, 3)
        return np.transpose(Pb[:, :3, :], (0, 2, 1)), Pb[:, 3, :]


def _nearest_rotation(A):
    U, _, Vt = np.linalg.svd(A)
    d = np.sign(np.linalg.det(U @ Vt))
    return U @ np.diag([1.0, 1.0, d]) @ Vt


def fit_rigid(fit, W, X, sweeps=30):
    """Rigid per bone: block coordinate descent over bones, weighted Procrustes each.

    Minimises sum_i ||y_i - sum_j w_ij (R_j v_i + t_j)||^2 (scaled frame).
    Starts from the affine fit's linear parts projected to rotations (translations
    refitted by the first sweep). Returns fitted positions (n, 3), input frame.
    """
    W = sp.csc_matrix(W)
    V = (fit.V - fit.c) / fit.s
    Y = (np.asarray(X, float) - fit.c) / fit.s
    A, t = fit.affines(fit.fit(X)[1])
    Rs = np.array([_nearest_rotation(a) for a in A])
    ts = t.copy()
    cols = [(W.indices[W.indptr[j]:W.indptr[j + 1]], W.data[W.indptr[j]:W.indptr[j + 1]]) for j in range(W.shape[1])]

    def model():
        out = np.zeros_like(V)
        for j, (idx, w) in enumerate(cols):
            out[idx] += w[:, None] * (V[idx] @ Rs[j].T + ts[j])
        return out

    F = model()
    for _ in range(sweeps):
        for j, (idx, w) in enumerate(cols):
            if len(idx) < 3:
                continue
            own = w[:, None] * (V[idx] @ Rs[j].T + ts[j])
            r = Y[idx] - (F[idx] - own)          # what bone j should supply: w_i (R v_i + t)
            w2 = w * w
            sw2 = w2.sum()
            vbar = (w2[:, None] * V[idx]).sum(0) / sw2
            qbar = (w[:, None] * r).sum(0) / sw2  # weighted mean of r_i / w_i
            H = (V[idx] - vbar).T @ (w[:, None] * r - w2[:, None] * qbar)
            U, _, Vt = np.linalg.svd(H)
            d = np.sign(np.linalg.det(Vt.T @ U.T))
            R = Vt.T @ np.diag([1.0, 1.0, d]) @ U.T
            Rs[j], ts[j] = R, qbar - R @ vbar
            F[idx] += w[:, None] * (V[idx] @ R.T + ts[j]) - own
    return fit.unscale(model())


# fit_rig's search: stage 1's jaw (degrees) and lid grids; the bounds both stages keep to
JAW_GRID = np.arange(-2.0, 30.1, 2.0)
LID_GRID = np.linspace(-0.6, 1.3, 20)
LID_BOUNDS = (-0.6, 1.3)
JAW_BOUNDS = (-2.0, 30.0)
C_MAX = 2.0


def contraction_bounds(model):
    """(k,) lower and upper bounds: muscles only pull (>= 0), except the frontalis joints, which
    the model lengthens for AU4 (depressor supercilii is not among its muscles)."""
    lo = np.array([-0.5 if t.startswith("frontalis") else 0.0 for t in model.joints_.types])
    return lo, np.full(len(lo), C_MAX)


def _bounded_solve(R, qy, yy, lo, hi):
    """min ||M c - y|| within [lo, hi] from M's thin QR: R (k, k), qy = Q^T y (k,), yy = y . y.
    Returns (c, residual norm)."""
    import scipy.optimize

    c = scipy.optimize.lsq_linear(R, qy, bounds=(lo, hi), method="bvls").x
    r2 = float(np.sum((R @ c - qy) ** 2) + max(yy - qy @ qy, 0.0))
    return c, np.sqrt(r2)


def _solve_linear(model, X, sel, jaw, lids, lo, hi):
    """Best contractions for fixed jaw / lids: bounded linear least squares on the unclamped
    model (``linear_pose``) over the rows ``sel``, via a thin QR. Returns (c, residual norm)."""
    A, b = model.linear_pose(jaw, lids)
    M = A[:, sel].reshape(len(A), -1).T                  # (3 m, k)
    y = (X[sel] - b[sel]).ravel()
    Q, R = scipy.linalg.qr(M, mode="economic", check_finite=False)   # LAPACK geqrf, as np.linalg.qr, faster here
    return _bounded_solve(R, Q.T @ y, y @ y, lo, hi)


class SharedSolves:
    """``fit_rig``'s stage-1 solves for many targets on one model, sharing the work.

    The targets are ``base + D[name]`` ((n, 3), input frame) fitted over the rows ``masks[where]``.
    For a jaw angle and lid amounts, ``linear_pose`` and the thin QR of each mask's design matrix
    do not depend on the target: they are made once, with Q^T of every target's displacement, and
    kept; a target that visits the same grid point again (most do: the jaw grid at lids 0 is the
    same for all, lids are mostly searched at the same jaw) costs a 26-unknown solve. Same answer
    as ``_solve_linear`` up to rounding. ``solver(name, where)`` is ``fit_rig``'s ``solve``.
    """

    def __init__(self, model, base, D, masks):
        self.model, self.masks, self.names = model, masks, list(D)
        self.lo, self.hi = contraction_bounds(model)
        self.E = {w: np.stack([np.asarray(D[n], float)[m].ravel() for n in self.names]) for w, m in masks.items()}
        self.EE = {w: np.einsum("sv,sv->s", E, E) for w, E in self.E.items()}
        self.base = np.asarray(base, float)
        self.cache, self.misses, self.calls = {}, 0, 0

    def _entry(self, jaw, lids):
        key = (round(float(jaw), 9), tuple(np.round(np.asarray(lids, float), 9)))
        if key not in self.cache:
            self.misses += 1
            A, b = self.model.linear_pose(jaw, lids)
            ent = {}
            for w, sel in self.masks.items():
                M = A[:, sel].reshape(len(A), -1).T
                Q, R = scipy.linalg.qr(M, mode="economic", check_finite=False)
                y0 = (self.base[sel] - b[sel]).ravel()
                ent[w] = (R, Q.T @ y0, Q.T @ self.E[w].T, y0 @ y0, self.E[w] @ y0)
            self.cache[key] = ent
        return self.cache[key]

    def solver(self, name, where):
        s = self.names.index(name)

        def solve(jaw, lids):
            self.calls += 1
            R, qy0, qE, y0y0, Ey0 = self._entry(jaw, lids)[where]
            return _bounded_solve(R, qy0 + qE[:, s], y0y0 + 2 * Ey0[s] + self.EE[where][s], self.lo, self.hi)

        return solve


def fit_rig(model, X, sel, refine=30, solve=None):
    """Rig parameters reproducing the target positions ``X`` (n, 3) over the vertices ``sel``.

    Stage 1 (variable projection on a grid): for a jaw angle and lid amounts the pose is affine in
    the muscle contractions (skull clamp aside), solved by bounded linear least squares; the jaw is
    searched on a 2-degree grid (lids 0), then each of the 4 lids on a 0.1 grid in turn (the
    others held); a second such sweep (the jaw grid again with those lids, the lids again),
    then the jaw on a 0.5-degree grid around its best. ``solve(jaw, lids) -> (c, residual norm)``
    replaces that solve (``SharedSolves.solver``; default ``_solve_linear`` on ``X``).
    Stage 2: ``scipy.optimize.least_squares`` (trf, finite differences, ``refine`` evaluations
    at most) over all 31 parameters of the full nonlinear pose (``pose_parameters``, skull clamp
    included), from stage 1, within the same bounds. Returns (contractions, jaw, lids, info).
    """
    import scipy.optimize

    lo, hi = contraction_bounds(model)
    if solve is None:
        def solve(j, l):
            return _solve_linear(model, X, sel, j, l, lo, hi)
    lids = np.zeros(4)
    jaw = 0.0
    for sweep in range(2):
        jaw = min((solve(j, lids)[1], j) for j in JAW_GRID)[1]
        for q in range(4):
            trials = []
            for a in LID_GRID:
                l2 = lids.copy()
                l2[q] = a
                trials.append((solve(jaw, l2)[1], a))
            lids[q] = min(trials)[1]
    fine = np.clip(jaw + np.arange(-2.0, 2.01, 0.5), *JAW_BOUNDS)
    jaw = min((solve(j, lids)[1], j) for j in fine)[1]
    c, _ = solve(jaw, lids)
    x0 = np.r_[c, jaw, lids]
    k = len(c)

    def resid(x):
        return (model.pose_parameters(x[:k], x[k], x[k + 1:]) - X)[sel].ravel()

    r0 = np.linalg.norm(resid(x0))
    info = {"stage1": r0, "stage2": r0}
    if refine:
        lb = np.r_[lo, JAW_BOUNDS[0], np.full(4, LID_BOUNDS[0])]
        ub = np.r_[hi, JAW_BOUNDS[1], np.full(4, LID_BOUNDS[1])]
        res = scipy.optimize.least_squares(resid, np.clip(x0, lb, ub), bounds=(lb, ub), method="trf",
                                           x_scale=np.r_[np.full(k, 0.3), 5.0, np.full(4, 0.3)],
                                           diff_step=1e-3, max_nfev=refine)
        r1 = np.linalg.norm(res.fun)
        if r1 < r0:
            x0, info["stage2"] = res.x, r1
    return x0[:k], float(x0[k]), x0[k + 1:], info


def rotation_ceiling(model, X, pivot, degrees, glide=None):
    """Best per-vertex rotation about the canonical +X axis through ``pivot``: each vertex picks
    its own angle from ``degrees`` (plus ``glide`` (3,) per degree, canonical, the jaw's condyle
    glide) to match the target positions ``X`` (n, 3, input frame). Free per-vertex angles are
    any weight field a joint could have, so this bounds what that joint can explain.
    Returns the fitted positions (n, 3), input frame."""
    from autobones.geometry.rotations import x_turn

    Vc = model.canonical_
    D = model.frame_.to_canonical(X) - Vc
    P = Vc - pivot
    best, res = np.zeros_like(Vc), np.linalg.norm(D, axis=1)
    for a in degrees:
        d = x_turn(P, np.radians(a))
        if glide is not None:
            d = d + a * glide[None, :]
        r = np.linalg.norm(D - d, axis=1)
        b = r < res
        res[b], best[b] = r[b], d[b]
    return model.frame_.from_canonical(Vc + best)

