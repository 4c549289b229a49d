"""The carried jaw weight checked against the head's landmarks and repaired: it reaches the chin and
the lower lip, stays off the upper lip and the face above, and falls off smoothly everywhere but
across the lip line.

The dense correspondence carries the generic rig's jaw weight well on human heads, but on a long
snout it can miss the chin and lower lip (the generic chin lands elsewhere), and on any head
coarser than the generic rig (its jaw weight falls off over about 1 cm) neighbouring vertices can
jump from 0 to 1: a torn flap when the jaw opens. :func:`repair_jaw` replaces the jaw weight by
the smooth field closest to it that the landmarks allow:

    minimise   x' (L + S) x  +  sum_i c_i m_i / h_i^2 (x_i - w_i)^2,   x = 1 on the lower seeds,
                                                                    x = 0 on the upper seeds,

a screened Laplace problem (a harmonic field with Dirichlet seeds plus a data term, as in screened
Poisson smoothing, Chuang & Kazhdan 2011) on the welded surface: ``L`` the cotangent Laplacian
with its negative weights clipped (:func:`autobones.geometry.laplacian.clipped_cotangent_laplacian`:
the intrinsic Delaunay one gave the same weights on every benchmarked head at twice the cost) and
``m`` the barycentric vertex area, ``w``
the carried weight, ``h_i`` the vertex's mean edge length and ``c_i = 0.1 + 0.9 w_i`` (the jaw's
core is held harder than its rim, so a falloff widens outward, into the neck and cheeks, instead
of eating into the chin). ``S`` is a graph Laplacian of springs on the edges that still jump:
after each solve every edge off the lip line stepping by more than :data:`TARGET_JUMP` gets a
spring (1, then doubled each round up to :data:`SPRING_CAP`, at most :data:`ROUNDS` rounds); the
springs matter where the Laplacian's own weights do not reach (long edges of sliver triangles, the
robot's fans) and spread a falloff ring by ring. Where the carried weight is already smooth and agrees with the landmarks
nothing but the mild data-term smoothing changes. Only the jaw's surroundings are solved: vertices
farther than :data:`REACH` face units from any jaw weight keep theirs (0), and the rounds after the
first re-solve only :data:`RINGS` rings of edges around the springs, the rest held (on a dense scan a
whole-face solve per round took seconds).

Seeds (what the landmarks say; :func:`autobones.rig_transfer.jaw_seeds.seeds`), each the vertex
nearest a landmark, or a band of vertices:

- lower (jaw 1): ``pogonion``, ``labiale_inferius``, ``sublabiale``, ``menton``, and the lower lip
  along the lip line (below the mouth surface through ``stomion`` and both ``cheilion``, in front
  of the line between the corners, within a thin band of it). The menton is pinned since issue 31
  (its check asks jaw >= 0.9 there; the carried weight gave 0.41-0.89 on rotated human heads and
  0.45 on the stuffed toy); below it the weight still fades toward the neck;
- a mouth interior (:func:`inner_mouth_sides`: ICT's, a game head's mouth bag; a closed-mouth scan
  has none): its floor, facing up across the mouth plane, is jaw 1 and its roof, facing down, jaw 0.
  Without them the interior was left to the smooth field between the outer lips' seeds: about half
  jaw on both, so an opened jaw dragged the inside of the upper lip down and left the inside of the
  lower lip behind;
- upper (jaw 0): the upper lip along the lip line (above the mouth surface, same band), the upper
  lip, nose, eye, brow, forehead, ear and skull landmarks, and every vertex more than
  :data:`ABOVE_MARGIN` face units above the jaw's top plane (``stomion`` and both ``gonion``; without
  gonions the mouth plane): the upper face, the eyes, the skull.

Seeds of the two sides fewer than :data:`~autobones.rig_transfer.jaw_seeds.GAP_EDGES` edges apart
with no lip line between would force a step no spring can spread, so the weaker one yields (is
solved instead of pinned): the upper face near any lower seed, a mouth interior's floor or roof
near a seed of the other side, and a chin landmark near an upper seed (a head without a lip line
whose chin is a few edges below its nose: the robot, the cat). The mouth surface is the plane of
the three mouth landmarks, steadied where the stomion lies on the corners' line and bent ahead of
the stomion on a snout whose lips meet at its tip (:mod:`autobones.rig_transfer.jaw_seeds`).

The lip line is the one place the field may jump: its edges (:func:`lip_line_edges`) join an
upper and a lower lip seed across the mouth surface, cross it between the lips of an open mouth,
or run near a corner. Missing landmarks drop their seeds; without ``stomion`` and both cheilions
there is no lip line and no band, and without ``stomion`` no plane: the carried weight is then
only smoothed where it jumps, with any chin or lip landmarks still pinned where they can be, and
``details["note"]`` (the sidecar's ``options.jaw``) says in one line what the landmarks could not
give. Vertices with eye weight (eyeballs bound to the eye bones) keep their jaw weight.

Every vertex keeps weights summing to 1: :func:`with_jaw` moves the jaw's gain or loss to or from
the head bone (then the other bones, proportionally, when the head bone has too little).

Frames and units: the head's own (any frame, any unit); lengths are in face units ``fu`` (the
exocanthion distance). All arrays are numpy, the matrices scipy sparse; the result is deterministic.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..geometry.areas import vertex_areas
from ..geometry.laplacian import clipped_cotangent_laplacian, factor_spd
from ..geometry.topology import mesh_edges, weld
from .jaw_seeds import (ABOVE_MARGIN, CORNER, INNER_BAND, INNER_DEPTH, INNER_FACING, LOWER,  # noqa: F401
                        UPPER, face_unit, inner_mouth_sides, jaw_note, lip_line_edges, mouth_frame,
                        mouth_height, seeds)

MAX_JUMP = 0.3          # the largest jaw-weight step allowed on an edge off the lip line
TARGET_JUMP = 0.27      # what the repair aims for (a margin below MAX_JUMP)
ROUNDS = 32             # smoothing rounds at most (16 left the SMPL man's chin-to-neck chain at 0.31: each round after
                        # the springs reach SPRING_CAP pins one more vertex of a chain, and a coarse chin's chain is long)
SPRING_CAP = 64.0        # the strongest spring, in the Laplacian's weights (an infeasible step stays local)
RINGS = 8               # rings of edges around the springs that later rounds re-solve
REACH = 0.4             # fu: vertices farther than this from any jaw weight keep theirs (0), unsolved


def _mean_edge_length(n, E, V):
    """(n,) mean length of each vertex's edges (0 for a vertex on none)."""
    length = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    # E.ravel() lists each edge's two ends in turn, so each length twice in turn (until 2026-12-06 the
    # lengths were listed all once then all again: a vertex got other edges' lengths, which changed
    # with the order the weld put the vertices in, i.e. with the file's axes)
    total = np.bincount(E.ravel(), weights=np.repeat(length, 2), minlength=n)
    count = np.bincount(E.ravel(), minlength=n)
    return total / np.maximum(count, 1)


def repair_jaw(V, F, jaw, landmarks, keep=None, details=None, still=None):
    """The jaw weight (n,) checked against the landmarks and repaired (module doc).

    Parameters
    ----------
    V : (n, 3) float
        The head's vertices, any frame and unit (the landmarks').
    F : (m, 3) int
        Its triangles; unwelded meshes are welded for the solve (coincident vertices share a value).
    jaw : (n,) float
        The carried jaw weight, 0..1.
    landmarks : dict str -> (3,) float
        The head's landmarks (contract names, ``spec/landmarks.md``), same frame and units as ``V``.
    keep : (n,) bool, optional
        Vertices whose jaw weight must not change (eyeballs bound to the eye bones).
    still : (n,) bool, optional
        Vertices held at their jaw weight unless they are seeds (the neck base, made still before:
        :mod:`.neck`): the falloff is solved smooth up to them instead of stepping there.
        Filled with ``lower`` / ``upper`` (n,) bool (the seeds), ``on_line`` (k,) bool and ``edges``
        (k, 2) (:func:`lip_line_edges`), ``rounds`` (int), ``max_jump`` (float, off the lip line) and
        ``note`` (str, :func:`autobones.rig_transfer.jaw_seeds.jaw_note`: what the landmarks cannot
        give, "" when nothing).

    Returns
    -------
    (n,) float
        The repaired jaw weight, 0..1.
    """
    from scipy.spatial import cKDTree

    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    w = np.clip(np.asarray(jaw, dtype=np.float64), 0.0, 1.0)
    lm = {k: np.asarray(v, dtype=np.float64) for k, v in landmarks.items()}
    fu = face_unit(V, lm)

    # the solve runs on the welded surface: an unwelded mesh (every face its own corners) would
    # have no edges between faces, and its seams would tear
    diag = float(np.linalg.norm(np.ptp(V, axis=0))) or 1.0
    Vw, Fw, index = weld(V, F, 1e-6 * diag)
    nw = len(Vw)
    Ew = mesh_edges(Fw)
    h = _mean_edge_length(nw, Ew, Vw)
    h_med = float(np.median(h[h > 0])) if (h > 0).any() else fu * 0.05
    h = np.where(h > 0, h, h_med)
    # edges allowed to jump: the lip line (across the mouth surface between the corners, and around them)
    on_line_w = lip_line_edges(Vw, Fw, lm)[1]
    tree = cKDTree(Vw)
    lower, upper, notes = seeds(Vw, Fw, Ew, on_line_w, lm, h, tree)

    # --- fixed values: seeds, and vertices that must keep theirs ----------------------------------
    ww = np.zeros(nw)
    np.maximum.at(ww, index, w)  # coincident vertices of an unwelded mesh: their largest weight
    fixed = lower | upper
    value = np.where(lower, 1.0, 0.0)
    if keep is not None:
        kw = np.zeros(nw, dtype=bool)
        kw[index[np.asarray(keep, dtype=bool)]] = True
        value = np.where(kw, ww, value)
        fixed |= kw
    if still is not None:
        sw = np.zeros(nw, dtype=bool)
        sw[index[np.asarray(still, dtype=bool)]] = True
        sw &= ~(lower | upper)   # a chin seed in the neck base (a chin at the mesh's bottom) wins
        value = np.where(sw, ww, value)
        fixed |= sw
    check = ~on_line_w & ~(fixed[Ew[:, 0]] & fixed[Ew[:, 1]])  # two fixed ends: nothing to solve
    # far from any jaw weight nothing is solved (the screened field decays within a few edges)
    settled = _settled(Vw, ww, lower, fixed, max(REACH * fu, 30.0 * h_med))
    value = np.where(settled, ww, value)
    fixed |= settled

    L, m = _local_laplacian(Vw, Fw, fixed)
    m = np.where(m > 0, m, h ** 2)  # vertices on no face: a nominal area
    # the data term holds the jaw's core harder than its rim: the falloff widens outward (into the
    # neck and the cheeks) instead of eating into the chin. One screening length for the head, its
    # median edge: with each vertex's own (correct) edge length the coarse robot's chin, two edges
    # under its nose, was smoothed to 0.33 of the jaw, 0.78 with the median (every other head alike,
    # benchmarks/README.md "the jaw's repair reads its own edges")
    lam = (0.1 + 0.9 * ww) * m / h_med ** 2
    x, rounds = _solve(Ew, L, lam, ww, value, fixed, on_line_w, check)

    out = x[index]
    if keep is not None:
        out = np.where(keep, w, out)
    if details is not None:
        E, on_line = lip_line_edges(V, F, lm)
        jump = np.abs(out[E[:, 0]] - out[E[:, 1]])
        details.update(lower=lower[index], upper=upper[index], edges=E, on_line=on_line, rounds=rounds,
                       max_jump=float(jump[~on_line].max()) if (~on_line).any() else 0.0,
                       note=_note(lm, notes, x[tree.query([lm[k] for k in notes])[1]] if notes else ()))
    return out


def _note(lm, yielded, weights):
    """One line (str, "" when all is well) for the rig's sidecar: what the landmarks cannot give
    (:func:`autobones.rig_transfer.jaw_seeds.jaw_note`) and the chin landmarks (``yielded``, list
    of str) left to the carried weight because a seed of the face above lies a few edges away,
    with the jaw weight (``weights``, floats) each got."""
    parts = [jaw_note(lm)]
    if yielded:
        got = ", ".join(f"{k} {float(v):.2f}" for k, v in zip(yielded, weights))
        parts.append(f"the chin is too few edges from the face above for a jaw weight of 1 that falls off "
                     f"smoothly: left to the carried weight ({got})")
    return "; ".join(p for p in parts if p)


def _settled(V, w, lower, fixed, reach):
    """(n,) bool: free vertices farther than ``reach`` (mesh units) from any jaw weight or lower
    seed: they keep their weight (0) unsolved. The data term holds such a vertex at 0 anyway, so
    the scalp, a bust's chest and the back of the neck need no solve; the solve and its Laplacian
    cover only the jaw's surroundings, a fraction of a dense scan. ``V`` (n, 3), ``w`` (n,) the
    carried weight, ``lower`` / ``fixed`` (n,) bool."""
    from scipy.spatial import cKDTree

    source = (w > 0) | lower
    if not source.any() or fixed.all():
        return np.zeros(len(V), dtype=bool)
    far = np.isinf(cKDTree(V[source]).query(V, distance_upper_bound=reach, workers=-1)[0])
    return ~fixed & far


def _local_laplacian(V, F, fixed):
    """The clipped cotangent Laplacian (n, n) sparse and the vertex areas (n,) of the faces around
    the free vertices (~``fixed``): complete rows for every free vertex, zero elsewhere. ``V`` (n, 3)
    mesh units, ``F`` (m, 3)."""
    n = len(V)
    sub_f = (~fixed[F]).any(axis=1)
    on_sub = np.zeros(n, dtype=bool)
    on_sub[F[sub_f].ravel()] = True
    rows = np.flatnonzero(on_sub)
    L, m = sp.csr_matrix((n, n)), np.zeros(n)
    if len(rows):
        Fs = (np.cumsum(on_sub) - 1)[F[sub_f]]
        Ls = clipped_cotangent_laplacian(V[rows], Fs).tocoo()
        L = sp.csr_matrix((Ls.data, (rows[Ls.row], rows[Ls.col])), shape=(n, n))
        m[rows] = vertex_areas(V[rows], Fs)
    return L, m


def _solve(E, L, lam, w, value, fixed, on_line, check):
    """The screened Laplace solve with springs on the edges that still jump (module doc).

    ``E`` (k, 2) the edges, ``L`` (n, n) the local Laplacian, ``lam`` (n,) the data term's weights,
    ``w`` (n,) the carried weight, ``value`` (n,) the fixed vertices' values, ``fixed`` (n,) bool
    (changed: vertices pinned by the stuck rule are added), ``on_line`` (k,) bool the lip line,
    ``check`` (k,) bool the edges whose jump is watched.
    Returns ``(x, rounds)``: the field (n,) in 0..1 and the rounds run."""
    n = len(w)
    x = value.copy()
    free = np.flatnonzero(~fixed)
    spring = np.zeros(len(E))
    rounds = 0
    solve_at = free
    for rounds in range(1, ROUNDS + 1):
        if len(solve_at):
            x[solve_at] = _solve_rows(E, L, lam, w, x, spring, solve_at)
        x = np.clip(x, 0.0, 1.0)
        jump = np.abs(x[E[:, 0]] - x[E[:, 1]])
        bad = check & (jump > TARGET_JUMP)
        if not bad.any():
            break
        stuck = bad & (spring >= SPRING_CAP) & (fixed[E[:, 0]] != fixed[E[:, 1]])
        if stuck.any():
            x = _pin_stuck(E, x, fixed, stuck)
            check = ~on_line & ~(fixed[E[:, 0]] & fixed[E[:, 1]])
        spring[bad] = np.minimum(np.maximum(2.0 * spring[bad], 1.0), SPRING_CAP)
        # later rounds re-solve only around the springs (RINGS rings of edges): the screened field
        # decays within a few edges, and a whole face's solve per round took seconds on dense scans
        near = np.zeros(n, dtype=bool)
        near[E[spring > 0].ravel()] = True
        for _ in range(RINGS):
            near[E[near[E].any(axis=1)].ravel()] = True
        solve_at = np.flatnonzero(near & ~fixed)
    return x, rounds


def _solve_rows(E, L, lam, w, x, spring, rows):
    """(len(rows),) the field at ``rows`` (int) solved with the rest of ``x`` (n,) held: the
    Laplacian ``L`` plus a graph Laplacian of the ``spring`` (k,) weights on the edges ``E`` (k, 2)
    (on sliver triangles the Laplacian's weight of a long edge is near zero, and only a spring
    evens its two ends), screened by ``lam`` (n,) toward ``w`` (n,)."""
    n = len(x)
    on = spring > 0
    Es, ks = E[on], spring[on]
    S = sp.csr_matrix((np.r_[ks, ks], (np.r_[Es[:, 0], Es[:, 1]], np.r_[Es[:, 1], Es[:, 0]])), shape=(n, n))
    r = np.arange(len(rows))
    degree = sp.csr_matrix((np.asarray(S.sum(axis=1)).ravel()[rows], (r, rows)), shape=(len(rows), n))
    K = L[rows] + degree - S[rows]
    held = x.copy()
    held[rows] = 0.0
    A = K[:, rows] + sp.diags(lam[rows])
    return factor_spd(A)(lam[rows] * w[rows] - K @ held)


def _pin_stuck(E, x, fixed, stuck):
    """A step against a fixed vertex that the strongest spring could not even out (the robot's
    nose tip, pinned at 0, a few edges above its chin): the free end of each ``stuck`` (k,) bool
    edge of ``E`` (k, 2) is pinned one allowed step from the fixed one (the lowest bound when it is
    lowered, the highest when raised), and the next rounds spread the rest of the falloff behind
    it. Returns the new ``x`` (n,); ``fixed`` (n,) bool gains the pinned vertices (in place)."""
    n = len(x)
    a = np.where(fixed[E[stuck, 0]], E[stuck, 0], E[stuck, 1])
    b = np.where(fixed[E[stuck, 0]], E[stuck, 1], E[stuck, 0])
    step = np.clip(x[b], x[a] - TARGET_JUMP, x[a] + TARGET_JUMP)
    pin = np.full(n, np.inf)
    np.minimum.at(pin, b, np.where(step < x[b], step, np.inf))
    high = np.full(n, -np.inf)
    np.maximum.at(high, b, np.where(step > x[b], step, -np.inf))
    fixed[b] = True
    return np.where(np.isfinite(pin), pin, np.where(np.isfinite(high), high, x))


def with_jaw(W, j, head, jaw):
    """Skin weights (n, b) with column ``j`` set to ``jaw`` (n,) and each row still summing to its
    old sum (1): the jaw's gain is taken from the ``head`` column (an index, or None) first, then
    from the other bones in proportion; its loss is given to the head column (to the other bones in
    proportion when there is no head column). New array."""
    W = np.asarray(W, dtype=np.float64)
    out = W.copy()
    delta = np.asarray(jaw, dtype=np.float64) - W[:, j]
    out[:, j] = jaw
    others = [k for k in range(W.shape[1]) if k != j]
    if head is not None:
        # the head bone gives (or takes) as much as it can
        take = np.minimum(delta, out[:, head])
        out[:, head] -= take
        delta = delta - take
        others = [k for k in others if k != head]
    # what is left: from (or to) the other bones in proportion to their weights
    rest = out[:, others].sum(axis=1) if others else np.zeros(len(W))
    scale = np.where(rest > 1e-12, 1.0 - delta / np.maximum(rest, 1e-12), 1.0)
    if others:
        out[:, others] *= np.clip(scale, 0.0, None)[:, None]
    left = np.where(rest > 1e-12, 0.0, delta)  # no other bone to take from or give to
    if head is not None:
        out[:, head] -= np.minimum(left, 0.0)
    return np.clip(out, 0.0, None)


def repair_jaw_weights(V, F, W, names, landmarks, details=None, still=None):
    """Skin weights ``W`` (n, b) (bone ``names``, list of b str) with the jaw column repaired by
    :func:`repair_jaw` and the head bone taking up the difference (:func:`with_jaw`); eyeball
    vertices (any ``eye_l`` / ``eye_r`` weight) keep theirs, ``still`` ones (n,) bool too unless
    they are seeds. A copy of ``W`` without a ``jaw`` bone. Rows keep their sums (1)."""
    W = np.asarray(W, dtype=np.float64)
    if "jaw" not in names:
        return W.copy()
    j = names.index("jaw")
    eyes = [names.index(e) for e in ("eye_l", "eye_r") if e in names]
    keep = (W[:, eyes].sum(axis=1) > 0) if eyes else None
    jaw = repair_jaw(V, F, W[:, j], landmarks, keep=keep, details=details, still=still)
    return with_jaw(W, j, names.index("head") if "head" in names else None, jaw)
