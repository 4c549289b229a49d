"""Can the rig express a face?  Issue #4's proof: the full expression rig's fit (1) and
transfer (2), and the placed bones alone (3).

Run by hand, not by the tests::

    python benchmarks/expressions.py            # everything (~4 min on 2 cores)
    python benchmarks/expressions.py --part rig # parts 1 and 2 only (~8 min with --refine 0, 2026-12-02)
    python benchmarks/expressions.py --part rig --refine 0   # no nonlinear refinement
    python benchmarks/expressions.py --quick    # bones: sparse and dense only, no rigid variant
    python benchmarks/expressions.py --sweeps 60  # more rigid block-descent sweeps
    python benchmarks/expressions.py --part ict57 --refine 0   # ICT's AU shapes, remeshed transfer (~20 min)
    python benchmarks/expressions.py --part ict57 --shapes jawOpen eyeBlink_L --identities identity003
    python benchmarks/expressions.py --part ceiling   # what any contractions of the fields could explain (~8 min)
    python benchmarks/expressions.py --part au-shapes # AUs through the head's ARKit shapes vs muscles (~5 min)
    python benchmarks/expressions.py --captures NEUTRAL.obj A.obj B.obj --landmarks L.json   # your own captures

Part "au-shapes" (issue #34 item 2; not run by "all"): benchmarks/au_shapes.py, see its docstring.
``--captures`` (issue #34 item 4): the rest of the command line goes to benchmarks/captures.py, which
scores a rig on any neutral and its expressions (ARKit and AU targets' explained fraction, presets).

Parts 1 and 2 (``full_rig_benchmark``): identity002 rigged by ``transfer`` with its
landmarks, ``ExpressionModel`` fitted to each expression (``fit_rig``: grid over
jaw and lids with bounded linear least squares over the muscle contractions (40 since the sphincters), then
``scipy.optimize.least_squares`` on the full nonlinear pose), on all vertices and
on the skin only; the same parameters applied to identity000 and identity001,
with the baselines neutral, copy by vertex index (100 % by construction: ICT's
identities share one displacement per expression) and copy through the
transfer's dense correspondence (``copy_through``). Scores per vertex set: all,
skin (``model.skin_``), parts (the rest) and the skin regions of the transferred
``region`` field (``REGIONS``).

Ceilings (after the table): what one joint could explain with ANY weight field, on identity002:
each vertex turns about the joint's axis (canonical +X through its pivot) by its own best angle
(``rotation_ceiling``; 0.5-degree grid), for the left upper lid in eyeBlink_L and the jaw (with its
condyle glide) in jawOpen. Where this is below the target, no lid or jaw weights can reach it and
the rest must come from the muscles.

Part 3, bones alone, follows.

Part "ict57" (``ict57_benchmark``, issue #16 item 3; not run by "all"): every ICT-FaceKit shape the
AU <-> ARKit table maps (``au_arkit`` in ``generic_rig/expressions.json``: 34 shapes, both halves
where ICT splits them, from ``ict_facekit_shapes.npz``) fitted by ``fit_rig`` on identity002 (ICT's
triangulation; skin and all, as above), and the same parameters applied on identity000 and
identity001 **remeshed** (``remesh`` of benchmarks/arkit.py: one Loop subdivision, then
``fast_simplification`` back; no vertex or triangle is ICT's), each rigged by ``transfer`` with
ICT's neutral landmarks carried onto it as benchmarks/arkit.py's ``run_identity`` does. The truth
at a remeshed vertex is the ICT displacement interpolated at its closest point on the identity,
in the part it came from. Beside it, the copy through the correspondence (``copy_through``).
Stage 1's grid solves are shared between the shapes (``SharedSolves``: ``linear_pose`` and its QR
do not depend on the target), which gives ``_solve_linear``'s answers (checked at the start).
The "tissue" columns pose the same fitted parameters with the layered tissue pass (issue #16 item 1,
``pose_parameters(..., tissue=True)``); the fit does not search through the tissue.

Data: ICT-FaceKit (``../shared/data/ict``), a linear model whose neutral head
``generic_neutral_mesh.obj`` and four real expression shapes (``jawOpen``,
``mouthSmile_L``, ``eyeBlink_L``, ``browInnerUp_L``) share one vertex list
(26,719 vertices; ``load_mesh`` keeps the file's order, which is checked).

Rigs: ``autobones.place`` of the neutral head at sparse / medium / dense, and
dense with the head's landmarks (adds the transferred jaw and eye bones, facial
bones parented to head or jaw). Plus two references: "neutral" (no motion, 0 %)
and "global affine" (one bone weighted 1 everywhere).

Fit, weights FIXED: the best per-bone transforms reproducing an expression by
linear blend skinning, x_i ~ sum_j w_ij (A_j v_i + t_j), A_j a free 3x3 affine,
t_j a translation (12 unknowns per bone). Each output coordinate c separates:
x_ic = sum_j w_ij [v_i, 1] . p_jc, an (n x 4b) sparse design matrix solved three
times through its (4b x 4b) normal equations (``scipy.linalg.lstsq`` on them,
so bones the data do not pin down get the minimum-norm answer). Coordinates are
centred and scaled before the solve, for conditioning. Two weight sets:

- "4 infl": ``autobones.io.gltf.top_influences(W, 4)``, the weights as exported;
- "all": the full ``rig.weights``.

Optional "rigid" variant (skin, 4 influences, A_j a rotation): block coordinate
descent, each bone in turn solved by weighted Procrustes against what the other
bones leave, started from the affine fit projected to rotations; ``--sweeps``
Gauss-Seidel sweeps (never worse than its start, which is checked).

Metric (issue #4): explained = 1 - ||residual|| / ||displacement||, Frobenius
norms over a vertex set, displacement = expression - neutral, residual =
fitted - expression; 100 % is exact, 0 % is no better than not moving
(negative: the fit moves a region more wrongly than leaving it still).

The ICT mesh is 56 connected parts: the skin (the largest, 14,062 vertices:
face, scalp, ears, neck, mouth and eye sockets) plus teeth, gums, tongue,
eyeballs and eye-blend shells. Those inner parts carry most of some
expressions' displacement (jawOpen: 232.6 over all vertices, 129.4 on the
skin; eyeBlink_L 22.8 vs 8.8) and get bone-heat weights from bones they are not
attached to. So two fits per row:

- all: fitted and scored over every vertex (the issue's literal wording);
- skin: fitted and scored over the skin only, and from that same skin fit,
- lower / upper: the skin's "moved" vertices (||displacement|| > 1 % of that
  expression's largest on the skin) below / at or above the nose tip (landmark
  ``pronasale``; the mesh is +Y up). Fewer than 50 moved vertices in a region
  prints "-".

Lip check: the lips are the skin vertices of region ``lips`` of the transferred
labelled generic rig (the same on every rig: one mesh) on the outer surface
(z > cheilion z - 0.7; deeper ones are the mouth socket); upper lip above the
line stomion -> cheilion (in |x|), lower below, mouth corners (|x| > 0.8 of the
cheilion's) left out. A lip vertex is "mixed" when a bone other than ``head``
gives it weight >= 0.2 and also gives weight >= 0.2 to some vertex of the
other lip (full weights). ``head`` is left out: it is the parent that stays
still, not a mouth bone.

Self-check before the table: the neutral shape is fitted with zero residual
(identity transforms), and a rigid motion of the whole head is explained
>= 99.9 % by every rig and weight set.
"""
from __future__ import annotations

import argparse
import datetime
import json
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg
import scipy.sparse as sp

import autobones
from autobones.io.gltf import top_influences
from autobones.io.mesh import load_mesh
from autobones.geometry.topology import mesh_parts

ICT = Path(__file__).resolve().parents[2] / "shared" / "data" / "ict"
NEUTRAL = ICT / "generic_neutral_mesh.obj"
LANDMARKS = ICT / "generic_neutral_mesh.landmarks.json"
EXPRESSIONS = ["jawOpen", "mouthSmile_L", "eyeBlink_L", "browInnerUp_L"]


# ---------------------------------------------------------------- fitting
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


def explained(fitted, X, V, sel=None):
    """1 - ||fitted - X|| / ||X - V|| over the vertices ``sel`` (all if None); nan if nothing moves."""
    if sel is not None:
        fitted, X, V = fitted[sel], X[sel], V[sel]
    d = np.linalg.norm(X - V)
    return np.nan if d == 0 else 1.0 - np.linalg.norm(fitted - X) / d


# ---------------------------------------------------------------- rigs
def sparse_top4(W):
    J, w = top_influences(W, 4)
    n = len(W)
    M = sp.csr_matrix((w.astype(np.float64).ravel(), (np.repeat(np.arange(n), J.shape[1]), J.ravel())), shape=W.shape)
    M.sum_duplicates()  # unused slots are (joint 0, weight 0)
    return M


def lips(V, lm, region_field, region_names, skin):
    """Boolean masks (upper lip, lower lip) on the neutral head."""
    on = (region_field == region_names.index("lips")) & skin & (V[:, 2] > lm["cheilion_l"][2] - 0.7)
    st, ch = np.asarray(lm["stomion"]), np.asarray(lm["cheilion_l"])
    ax = np.abs(V[:, 0])
    line = st[1] + (ch[1] - st[1]) * np.clip(ax / ch[0], 0, 1)
    inner = on & (ax < 0.8 * ch[0])
    return inner & (V[:, 1] > line), inner & (V[:, 1] <= line)


def lip_mixing(W, names, up, lo, thr=0.2):
    """Lip vertices carrying >= thr of a non-head bone that also weights the other lip >= thr."""
    W = np.asarray(W)
    big = W >= thr
    span = big[up].any(axis=0) & big[lo].any(axis=0)
    if "head" in names:
        span[names.index("head")] = False
    mixed = big[:, span].any(axis=1)
    return int((mixed & up).sum()), int((mixed & lo).sum()), [names[j] for j in np.flatnonzero(span)]


def machine():
    cpu = platform.processor() or ""
    try:
        for line in subprocess.run(["lscpu"], capture_output=True, text=True).stdout.splitlines():
            if line.startswith("Model name"):
                cpu = line.split(":", 1)[1].strip()
    except OSError:
        pass
    import os

    return f"{platform.system()} {platform.machine()}, {cpu}, {os.cpu_count()} cores, Python {platform.python_version()}"


def fmt(x):
    return "-" if np.isnan(x) else f"{100 * x:.1f}"


# ---------------------------------------------------------------- full rig (parts 1 and 2)
REGIONS = [("brow", ("forehead", "brow")), ("eyelids", ("eyelids",)), ("nose", ("nose",)),
           ("cheeks", ("cheeks",)), ("lips", ("lips",)), ("chin/jaw", ("chin", "jaw"))]
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


def copy_through(P_src, P_dst, gF, V_src, F_src, D_src, V_dst):
    """Per-vertex displacement copied from one head to another through the transfer's dense
    correspondence: each generic vertex g sits at P_src[g] on the source and P_dst[g] on the
    target; it takes the source displacement at its point (barycentric on the source triangle),
    and each target vertex takes the displacement at its closest point on the generic mesh laid
    on the target (P_dst, gF). Returns (n_dst, 3)."""
    from autobones.rig_transfer.under_skin import ride

    return ride(V_dst, P_dst, gF, ride(P_src, V_src, F_src, D_src))


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


def region_masks(rig, skin):
    """Named boolean masks: "all", "skin", "parts" (everything not skin: eyeballs, eyelashes,
    eye-occlusion shells, teeth, tongue...) and the skin's regions (transferred ``region``)."""
    labels = list(rig.field_labels["region"])
    reg = np.asarray(rig.fields["region"]).astype(int)
    out = {"all": np.ones(len(skin), bool), "skin": skin, "parts": ~skin}
    for name, members in REGIONS:
        out[name] = skin & np.isin(reg, [labels.index(m) for m in members if m in labels])
    return out


def region_scores(Y, X, V, masks):
    """explained per mask; nan ('-') where the mask carries under 10 % of the skin's
    displacement norm (a region the expression hardly moves)."""
    ds = np.linalg.norm((X - V)[masks["skin"]])
    out = {}
    for name, m in masks.items():
        d = np.linalg.norm((X - V)[m])
        out[name] = np.nan if (name not in ("all", "skin", "parts") and d < 0.1 * ds) or d == 0 else \
            explained(Y, X, V, m)
    return out


def rig_head(name, head, landmarks):
    """``autobones.transfer`` of ``head`` (path or (V, F)) with ``landmarks`` (path or dict), then
    ``ExpressionModel().fit``. Returns (rig, model, correspondence (n_generic, 3), region masks)."""
    from autobones.expressions.model import ExpressionModel

    t = time.perf_counter()
    det = {}
    rig = autobones.transfer(head, landmarks, details=det)
    model = ExpressionModel().fit(rig)
    print(f"rigged {name}: transfer + model fit {time.perf_counter() - t:.1f} s", flush=True)
    return rig, model, det["correspondence"], region_masks(rig, model.skin_)


def full_rig_benchmark(source="identity002", targets=("identity000", "identity001"), refine=30):
    """Parts 1 and 2 of the proof; prints its table and returns the lines."""
    from autobones.rig_transfer.pipeline import load_generic

    N0, F = load_mesh(NEUTRAL)
    E = {}
    for e in EXPRESSIONS:
        X, Fe = load_mesh(ICT / f"{e}.obj")
        assert X.shape == N0.shape and np.array_equal(Fe, F)
        E[e] = X - N0                                     # the same displacement on every identity
    gF = np.asarray(load_generic().faces)
    heads = {}
    for name in (source, *targets):
        heads[name] = rig_head(name, str(ICT / f"{name}.obj"), str(ICT / f"{name}.landmarks.json"))
        assert np.array_equal(heads[name][0].faces, F), f"{name}: not the ICT topology"
    cols = ["all", "skin", "parts"] + [r for r, _ in REGIONS]
    hdr = "| identity | method | expression | " + " | ".join(cols) + " |"
    lines = [hdr, "|" + "---|" * (len(cols) + 3)]

    def row(who, method, e, sc):
        lines.append(f"| {who} | {method} | {e} | " + " | ".join(fmt(sc[c]) for c in cols) + " |")

    rig_s, m_s, P_s, masks_s = heads[source]
    Vs = rig_s.vertices
    fits, summary, t_fit = {}, {}, time.perf_counter()
    for e in EXPRESSIONS:
        Xs = Vs + E[e]
        row(source, "neutral", e, region_scores(Vs, Xs, Vs, masks_s))
        for where in ("all", "skin"):
            t = time.perf_counter()
            c, jaw, lids, info = fit_rig(m_s, Xs, masks_s[where], refine=refine)
            fits[e, where] = (c, jaw, lids)
            Y = m_s.pose_parameters(c, jaw, lids)
            sc = region_scores(Y, Xs, Vs, masks_s)
            summary[source, where, e] = sc
            row(source, f"full rig, fit on {where}", e, sc)
            top = np.argsort(-c)[:4]
            print(f"  {e} fit on {where}: {time.perf_counter() - t:.1f} s, stage 1 -> 2 residual "
                  f"{info['stage1']:.3f} -> {info['stage2']:.3f}; jaw {jaw:.1f} deg, lids "
                  f"{np.array2string(lids, precision=2)}, largest contractions "
                  + ", ".join(f"{m_s.muscle_names_[i]} {c[i]:.2f}" for i in top if c[i] > 0.01), flush=True)
    for tname in targets:
        rig_t, m_t, P_t, masks_t = heads[tname]
        Vt = rig_t.vertices
        for e in EXPRESSIONS:
            Xt = Vt + E[e]
            row(tname, "neutral", e, region_scores(Vt, Xt, Vt, masks_t))
            row(tname, "copy by vertex index", e, region_scores(Vt + E[e], Xt, Vt, masks_t))
            Dc = copy_through(P_s, P_t, gF, Vs, F, E[e], Vt)
            sc = region_scores(Vt + Dc, Xt, Vt, masks_t)
            summary[tname, "copy", e] = sc
            row(tname, "copy through the correspondence", e, sc)
            for where in ("all", "skin"):
                c, jaw, lids = fits[e, where]
                sc = region_scores(m_t.pose_parameters(c, jaw, lids), Xt, Vt, masks_t)
                summary[tname, where, e] = sc
                row(tname, f"full rig, {source}'s fit on {where}", e, sc)
    t_fit = time.perf_counter() - t_fit
    print("\n".join(lines))
    print("\ntargets: fit >= 80 % and transfer >= 70 % explained per expression (column 'all' / 'skin'):")
    for key in [(source, "all"), (source, "skin")] + [(t, w) for t in targets for w in ("copy", "all", "skin")]:
        v = [summary[key[0], key[1], e] for e in EXPRESSIONS]
        print(f"  {key[0]} {key[1]:5s} " + "  ".join(f"{e} {fmt(s['all'])}/{fmt(s['skin'])}" for e, s in zip(EXPRESSIONS, v))
              + f"   mean {fmt(np.mean([s['all'] for s in v]))}/{fmt(np.mean([s['skin'] for s in v]))}")
    print(f"full-rig fits and transfers: {t_fit:.1f} s")
    # what one joint could do with ANY weight field (free angle per vertex), on the source head
    grid = np.arange(-90.0, 90.01, 0.5)
    j = m_s.bones_.index("jaw")
    for e, label, pivot, glide in (("eyeBlink_L", "left upper-lid joint about the eye bone", m_s.lid_pivots_[0], None),
                                   ("jawOpen", "jaw joint (with its glide)", m_s.pivots_[j], m_s.jaw_glide_)):
        Xs = Vs + E[e]
        sc = region_scores(rotation_ceiling(m_s, Xs, pivot, grid, glide), Xs, Vs, masks_s)
        print(f"ceiling, {e}: the {label} with a free angle per vertex explains "
              + ", ".join(f"{k} {fmt(v)}" for k, v in sc.items() if k != "parts"))
    return lines


# ---------------------------------------------------------------- ICT's 57 shapes (part "ict57", issue #16 item 3)
ICT57_TARGETS = {"fit skin mean": 0.80, "fit skin every shape": 0.65, "fit skin of the four": 0.80,
                 "transfer skin mean": 0.70}
FOUR = ("jawOpen", "mouthSmile_L", "eyeBlink_L", "browInnerUp_L")


def _arkit_bench():
    """benchmarks/arkit.py as a module (its ``remesh``, ``carry``), loaded by path."""
    import importlib.util
    import sys

    if "_bench_arkit" not in sys.modules:
        spec = importlib.util.spec_from_file_location("_bench_arkit", Path(__file__).with_name("arkit.py"))
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        sys.modules["_bench_arkit"] = mod
    return sys.modules["_bench_arkit"]


def ict57_shapes(shapes=None):
    """(ICT expression name, AU label) for every row of the definitions' ``au_arkit`` table, both
    halves where ICT splits a shape, in the table's order; only those named in ``shapes`` if given
    (SystemExit when none of them is in the table)."""
    from autobones.expressions.definitions import au_arkit_table

    rows = [(n, "/".join(f"AU{a}" for a in row["au"])) for row in au_arkit_table() for n in row["ict"]]
    if shapes:
        rows = [r for r in rows if r[0] in shapes]
        if not rows:
            raise SystemExit(f"--shapes: none of {shapes} is in the au_arkit table")
    return rows


def remeshed_identity(name, z, N0, F, part, lm_neutral):
    """ICT identity ``name`` (``N0 + identity``, cm) with ICT's neutral landmarks at their barycentric
    place on it, then remeshed as benchmarks/arkit.py's ``run_identity`` does (its
    ``remeshed_identity``). Returns (Vt (n, 3), Ft (m, 3), landmarks dict, tf (n,) ICT face,
    tb (n, 3) barycentric: where each remeshed vertex's truth is read)."""
    ak = _arkit_bench()
    Vi = N0 + z[f"identity/{name}"].astype(np.float64)
    lf, lb = ak.carry(np.array(list(lm_neutral.values())), N0, F, part)
    lm = {n: (Vi[F[f]] * b[:, None]).sum(axis=0) for n, f, b in zip(lm_neutral, lf, lb)}
    return ak.remeshed_identity(Vi, F, part, lm)


def ict57_benchmark(source="identity002", targets=("identity000", "identity001"), refine=30, shapes=None):
    """Issue #16 item 3: every ICT shape the AU <-> ARKit table maps, fitted by the full rig on
    ``source`` (ICT's triangulation) and the parameters applied on ``targets`` remeshed, beside
    the copy through the correspondence. Prints the table and returns the per-shape scores."""
    from autobones.rig_transfer.pipeline import load_generic

    t_all = time.perf_counter()
    rows = ict57_shapes(shapes)
    z = np.load(ICT / "ict_facekit_shapes.npz")
    N0, F = load_mesh(NEUTRAL)
    assert np.abs(N0 - z["neutral"]).max() < 1e-4, "the npz's neutral is not generic_neutral_mesh.obj"
    part = mesh_parts(len(N0), F)
    lm_neutral = {n: np.asarray(v, float) for n, v in json.loads(LANDMARKS.read_text())["landmarks"].items()}
    E = {n: z[f"expression/{n}"].astype(np.float64) for n, _ in rows}
    gF = np.asarray(load_generic().faces)

    rig_s, m_s, P_s, masks_s = rig_head(source, str(ICT / f"{source}.obj"), str(ICT / f"{source}.landmarks.json"))
    assert np.array_equal(rig_s.faces, F), f"{source}: not the ICT topology"
    Vs = rig_s.vertices
    heads = {}
    for name in targets:
        t = time.perf_counter()
        Vt, Ft, lm_t, tf, tb = remeshed_identity(name, z, N0, F, part, lm_neutral)
        print(f"remeshed {name}: {len(Vt)} vertices, {len(Ft)} triangles, {time.perf_counter() - t:.1f} s", flush=True)
        rig_t, m_t, P_t, masks_t = rig_head(f"{name} remeshed", (Vt, Ft), lm_t)
        heads[name] = (Vt, m_t, P_t, masks_t, F[tf], tb)

    shared = SharedSolves(m_s, Vs, E, {w: masks_s[w] for w in ("skin", "all")})
    # self-check: the shared solve is _solve_linear's (same QR, target split into base + displacement)
    n0 = rows[0][0]
    for w in ("skin", "all"):
        a = shared.solver(n0, w)(8.0, np.array([0.3, 0, 0, 0.1]))
        b = _solve_linear(m_s, Vs + E[n0], masks_s[w], 8.0, np.array([0.3, 0, 0, 0.1]), shared.lo, shared.hi)
        assert abs(a[1] - b[1]) <= 1e-6 * max(b[1], 1e-12) and np.allclose(a[0], b[0], atol=1e-6), (w, a[1], b[1])
    print("self-check passed: shared stage-1 solves equal _solve_linear", flush=True)
    res = {}
    for n, au in rows:
        t = time.perf_counter()
        Xs = Vs + E[n]
        r = {"au": au}
        truth, copies = {}, {}
        for name, (Vt, m_t, P_t, masks_t, tri, tb) in heads.items():
            truth[name] = Vt + np.einsum("vcd,vc->vd", E[n][tri], tb)   # the truth at each remeshed vertex
            copies[name] = Vt + copy_through(P_s, P_t, gF, Vs, F, E[n], Vt)
        for where in ("skin", "all"):
            sel = masks_s[where]
            c, jaw, lids, info = fit_rig(m_s, Xs, sel, refine=refine, solve=shared.solver(n, where))
            r["fit", where] = explained(m_s.pose_parameters(c, jaw, lids), Xs, Vs, sel)
            # the same parameters with the tissue pass (issue #16 item 1): not refitted through it
            r["fit+tissue", where] = explained(m_s.pose_parameters(c, jaw, lids, tissue=True), Xs, Vs, sel)
            tr, cp, tt = [], [], []
            for name, (Vt, m_t, P_t, masks_t, tri, tb) in heads.items():
                tr.append(explained(m_t.pose_parameters(c, jaw, lids), truth[name], Vt, masks_t[where]))
                tt.append(explained(m_t.pose_parameters(c, jaw, lids, tissue=True), truth[name], Vt, masks_t[where]))
                cp.append(explained(copies[name], truth[name], Vt, masks_t[where]))
                r["transfer", where, name] = tr[-1]
            r["transfer", where], r["copy", where] = float(np.mean(tr)), float(np.mean(cp))
            r["transfer+tissue", where] = float(np.mean(tt))
            if where == "skin":
                r["params"] = (jaw, lids, info)
        res[n] = r
        jaw, lids, info = r["params"]
        print(f"  {n} ({au}): {time.perf_counter() - t:.1f} s ({shared.misses} grid points made for "
              f"{shared.calls} solves so far); skin fit {fmt(r['fit', 'skin'])} (jaw {jaw:.1f} deg, "
              f"lids {np.array2string(lids, precision=2)}, residual {info['stage1']:.3f} -> {info['stage2']:.3f}), "
              f"all {fmt(r['fit', 'all'])}; transfer skin "
              + " / ".join(fmt(r["transfer", "skin", h]) for h in heads) + f"; copy-through skin {fmt(r['copy', 'skin'])}",
              flush=True)

    cols = [("fit skin", ("fit", "skin")), ("fit all", ("fit", "all")), ("transfer skin", ("transfer", "skin")),
            ("transfer all", ("transfer", "all")), ("copy-through skin", ("copy", "skin")),
            ("copy-through all", ("copy", "all")), ("fit skin, tissue", ("fit+tissue", "skin")),
            ("fit all, tissue", ("fit+tissue", "all")), ("transfer skin, tissue", ("transfer+tissue", "skin")),
            ("transfer all, tissue", ("transfer+tissue", "all"))]
    lines = ["| shape | AU | " + " | ".join(c for c, _ in cols) + " |",
             "|---|---|" + "---|" * len(cols)]
    for n, r in res.items():
        lines.append(f"| {n} | {r['au']} | " + " | ".join(fmt(r[k]) for _, k in cols) + " |")
    M = {c: np.array([r[k] for r in res.values()]) for c, k in cols}
    lines.append(f"| **mean of {len(res)}** | | " + " | ".join(fmt(np.nanmean(M[c])) for c, _ in cols) + " |")
    names = list(res)
    lines.append("| **worst** | | " + " | ".join(f"{fmt(np.nanmin(M[c]))} ({names[int(np.nanargmin(M[c]))]})"
                                                  for c, _ in cols) + " |")
    print(f"\nICT's shapes mapped to action units (generic_rig/expressions.json au_arkit), explained %: fit on "
          f"{source} (ICT's triangulation), transfer = {source}'s parameters on "
          + " and ".join(f"{h} remeshed" for h in heads) + " (mean of the two), copy-through = the displacement "
          "copied through the transfer's dense correspondence (mean of the two)\n")
    print("\n".join(lines))
    print("\nnotes: 'skin' columns are fitted and scored on the skin (largest part), 'all' columns on every "
          "vertex (eyeballs, teeth, lashes, shells too). 'tissue' columns pose the same parameters with the "
          "layered tissue pass (issue #16 item 1; pose(tissue=True)), not refitted through it. Per remeshed "
          "identity, transfer skin: "
          + "; ".join(f"{h} mean {fmt(np.mean([r['transfer', 'skin', h] for r in res.values()]))}" for h in heads))
    fs, ts = M["fit skin"], M["transfer skin"]
    four = [n for n in FOUR if n in res]
    checks = [
        (f"fit skin mean >= 80 % over the {len(res)} mapped shapes", np.nanmean(fs) >= 0.80, fmt(np.nanmean(fs))),
        ("every shape's fit skin >= 65 %", np.nanmin(fs) >= 0.65,
         ", ".join(f"{n} {fmt(r['fit', 'skin'])}" for n, r in res.items() if r["fit", "skin"] < 0.65) or "none below"),
        ("jawOpen, mouthSmile_L, eyeBlink_L, browInnerUp_L fit skin each >= 80 %",
         bool(four) and all(res[n]["fit", "skin"] >= 0.80 for n in four),
         ", ".join(f"{n} {fmt(res[n]['fit', 'skin'])}" for n in four) or "not run"),
        ("transfer to remeshed identities, skin mean >= 70 %", np.nanmean(ts) >= 0.70, fmt(np.nanmean(ts))),
    ]
    print("\ntargets (issue #16 item 3; judged on the skin columns):")
    for what, ok, val in checks:
        print(f"  {'met    ' if ok else 'NOT met'}  {what}: {val}")
    print(f"  (on all vertices: fit mean {fmt(np.nanmean(M['fit all']))}, transfer mean "
          f"{fmt(np.nanmean(M['transfer all']))}; copy-through skin mean {fmt(np.nanmean(M['copy-through skin']))})")
    print(f"\nict57: {time.perf_counter() - t_all:.1f} s in all ({len(res)} shapes x 2 fits, refine {refine}); "
          f"{datetime.date.today()}, {machine()}")
    return res


def ceiling_benchmark(source="identity002", shapes=None):
    """How far the rig's muscle fields can go at all: for every mapped ICT shape, stage 1 of
    ``fit_rig`` (grid over jaw and lids, linear surrogate, no refinement) on ``source``, once with
    the contractions in their bounds (what the benchmark fits) and once with the contractions free
    in sign and size (any linear combination of the fields: a ceiling no contraction values, bounds
    or refinement can pass). Scored on the surrogate ``linear_pose`` itself, so the two columns
    differ only by the bounds. Prints the table; returns the per-shape scores."""
    t_all = time.perf_counter()
    rows = ict57_shapes(shapes)
    z = np.load(ICT / "ict_facekit_shapes.npz")
    E = {n: z[f"expression/{n}"].astype(np.float64) for n, _ in rows}
    rig_s, m_s, _, masks_s = rig_head(source, str(ICT / f"{source}.obj"), str(ICT / f"{source}.landmarks.json"))
    Vs = rig_s.vertices
    where = "skin"
    sel = masks_s[where]
    bounded = SharedSolves(m_s, Vs, E, {where: sel})
    free = SharedSolves(m_s, Vs, E, {where: sel})
    free.lo, free.hi = np.full(len(free.lo), -np.inf), np.full(len(free.hi), np.inf)
    free.cache = bounded.cache                              # same QR per grid point; only the bounds differ

    def surrogate(c, jaw, lids):
        A, b = m_s.linear_pose(jaw, lids)
        return b + np.tensordot(c, A, axes=1)

    res = {}
    for n, au in rows:
        X = Vs + E[n]
        r = {"au": au}
        for key, sh in (("bounded", bounded), ("free", free)):
            c, jaw, lids, _ = fit_rig(m_s, X, sel, refine=0, solve=sh.solver(n, where))
            r[key] = explained(surrogate(c, jaw, lids), X, Vs, sel)
        # c is the free fit's: the muscles it makes push (a muscle cannot)
        r["free range"] = (float(c.min()), float(c.max()))
        r["free pushes"] = [f"{m_s.joints_.names[i]} {c[i]:.2f}" for i in np.argsort(c)[:3] if c[i] < -0.05]
        res[n] = r
        print(f"  {n} ({au}): bounded {fmt(r['bounded'])}, free {fmt(r['free'])} "
              f"(free contractions {r['free range'][0]:.2f} .. {r['free range'][1]:.2f}; most negative: "
              f"{', '.join(r['free pushes']) or 'none'})", flush=True)
    lines = ["| shape | AU | bounded (fitted) | free (ceiling) | free contractions min .. max |", "|---|---|---|---|---|"]
    for n, r in res.items():
        lines.append(f"| {n} | {r['au']} | {fmt(r['bounded'])} | {fmt(r['free'])} | "
                     f"{r['free range'][0]:.2f} .. {r['free range'][1]:.2f} |")
    b = np.array([r["bounded"] for r in res.values()])
    f = np.array([r["free"] for r in res.values()])
    lines.append(f"| **mean of {len(res)}** | | {fmt(np.nanmean(b))} | {fmt(np.nanmean(f))} | |")
    print(f"\nThe muscle fields' ceiling on {source}, skin, explained % on the linear surrogate "
          f"({len(m_s.joints_.types)} contractions, jaw and 4 lids on fit_rig's grid):\n")
    print("\n".join(lines))
    print(f"\nshapes with a free ceiling >= 80 %: {int((f >= 0.8).sum())} of {len(f)}; >= 65 %: {int((f >= 0.65).sum())}")
    print(f"ceiling: {time.perf_counter() - t_all:.1f} s; {datetime.date.today()}, {machine()}")
    return res


def main():
    if "--captures" in sys.argv[1:]:  # everything after it is captures.py's command line
        import captures

        return captures.main(sys.argv[sys.argv.index("--captures") + 1:])
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="sparse and dense only, no rigid variant")
    ap.add_argument("--sweeps", type=int, default=30, help="rigid variant: block-descent sweeps (0: skip it)")
    ap.add_argument("--part", choices=["all", "rig", "bones", "ict57", "ceiling", "au-shapes"], default="all",
                    help="rig: the full-rig fit and transfer (parts 1, 2) only; bones: bones alone (part 3) only; "
                         "ict57: every ICT shape the AU <-> ARKit table maps, transferred to remeshed identities "
                         "(not part of 'all'); ceiling: what any contractions of the muscle fields could explain "
                         "of those shapes on identity002 (not part of 'all'); au-shapes: every mapped AU and the "
                         "six emotions through the head's ARKit shapes against the muscles, on held-out ICT "
                         "identities (benchmarks/au_shapes.py; not part of 'all')")
    ap.add_argument("--variants", nargs="+", help="au-shapes: only these heads (identity001, 'identity000 remeshed', ...)")
    ap.add_argument("--identities", nargs="+", default=["identity000", "identity001"],
                    help="ict57: the ICT identities the fit is transferred to (remeshed)")
    ap.add_argument("--shapes", nargs="+", help="ict57: only these ICT shapes (default: every mapped one)")
    ap.add_argument("--refine", type=int, default=30,
                    help="full rig: least_squares evaluations of the nonlinear refinement (0: grid + linear only)")
    args = ap.parse_args()
    sweeps = 0 if args.quick else args.sweeps
    if args.part == "ceiling":
        ceiling_benchmark(shapes=args.shapes)
        return
    if args.part == "au-shapes":
        import au_shapes

        au_shapes.au_shapes_benchmark(ICT, machine, **({"variants": args.variants} if args.variants else {}))
        return
    if args.part == "ict57":
        ict57_benchmark(targets=tuple(args.identities), refine=args.refine, shapes=args.shapes)
        return
    if args.part in ("all", "rig"):
        full_rig_benchmark(refine=args.refine)
        print()
    if args.part == "rig":
        return

    V, F = load_mesh(NEUTRAL)
    shapes = {}
    for e in EXPRESSIONS:
        X, Fe = load_mesh(ICT / f"{e}.obj")
        assert X.shape == V.shape and np.array_equal(Fe, F), f"{e}: not the neutral's vertex list"
        shapes[e] = X
    lm = json.loads(LANDMARKS.read_text())["landmarks"]
    nose_y = lm["pronasale"][1]

    specs = [("sparse", "sparse", None), ("medium", "medium", None), ("dense", "dense", None),
             ("dense + landmarks", "dense", str(LANDMARKS))]
    if args.quick:
        specs = [specs[0], specs[2], specs[3]]
    rigs = {}
    for label, density, landmarks in specs:
        t = time.perf_counter()
        rig = autobones.place(str(NEUTRAL), density=density, landmarks=landmarks)
        assert np.allclose(rig.vertices, V), "place must keep the vertices"
        rigs[label] = rig
        print(f"placed {label}: {len(rig.skeleton)} bones in {time.perf_counter() - t:.1f} s", flush=True)
    ref = rigs["dense + landmarks"]
    parts = mesh_parts(len(V), F)
    skin = parts == np.argmax(np.bincount(parts))
    up_lip, lo_lip = lips(V, lm, ref.fields["region"], ref.field_labels["region"], skin)

    # weight sets per rig; "global affine" is one bone with weight 1
    entries = [("global affine", 1, {"all": np.ones((len(V), 1))}, ["root"])]
    for label, rig in rigs.items():
        entries.append((label, len(rig.skeleton), {"4 infl": sparse_top4(rig.weights), "all": rig.weights},
                        list(rig.skeleton.names)))

    # ---- self-check
    ang = np.deg2rad(12.0)
    Rx = np.array([[1, 0, 0], [0, np.cos(ang), -np.sin(ang)], [0, np.sin(ang), np.cos(ang)]])
    Ry = np.array([[np.cos(ang / 2), 0, np.sin(ang / 2)], [0, 1, 0], [-np.sin(ang / 2), 0, np.cos(ang / 2)]])
    Xrig = (V - V.mean(0)) @ (Ry @ Rx).T + V.mean(0) + np.array([0.7, -1.3, 2.1])
    fits = {}
    for label, b, wsets, names in entries:
        for kind, W in wsets.items():
            Ws = sp.csr_matrix(W)[np.flatnonzero(skin)]
            for where, fit, sel in [("all", LBSFit(V, W), slice(None)), ("skin", LBSFit(V[skin], Ws), skin)]:
                fits[label, kind, where] = (fit, Ws if where == "skin" else W)
                Y0, _ = fit.fit(V[sel])
                err0 = np.abs(Y0 - V[sel]).max()
                # 4 infl: float32 weights sum to 1 only to float32 rounding (~1e-7 of the head size)
                assert err0 < 1e-6 * fit.s, f"{label}/{kind}/{where}: neutral fit residual {err0:.3g}"
                e = explained(fit.fit(Xrig[sel])[0], Xrig[sel], V[sel])
                assert e >= 0.999, f"{label}/{kind}/{where}: rigid head motion explained {100 * e:.3f} %"
    print("self-check passed: neutral residual 0, rigid head motion >= 99.9 % on every rig and weight set\n")

    # ---- the table
    Vs = V[skin]
    sk = {e: X[skin] for e, X in shapes.items()}
    lower, upper = {}, {}
    for e, X in sk.items():
        d = np.linalg.norm(X - Vs, axis=1)
        moved = d > 0.01 * d.max()
        lower[e] = moved & (Vs[:, 1] < nose_y)
        upper[e] = moved & (Vs[:, 1] >= nose_y)
    hdr = ("| rig | bones | expression | all weights: all / skin / lower / upper | 4 infl: all / skin / lower / upper |"
           + (" rigid 4 infl: skin |" if sweeps else ""))
    lines = [hdr, "|" + "---|" * (hdr.count("|") - 1)]
    summary = {}

    def region(fitted, e, sel):
        return explained(fitted, sk[e], Vs, sel) if sel.sum() >= 50 else np.nan

    def scores(label, kind, e):
        if label is None:  # neutral: no motion
            fa, fs = V, Vs
        else:
            fa = fits[label, kind, "all"][0].fit(shapes[e])[0]
            fs = fits[label, kind, "skin"][0].fit(sk[e])[0]
        return (explained(fa, shapes[e], V), explained(fs, sk[e], Vs),
                region(fs, e, lower[e]), region(fs, e, upper[e]))

    for e in EXPRESSIONS:
        z = " / ".join(map(fmt, scores(None, None, e)))
        lines.append(f"| neutral | 0 | {e} | {z} | {z} |" + (" 0.0 |" if sweeps else ""))
    t_fit = time.perf_counter()
    for label, b, wsets, names in entries:
        for e in EXPRESSIONS:
            row = {kind: scores(label, kind, e) for kind in wsets}
            rig_col = ""
            if sweeps:
                if "4 infl" in wsets:
                    fit, W = fits[label, "4 infl", "skin"]
                    Yr = fit_rigid(fit, W, sk[e], sweeps)
                    start = fit_rigid(fit, W, sk[e], 0)
                    er = explained(Yr, sk[e], Vs)
                    assert er >= explained(start, sk[e], Vs) - 1e-9, "rigid descent went up"
                    rig_col = f" {fmt(er)} |"
                else:
                    rig_col = " - |"
            a = row["all"]
            f4 = row.get("4 infl", (np.nan,) * 4)
            summary.setdefault(label, []).append((a[0], a[1], f4[1]))
            lines.append(f"| {label} | {b} | {e} | {' / '.join(map(fmt, a))} | {' / '.join(map(fmt, f4))} |{rig_col}")
    t_fit = time.perf_counter() - t_fit

    print("\n".join(lines))
    print("\nmean over the 4 expressions, explained (all vertices, all weights / skin, all weights / skin, 4 infl):")
    for label, vals in summary.items():
        v = np.array(vals)
        m = [fmt(np.nanmean(v[:, k])) if not np.all(np.isnan(v[:, k])) else "-" for k in range(3)]
        print(f"  {label:18s} {m[0]:>5s} / {m[1]:>5s} / {m[2]:>5s}   (skin min {fmt(np.nanmin(v[:, 1]))})")
    print(f"\nskin {skin.sum()} of {len(V)} vertices; moved skin vertices lower / upper face: "
          + ", ".join(f"{e} {lower[e].sum()}/{upper[e].sum()}" for e in EXPRESSIONS))
    print(f"lip check: {up_lip.sum()} upper-lip, {lo_lip.sum()} lower-lip vertices; jawOpen mean displacement "
          f"upper {np.linalg.norm(shapes['jawOpen'] - V, axis=1)[up_lip].mean():.3f}, "
          f"lower {np.linalg.norm(shapes['jawOpen'] - V, axis=1)[lo_lip].mean():.3f}")
    for label, rig in rigs.items():
        mu, ml, span = lip_mixing(rig.weights, list(rig.skeleton.names), up_lip, lo_lip)
        print(f"  {label:18s} mixed: {mu}/{up_lip.sum()} upper, {ml}/{lo_lip.sum()} lower; "
              f"bones weighting both lips >= 0.2: {', '.join(span) or 'none'}")
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=Path(__file__).parent,
                                capture_output=True, text=True).stdout.strip()
    except OSError:
        commit = "?"
    print(f"\nfits: {t_fit:.1f} s; {datetime.date.today()}, autobones {commit}, {machine()}")


if __name__ == "__main__":
    sys.exit(main())
