"""Deformation transfer (Sumner & Popovic 2004) of a source's shapes onto a target's own triangles.

Goes beyond the seeds (issue #15). Each source shape is a per-triangle deformation gradient
``Q = E' E^-1``, with ``E = [v2 - v1, v3 - v1, n / sqrt(|n|)]`` (Sumner & Popovic's fourth
vertex: the normal scaled so the frame is well conditioned). The target is tied to the source
by a dense correspondence ``P`` (each source vertex's point on the target surface,
:func:`autobones.rig_transfer.correspondence.dense_correspondence`): every target triangle
takes the mean gradient of the source triangles under four points of it (its centroid and
halfway to each corner) in the source mesh laid on the target (``(P, F_src)``), each turned
into the target's orientation by the source's turn on the way there (the rotation of the polar
decomposition of the warp's gradient ``E_P E^-1``, averaged over ten face-vertex-face rings
first: per triangle it is noisy where the fit is): the target deforms as the source did, in
its own proportions and frame, and a gradient is scale-free, so a head in metres takes shapes
made in centimetres. Measured on remeshed ICT identities (benchmarks/arkit.py, identity003,
skin): centroid only and per-triangle turns 94.3 % mean / 84.6 % worst shape; four samples
94.9 / 86.5; four samples and one global turn 95.2 / 87.5; four samples and smoothed turns
(the default: a head turned or shaped unlike the source still gets local turns) 95.0 / 87.1.

The displacements ``d`` (n, 3) per shape then solve the least-squares Poisson system (the
gradient form of Sumner & Popovic's energy, the normal column dropped as in Botsch et al.
2006)::

    min  sum_t a_t || grad_t d - (Q_t - I) ||^2  +  w sum_(anchored i) ||d_i||^2  +  eps sum_i m_i ||d_i||^2

``grad_t`` the in-plane gradient of a piecewise-linear field on target triangle ``t`` (area
``a_t``): the normal matrix is the cotangent Laplacian plus diagonal terms, factorised ONCE
(:func:`autobones.geometry.laplacian.factor_spd`) and solved for all shapes and coordinates
at once. Anchored: target vertices whose source region moves in no shape (back of the head,
neck) stay at 0; ``eps`` (a screening term 1e-6 of the Laplacian's scale) makes parts with no
anchor (a tongue, a separate mouth socket) well posed. Target triangles that land on no
source triangle (the eye and mouth openings of a scan, over the source's holes; parts the
source has no counterpart of) take no gradient (``Q = I``): the solve fills them from their
borders. A scan's eye surface between the lids (``free`` in :meth:`DeformationTransfer.fit`)
takes no gradient and almost no weight (``hole_weight``) either: it squashes to follow the lids,
so the upper lid can come down to the lower one in a blink instead of being held apart by it.
Vertices ``pinned`` in ``fit`` may be given displacements in ``transform`` (``pins``): soft
positional terms ``pin_weight * ||d_i - g_i||^2`` in a second factorisation, for the eye opening
of a scan whose lids the gradients alone leave apart (:mod:`autobones.arkit.lids`).
"""
from __future__ import annotations

import logging
import time

import numpy as np
import scipy.sparse as sp

from ..errors import AutobonesError, counted
from ..geometry.closest import closest_points
from ..geometry.laplacian import factor_spd
from ..geometry.normals import cross_rows, triangle_normals
from ..geometry.rotations import polar_rotations
from ..geometry.topology import mesh_parts

log = logging.getLogger(__name__)


def triangle_frames(V, F):
    """Sumner & Popovic's frames ``[v2 - v1, v3 - v1, n / sqrt(|n|)]`` as columns, (m, 3, 3) float64."""
    V = np.asarray(V, dtype=np.float64)
    e1, e2 = V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]
    n = cross_rows(e1, e2)
    n = n / np.sqrt(np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300))
    return np.stack([e1, e2, n], axis=2)


def _inverse(E):
    """Inverse of each (3, 3) frame; a degenerate triangle's frame gives zeros (no gradient)."""
    det = np.linalg.det(E)
    ok = np.abs(det) > 1e-300
    out = np.zeros_like(E)
    out[ok] = np.linalg.inv(E[ok])
    return out


def gradient_operator(V, F):
    """In-plane gradient of piecewise-linear fields: ``G`` (3m, n) sparse (rows ``3t + c``), areas (m,).

    ``(G f).reshape(m, 3)[t]`` is the gradient of ``f`` (n,) on triangle ``t``, in 1 / mesh units;
    ``G.T @ diag(a) @ G`` is the cotangent Laplacian.
    """
    V = np.asarray(V, dtype=np.float64)
    m = len(F)
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    n = cross_rows(b - a, c - a)
    dbl = np.linalg.norm(n, axis=1)
    area = 0.5 * dbl
    unit = n / np.maximum(dbl, 1e-300)[:, None]
    scale = 1.0 / np.maximum(dbl, 1e-300)[:, None]
    # grad of vertex i's hat function: (n x opposite edge) / (2 area)
    gi = [cross_rows(unit, c - b) * scale, cross_rows(unit, a - c) * scale, cross_rows(unit, b - a) * scale]
    rows = (3 * np.arange(m)[:, None] + np.arange(3)[None, :])  # (m, 3)
    R, C, X = [], [], []
    for k in range(3):
        R.append(rows.ravel())
        C.append(np.repeat(F[:, k], 3))
        X.append(gi[k].ravel())
    G = sp.csr_matrix((np.concatenate(X), (np.concatenate(R), np.concatenate(C))), shape=(3 * m, len(V)))
    return G, area


def _anchored(moving, F_src, face, F_tgt, n_t):
    """Target vertices (n_t,) bool none of whose triangles' source triangle (``face`` (m_t,) int,
    every target triangle's nearest, covered or not) has a ``moving`` (n_s,) bool corner: anchors
    at 0 (before the covered-parts filter)."""
    # anchors: target vertices whose nearest source triangle never moves
    still_face = ~moving[F_src[face]].any(axis=1)  # every target triangle, covered or not
    touches_moving = np.zeros(n_t, dtype=bool)
    np.logical_or.at(touches_moving, F_tgt.ravel(), np.repeat(~still_face, 3))
    return ~touches_moving


def _source_picker(faces, covered, used, m_t, m_s):
    """``S`` (3 m_t, 3 mu) sparse: each covered target triangle's gradient (rows ``3t + c``) as the
    mean of its sample points' source triangles' (``faces`` (m_t, samples) of the m_s, ``used``
    the mu that some covered triangle takes; columns ``3u + c``)."""
    # right-hand sides from the used source triangles' gradients: G^T A S, S picking each covered
    # target triangle's source triangle (rows 3t + c <- 3u + c)
    slot = np.full(m_s, -1)
    slot[used] = np.arange(len(used))
    ns = faces.shape[1]
    tc = np.flatnonzero(covered)
    rows = np.broadcast_to(3 * tc[:, None, None] + np.arange(3)[None, None, :], (len(tc), ns, 3)).ravel()
    cols = (3 * slot[faces[covered]][:, :, None] + np.arange(3)[None, None, :]).ravel()
    return sp.csr_matrix((np.full(len(rows), 1.0 / ns), (rows, cols)), shape=(3 * m_t, 3 * len(used)))


class DeformationTransfer:
    """Carry a source's shapes onto a target through a dense correspondence (module docstring).

    Parameters
    ----------
    anchor_weight : float
        Weight of the anchored vertices, relative to the Laplacian's mean diagonal.
    screening : float
        ``eps``, relative to the Laplacian's mean diagonal per unit of vertex area.
    max_distance : float
        A target triangle takes a source gradient when its centroid is within this many mean
        target edge lengths of the laid source and their normals agree within 60 degrees.
    min_part_coverage : float
        Target parts (connected components) with a smaller fraction of triangles covered
        take no gradient at all (eyeballs, teeth behind a source skin).
    hole_weight : float
        Weight (relative to the others) of the triangles set ``free`` in :meth:`fit`: they
        follow their borders instead of holding them together.
    samples : 1 or 4
        Points per target triangle whose source gradients are averaged.
    turn : "smooth", "local" or "global"
        The source-to-target rotation of the gradients: the warp's per-triangle rotation,
        smoothed over ``smooth_iterations`` rings or not, or one rotation for the whole head.

    Attributes (after :meth:`fit`)
    ----------
    source_face_ : (m_t,) int64
        Source triangle of each target triangle (-1: none).
    anchored_ : (n_t,) bool
    covered_parts_ : (n_t,) bool
        Vertices of parts that take gradients; the others inherit (see :meth:`transform`).
    timings_ : dict
        Seconds of ``map``, ``factor``.
    """

    def __init__(self, anchor_weight=1e3, screening=1e-6, max_distance=1.0, min_part_coverage=0.25, samples=4,
                 turn="smooth", smooth_iterations=10, hole_weight=1e-3, pin_weight=100.0):
        self.samples = samples
        self.pin_weight = pin_weight
        self.turn = turn
        self.smooth_iterations = smooth_iterations
        self.hole_weight = hole_weight
        self.anchor_weight = anchor_weight
        self.screening = screening
        self.max_distance = max_distance
        self.min_part_coverage = min_part_coverage

    def fit(self, V_src, F_src, P, V_tgt, F_tgt, moving=None, free=None, pinned=None):
        """Map target triangles to source triangles and factor the target's system.

        Parameters
        ----------
        V_src : (n_s, 3) float
            Source vertices, source frame and units.
        F_src : (m_s, 3) int
        P : (n_s, 3) float
            Each source vertex's point on the target (target frame and units).
        V_tgt : (n_t, 3) float
        F_tgt : (m_t, 3) int
        moving : (n_s,) bool, optional
            Source vertices that move in some shape; target vertices whose source triangle has
            none are anchored at 0. None: nothing anchored but by screening.
        free : (m_t,) bool, optional
            Target triangles to treat as over a hole of the source even where it covers them
            (a scan's eye surface between the lids: :func:`autobones.arkit.fissures.eye_fissures`).
        pinned : (p,) int, optional
            Target vertices whose displacements :meth:`transform` may be given (``pins``): soft
            positional constraints weighted ``pin_weight`` times the Laplacian's mean diagonal,
            in a second factorisation (a scan's eye opening:
            :class:`autobones.arkit.lids.LidClosure`).
        """
        t0 = time.perf_counter()
        V_src, P, V_tgt = (np.asarray(a, dtype=np.float64) for a in (V_src, P, V_tgt))
        F_src, F_tgt = np.asarray(F_src, dtype=np.int64), np.asarray(F_tgt, dtype=np.int64)
        if P.shape != V_src.shape:
            raise AutobonesError(f"deformation transfer: {counted(len(P), 'corresponding point')} for "
                                 f"{counted(len(V_src), 'source vertex', 'source vertices')}")
        self.V_src_, self.F_src_ = V_src, F_src
        n_t, m_t = len(V_tgt), len(F_tgt)
        free = None if free is None else np.asarray(free, dtype=bool)
        EP = triangle_frames(P, F_src)
        faces, covered = self._map_triangles(P, F_src, EP, V_tgt, F_tgt, free)
        face = faces[:, 0]
        # each source triangle's turn onto the target: rotation of the warp's gradient
        used = np.unique(faces[covered])
        R = self._turns(V_src, F_src, P, EP, used)
        anchored = np.zeros(n_t, dtype=bool)
        if moving is not None:
            anchored = _anchored(np.asarray(moving, dtype=bool), F_src, face, F_tgt, n_t) & self.covered_parts_
        self.anchored_ = anchored
        G, area = gradient_operator(V_tgt, F_tgt)
        # the triangles set free weigh little: held at Q = I with full weight, a scan's eye
        # surface would tie the upper lid to the lower one and no blink could close it
        weight = np.ones(m_t) if free is None else np.where(free, self.hole_weight, 1.0)
        A3 = sp.diags(np.repeat(area * weight, 3))
        L = (G.T @ A3 @ G).tocsc()
        scale = self._scale = float(L.diagonal().mean())
        mass = np.bincount(F_tgt.ravel(), np.repeat(area / 3.0, 3), minlength=n_t)
        diag = self.anchor_weight * scale * anchored + self.screening * scale * mass / max(mass.mean(), 1e-300)
        S = _source_picker(faces, covered, used, m_t, len(F_src))
        # parts that take no gradient (eyeballs, teeth, lashes) are blocks of their own whose right-hand
        # side is 0: left out of the solve (their vertices inherit in transform), which on an ICT head
        # is then 43 % smaller
        solved = self.covered_parts_.copy()
        if pinned is not None and len(pinned):
            solved |= np.isin(self._part, self._part[np.asarray(pinned, dtype=np.int64)])
        rows = self._rows = np.flatnonzero(solved)
        self._rhs_operators(V_src, F_src, used, R, (G.T @ A3 @ S).tocsr()[rows])
        self.timings_ = {"map": time.perf_counter() - t0}
        self._factorise(L[rows][:, rows], diag[rows], scale, pinned, n_t)
        self.n_t_, self.F_tgt_, self.V_tgt_ = n_t, F_tgt, V_tgt
        return self

    def _map_triangles(self, P, F_src, EP, V_tgt, F_tgt, free):
        """The source triangles (m_t, samples) int under each target triangle's sample points (its
        centroid, and halfway to each corner with ``samples`` 4) on the source laid on the target
        (``P`` (n_s, 3), ``F_src`` (m_s, 3), frames ``EP`` (m_s, 3, 3): :func:`triangle_frames`),
        and which target triangles take a gradient (m_t,) bool: their centroid near the laid
        source, the normals agreeing, in a part covered enough, not ``free``. Sets
        ``covered_parts_``, ``source_face_`` and the target's parts."""
        m_t = len(F_tgt)
        # source triangle under each target triangle's centroid, on the source laid on the target
        cent = V_tgt[F_tgt].mean(axis=1)
        # more samples per target triangle than its centroid: halfway to each corner too, so a target
        # triangle over several source triangles takes their mean gradient (less aliasing); one query
        pts = [cent] + ([0.5 * (cent + V_tgt[F_tgt[:, c]]) for c in range(3)] if self.samples > 1 else [])
        _, face_all, _, d2_all = closest_points(np.concatenate(pts), P, F_src)
        faces = face_all.reshape(len(pts), m_t).T  # (m_t, samples)
        face, d2 = faces[:, 0], d2_all[:m_t]
        edge = np.linalg.norm(V_tgt[F_tgt] - V_tgt[np.roll(F_tgt, 1, axis=1)], axis=2).mean()
        nt = triangle_normals(V_tgt, F_tgt)
        ns = EP[:, :, 2]
        cos = np.einsum("ij,ij->i", nt, ns[face]) / np.maximum(
            np.linalg.norm(nt, axis=1) * np.linalg.norm(ns[face], axis=1), 1e-300)
        covered = (np.sqrt(d2) <= self.max_distance * edge) & (cos > 0.5)
        part = self._part = mesh_parts(len(V_tgt), F_tgt)
        fpart = part[F_tgt[:, 0]]
        # a vertex no triangle uses is a part of its own, with no triangle: both counts span every part
        # (a scan with holes cut out keeps their vertices: James with 12 holes stopped with a ValueError)
        parts = part.max() + 1
        frac = np.bincount(fpart, covered, minlength=parts) / np.maximum(np.bincount(fpart, minlength=parts), 1)
        covered &= frac[fpart] >= self.min_part_coverage
        if free is not None:
            covered &= ~free
        self.covered_parts_ = frac[part] >= self.min_part_coverage
        self.source_face_ = np.where(covered, face, -1)
        return faces, covered

    def _turns(self, V_src, F_src, P, EP, used):
        """The source-to-target turn (mu, 3, 3) of each ``used`` source triangle (``turn``: the
        polar rotation of the warp's gradient ``EP E^-1``, smoothed over rings or not, or one
        rotation of the whole source onto ``P`` (n_s, 3))."""
        R = np.zeros((0, 3, 3))  # the turn of each used source triangle
        if len(used):
            if self.turn == "global":
                A0, B0 = V_src - V_src.mean(axis=0), P - P.mean(axis=0)
                R = np.broadcast_to(polar_rotations((B0.T @ A0)[None])[0], (len(used), 3, 3))
            else:
                W = EP @ _inverse(triangle_frames(V_src, F_src))
                if self.turn == "smooth":  # the warp's gradient averaged over a few rings first
                    n_s = len(V_src)
                    inc = sp.csr_matrix((np.ones(3 * len(F_src)), (F_src.ravel(), np.repeat(np.arange(len(F_src)), 3))),
                                        shape=(n_s, len(F_src)))
                    to_v = sp.diags(1.0 / np.maximum(np.asarray(inc.sum(axis=1)).ravel(), 1)) @ inc
                    to_f = inc.T.tocsr() / 3.0
                    Wf = W.reshape(-1, 9)
                    for _ in range(self.smooth_iterations):
                        Wf = to_f @ (to_v @ Wf)
                    W = Wf.reshape(-1, 3, 3)
                R = polar_rotations(W[used])
        return R

    def _factorise(self, L, diag, scale, pinned, n_t):
        """Factorise the solved rows' system ``L`` (r, r) sparse plus ``diag`` (r,); with ``pinned``
        target vertices, keep the system with their positional terms too (factorised when first
        used). ``scale``: the Laplacian's mean diagonal. Times it as ``factor``."""
        t1 = time.perf_counter()
        rows = self._rows
        self._solve = factor_spd(L + sp.diags(diag)) if len(rows) else None
        self._pinned = self._solve_pinned = None
        if pinned is not None and len(pinned):
            local = np.full(n_t, -1)
            local[rows] = np.arange(len(rows))
            self._pinned = local[np.asarray(pinned, dtype=np.int64)]  # rows of the solved system
            pin = np.zeros(len(rows))
            pin[self._pinned] = self.pin_weight * scale
            self._pinned_system = L + sp.diags(diag + pin)  # factorised when first used
        self.timings_["factor"] = time.perf_counter() - t1

    def _rhs_operators(self, V_src, F_src, used, R, B):
        """Keep what the right-hand sides of every shape need (:meth:`_right_hand_sides`).

        A used source triangle ``u`` (frame ``E``, turn ``R[u]``, (mu, 3, 3)) asks of a shape the gradient
        ``J = R (E' - E) E^-1 R^T`` (``E'`` its frame in the shape), and ``B`` (n_t, 3 mu) sums
        ``J``'s columns into the target's rows: ``E^-1 R^T`` is folded into ``B`` here, once, so
        a shape needs only ``R (E' - E)`` per triangle. A source triangle with no frame (zero
        area) asks nothing (``J = 0``, as over a hole).
        """
        mu = len(used)
        self._B1 = None
        if not mu:
            return
        Fu = F_src[used]
        E = triangle_frames(V_src, Fu)
        M = _inverse(E) @ np.transpose(R, (0, 2, 1))  # (mu, 3, 3): E^-1 R^T
        # B1[t, (u, b)] = sum_c B[t, (u, c)] M[u, b, c]
        r = 3 * np.arange(mu)[:, None, None] + np.arange(3)[None, None, :]  # (u, ., c)
        c = 3 * np.arange(mu)[:, None, None] + np.arange(3)[None, :, None]  # (u, b, .)
        K = sp.csr_matrix((M.ravel(), (np.broadcast_to(r, M.shape).ravel(), np.broadcast_to(c, M.shape).ravel())),
                          shape=(3 * mu, 3 * mu))
        self._B1 = (B @ K).tocsr()
        self._frames_used, self._F_used, self._R_used = E, Fu, R

    def _right_hand_sides(self, deltas, block=512):
        """``B J`` of each shape of ``deltas`` (k, n_s, 3): (n_t, 3k), column ``3j + i``.

        ``R (E' - E)`` of every used triangle in every shape, in blocks of ``block`` triangles
        that stay in cache (all at once it is memory-bound: 3.5x slower).
        """
        k = len(deltas)
        Fu, E, R = self._F_used, self._frames_used, self._R_used
        Dv = np.ascontiguousarray(np.transpose(deltas, (1, 2, 0)))  # (n_s, 3, k)
        Y = np.empty((len(Fu), 3, k, 3))  # (u, b, shape, i): B1 @ Y has the columns 3j + i
        for s in range(0, len(Fu), block):
            f, Rb = Fu[s:s + block], R[s:s + block]
            d0 = Dv[f[:, 0]]
            d1 = Dv[f[:, 1]] - d0
            d2 = Dv[f[:, 2]] - d0
            a = d1 + E[s:s + block, :, 0, None]
            b = d2 + E[s:s + block, :, 1, None]
            n = np.empty_like(a)
            np.multiply(a[:, 1], b[:, 2], out=n[:, 0])
            n[:, 0] -= a[:, 2] * b[:, 1]
            np.multiply(a[:, 2], b[:, 0], out=n[:, 1])
            n[:, 1] -= a[:, 0] * b[:, 2]
            np.multiply(a[:, 0], b[:, 1], out=n[:, 2])
            n[:, 2] -= a[:, 1] * b[:, 0]
            n /= np.sqrt(np.maximum(np.sqrt(np.einsum("uak,uak->uk", n, n)), 1e-300))[:, None, :]
            n -= E[s:s + block, :, 2, None]  # the scaled normal's change
            RbT = np.transpose(Rb, (0, 2, 1))
            for col, d in enumerate((d1, d2, n)):  # (R d)^T: rows the shapes, columns i
                np.matmul(np.transpose(d, (0, 2, 1)), RbT, out=Y[s:s + block, col])
        return self._B1 @ Y.reshape(3 * len(Fu), 3 * k)

    def transform(self, deltas, inherit=True, keep=None, pins=None):
        """Target displacements of the source shapes.

        Parameters
        ----------
        deltas : (k, n_s, 3) float
            Source displacements (source units) at weight 1.
        inherit : bool
            Target parts that take no gradient (teeth, a mouth socket, lashes) move rigidly by
            the mean displacement of their vertices' nearest vertices of covered parts (the
            teeth follow the lips and the jaw); False leaves them at the solve's 0.
        keep : (n_t,) bool, optional
            Vertices held at 0 whatever (eyeballs: they turn by their bones, not by the skin).
        pins : (k, p, 3) float, optional
            Displacements asked of the ``pinned`` vertices of :meth:`fit`, per shape (target units).

        Returns
        -------
        (k, n_t, 3) float64
            Target frame and units.
        """
        t0 = time.perf_counter()
        deltas = np.asarray(deltas, dtype=np.float64)
        k = len(deltas)
        rhs = np.zeros((len(self._rows), 3 * k))
        if self._B1 is not None:
            rhs = self._right_hand_sides(deltas)
        solve = self._solve
        if pins is not None:
            if self._pinned is None:
                raise AutobonesError("deformation transfer: pins given but no vertices were pinned in fit")
            g = np.asarray(pins, dtype=np.float64)  # (k, p, 3) -> rows of the pinned, columns j * 3 + c
            rhs[self._pinned] += self.pin_weight * self._scale * np.transpose(g, (1, 0, 2)).reshape(len(self._pinned), 3 * k)
            if self._solve_pinned is None:
                t1 = time.perf_counter()
                self._solve_pinned = factor_spd(self._pinned_system)
                self.timings_["factor_pinned"] = time.perf_counter() - t1
            solve = self._solve_pinned
        X = np.zeros((k, self.n_t_, 3))
        if solve is not None:
            X[:, self._rows] = np.asarray(solve(rhs)).reshape(len(self._rows), k, 3).transpose(1, 0, 2)
        if inherit and not self.covered_parts_.all() and self.covered_parts_.any():
            from scipy.spatial import cKDTree

            src = np.flatnonzero(self.covered_parts_)
            dst = np.flatnonzero(~self.covered_parts_)
            nearest = src[cKDTree(self.V_tgt_[src]).query(self.V_tgt_[dst])[1]]
            # each such part moves rigidly by the mean of what its vertices' nearest skin does:
            # copied vertex by vertex, a small part (a lash, a tooth) would be sheared and fold
            part = self._part[dst]
            cnt = np.bincount(part)
            for j in range(k):
                mean = np.stack([np.bincount(part, X[j, nearest, c]) for c in range(3)], axis=1)
                X[j, dst] = mean[part] / np.maximum(cnt[part], 1)[:, None]
        if keep is not None:
            X[:, np.asarray(keep, dtype=bool)] = 0.0
        self.timings_["solve"] = time.perf_counter() - t0
        return X
