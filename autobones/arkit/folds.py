"""Fold repair of a displacement field: the triangles it turns over at weight 1 turned back.

Goes beyond the seeds (issue #15: "no triangle turned over at weight 1 for any shape"). A shape
carried onto a head (deformation transfer, :mod:`.deformation_transfer`) can turn a few
triangles over where its displacement changes fast or the head's surface is crumpled: a lid
margin in a blink, the lip line, the mouth corners of a scan. :func:`folded_triangles` finds
them (the normal at weight 1 points against the rest normal); :func:`unfold` moves only their
vertices, as little as turns them back (each is a constraint on its area signed along its rest
normal, all projected together onto their linearisations); every other vertex keeps its displacement
bit for bit. Tried first and dropped: a harmonic fill of the displacement over the folded
triangles and 1-6 rings, then as-rigid-as-possible steps: it left folds where the head is
crumpled (the menpo3d template's mouth) and flattened shapes (remeshed ICT identities 003, 007, skin
explained: mean 94.7 -> 92.9 %, mouthDimpleLeft 95 -> 62 %).

A shape meant on top of another (ARKit's ``mouthClose`` is driven together with ``jawOpen``:
alone it pushes the lips of a closed mouth through each other, and ICT's own folds 597
triangles so) is judged and repaired with the other's displacement under it (``base``).

Measured: ``benchmarks/arkit.py`` (fold table per head and shape, before and after; the
explained fraction with and without the repair) and ``benchmarks/arkit.py --fold-heads``.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

from ..errors import AutobonesError, counted
from ..geometry.normals import cross_rows, triangle_normals

# ARKit shapes driven together with another: judged (and repaired) on top of it
ON_TOP = {"mouthClose": "jawOpen"}
# a projection aims each violated triangle at this share of its target area: the loop stops once
# every one has half (a margin for rounding to float32), and a step to the whole target moved the
# menpo3d template's lips twice as far (largest change 2.2 -> 5.7 % of half its size, 51 shapes)
AIM = 0.55


def folded_triangles(V, F, D, base=None, rest_normals=None):
    """Triangles turned over by a displacement: (m,) bool.

    Parameters
    ----------
    V : (n, 3) float
        Rest vertices, any frame and units.
    F : (m, 3) int
    D : (n, 3) float
        Displacement at weight 1, same frame and units.
    base : (n, 3) float, optional
        A displacement applied under ``D`` (``V + base + D`` is judged).
    rest_normals : (m, 3) float, optional
        ``triangle_normals(V, F)``, when already known.

    Returns
    -------
    (m,) bool
        The triangles whose normal at ``V + base + D`` points against the rest normal (dot < 0).
        Triangles degenerate at rest (zero normal) never count.
    """
    rest = triangle_normals(V, F) if rest_normals is None else rest_normals
    X = V + D if base is None else V + base + D
    moving = (D != 0).any(axis=1) if base is None else ((D != 0) | (base != 0)).any(axis=1)
    if moving.sum() > 0.5 * len(moving):  # a solved shape moves nearly every vertex a little: no subset
        return np.einsum("ij,ij->i", rest, triangle_normals(X, F)) < 0
    # only triangles with a moving corner can turn (most source shapes move a small part of the head)
    T = np.flatnonzero(moving[F].any(axis=1))
    out = np.zeros(len(F), dtype=bool)
    out[T] = np.einsum("ij,ij->i", rest[T], triangle_normals(X, F[T])) < 0
    return out


def folded_each(V, F, deltas, rest_normals=None, block=1024):
    """:func:`folded_triangles` of every displacement of ``deltas`` (k, n, 3): (k, m) bool.

    All shapes at once, in blocks of ``block`` triangles that stay in cache, first in float32
    (the test is memory-bound: half the bytes), then in float64 for the triangles whose float32
    test is not clear by a wide margin (signed area within 1e-4 of the rest area's square, far
    above float32's round-off), so the answer is :func:`folded_triangles`'s exactly.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    rest = triangle_normals(V, F) if rest_normals is None else rest_normals
    deltas = np.asarray(deltas, dtype=np.float64)
    k = len(deltas)
    X = (np.transpose(deltas, (1, 2, 0)) + V[:, :, None]).astype(np.float32)  # (n, 3, k)
    rest32 = rest.astype(np.float32)
    margin = (1e-4 * np.einsum("ij,ij->i", rest, rest)).astype(np.float32)
    out = np.empty((len(F), k), dtype=bool)
    unsure = []
    for s in range(0, len(F), block):
        f, r = F[s:s + block], rest32[s:s + block]
        x0 = X[f[:, 0]]
        a = X[f[:, 1]] - x0
        b = X[f[:, 2]] - x0
        dot = r[:, 0, None] * (a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1])
        dot += r[:, 1, None] * (a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2])
        dot += r[:, 2, None] * (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
        out[s:s + block] = dot < 0
        t, j = np.nonzero(np.abs(dot) <= margin[s:s + block, None])
        unsure.append((t + s, j))
    t = np.concatenate([u[0] for u in unsure])
    j = np.concatenate([u[1] for u in unsure])
    if len(t):  # the close calls again in float64
        x0 = V[F[t, 0]] + deltas[j, F[t, 0]]
        n = cross_rows(V[F[t, 1]] + deltas[j, F[t, 1]] - x0, V[F[t, 2]] + deltas[j, F[t, 2]] - x0)
        out[t, j] = np.einsum("ij,ij->i", rest[t], n) < 0
    return out.T


class _Context:
    """What :func:`unfold` needs of a head, computed once for all its shapes."""

    def __init__(self, V, F, rest_normals=None):
        self.V, self.F = V, F
        self.rest = triangle_normals(V, F) if rest_normals is None else rest_normals
        self.size = np.linalg.norm(self.rest, axis=1)
        self.unit = self.rest / np.maximum(self.size, 1e-300)[:, None]
        m = len(F)
        self.incidence = sp.csr_matrix((np.ones(3 * m, dtype=bool), (F.ravel(), np.repeat(np.arange(m), 3))),
                                       shape=(len(V), m))

    def faces_of(self, vertices):
        """Triangles (sorted, unique) with a corner among ``vertices`` (int array)."""
        return np.unique(self.incidence[vertices].indices)


def _signed_areas(X, F, T, unit_normals):
    """Areas (len(T),) of triangles ``F[T]`` at ``X``, signed along their unit rest normals."""
    x0, x1, x2 = X[F[T, 0]], X[F[T, 1]], X[F[T, 2]]
    return 0.5 * np.einsum("ij,ij->i", unit_normals[T], cross_rows(x1 - x0, x2 - x0))


def unfold(V, F, D, base=None, fixed=None, margin=0.1, iterations=20000, rest_normals=None, dtype=None,
           folded=None, context=None):
    """Move the vertices of the triangles a displacement turns over, as little as will turn them back.

    Each turned-over triangle is a constraint: its area signed along its rest normal at least
    ``margin`` times its rest area. Every iteration projects the violated constraints together onto
    their linearisations, by the least move of their vertices that meets them all (a Gauss-Newton
    step; :func:`_project`). A triangle that a move turns over joins the constraints. Only
    vertices of triangles that were turned over move; all others keep their displacement bit for bit.

    Parameters
    ----------
    V : (n, 3) float
        Rest vertices, any frame and units.
    F : (m, 3) int
    D : (n, 3) float
        Displacement at weight 1 to repair, same frame and units.
    base : (n, 3) float, optional
        Displacement under ``D`` (judged is ``V + base + D``; only ``D`` changes).
    fixed : (n,) bool, optional
        Vertices whose displacement never changes (separate eyeballs turned by their bone).
    margin : float
        The signed area asked of a repaired triangle, as a fraction of its rest area.
    iterations : int
        Cap on projections (joint projections take 1-80 per shape on the shared heads; the
        one-triangle-at-a-time sweeps they replaced took up to 12,055).
    rest_normals : (m, 3) float, optional
        ``triangle_normals(V, F)``, when already known (several shapes).
    dtype : numpy dtype, optional
        The precision the result will be stored in (``np.float32`` for a glb): the repaired
        vertices are rounded to it and ``after`` is counted on the result (the others keep
        their values: give ``D`` already rounded).
    folded : (m,) bool, optional
        :func:`folded_triangles` of ``D`` on ``base``, when already known (:func:`folded_each`).
    context : optional
        The head's :class:`_Context` (several shapes of one head).

    Returns
    -------
    D : (n, 3) float64
        The repaired displacement (a copy).
    report : dict
        ``before`` and ``after`` (turned-over triangle counts), ``iterations``, ``vertices`` (how
        many changed), ``max_change`` (largest change of a vertex's displacement, input units).
    """
    V, F, D0 = _checked(V, F, D)
    n = len(V)
    ctx = _Context(V, F, rest_normals) if context is None else context
    bad = folded_triangles(V, F, D0, base, ctx.rest) if folded is None else np.asarray(folded, dtype=bool)
    report = {"before": int(bad.sum()), "after": int(bad.sum()), "iterations": 0, "vertices": 0, "max_change": 0.0}
    if not bad.any():
        return D0.copy(), report
    B = np.zeros_like(V) if base is None else np.asarray(base, dtype=np.float64)
    unit = ctx.unit
    target = margin * 0.5 * ctx.size
    w = np.ones(n) if fixed is None else (~np.asarray(fixed, dtype=bool)).astype(np.float64)
    X = V + B + D0
    moved, report["iterations"] = _project_folds(ctx, X, F, bad, target, w, iterations)
    out = D0.copy()  # the vertices never moved keep their displacement bit for bit
    out[moved] = X[moved] - V[moved] - B[moved]
    if dtype is not None:
        out[moved] = out[moved].astype(dtype)
    changed = np.linalg.norm(out[moved] - D0[moved], axis=1)
    # every triangle turned over at first had its vertices moved: only the moved ones' can be turned now
    near = ctx.faces_of(np.flatnonzero(moved))
    after = int((_signed_areas(V + B + out, F, near, unit) < 0).sum())
    report.update(after=after, vertices=int(moved.sum()), max_change=float(changed.max(initial=0.0)))
    return out, report


def _checked(V, F, D):
    """``V`` (n, 3) and ``D`` (n, 3) as float64, ``F`` (m, 3) as int64 indices of ``V``; an error
    naming the shapes otherwise."""
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    D0 = np.asarray(D, dtype=np.float64)
    if V.ndim != 2 or V.shape[1] != 3 or D0.shape != V.shape:
        raise AutobonesError(f"fold repair: vertices {V.shape} and displacement {D0.shape} must both be (n, 3)")
    if F.ndim != 2 or F.shape[1] != 3 or (len(F) and (F.min() < 0 or F.max() >= len(V))):
        raise AutobonesError(f"fold repair: faces {F.shape} must be (m, 3) indices of the {counted(len(V), 'vertex', 'vertices')}")
    return V, F, D0


def _project_folds(ctx, X, F, bad, target, w, iterations):
    """:func:`unfold`'s projection sweeps on the judged positions ``X`` (n, 3, changed in place),
    ``F`` (m, 3), starting from the turned-over triangles ``bad`` (m,) bool; ``target`` (m,) the signed area
    asked of each triangle (input units squared), ``w`` (n,) 1 for a vertex free to move, 0 for
    a fixed one. Returns which vertices moved (n,) bool and the sweeps that projected."""
    unit = ctx.unit
    active = bad.copy()
    moved = np.zeros(len(X), dtype=bool)
    T = np.flatnonzero(active)
    done = 0
    for it in range(iterations):
        A = _signed_areas(X, F, T, unit)
        viol = (A < target[T]) & (active[T] | (A < 0))
        # done when every constraint is at least half met (a margin against rounding to float32)
        if not (A < 0.5 * target[T]).any():
            # nothing left among these: only triangles of moved vertices can have turned since
            newly = _turned_near(ctx, X, F, active, np.flatnonzero(moved))
            if not len(newly):
                break
            active[newly] = True
            T = np.flatnonzero(active)
            continue
        active[T[viol]] = True
        Tb = T[viol]
        verts = _project(X, F, Tb, A[viol], unit, target, w)
        moved[verts] |= w[verts] > 0
        if it % 20 == 19:  # triangles the moves turned over join the constraints
            active[_turned_near(ctx, X, F, active, np.unique(F[Tb]))] = True
            T = np.flatnonzero(active)
        done = it + 1
    return moved, done


def _turned_near(ctx, X, F, active, vertices):
    """Triangles not yet ``active`` (m,) bool, with a corner among ``vertices`` (int array), that
    are turned over at ``X`` (n, 3) (triangles ``F`` (m, 3)): int array."""
    near = ctx.faces_of(vertices)
    near = near[~active[near]]
    return near[_signed_areas(X, F, near, ctx.unit) < 0]


def _project(X, F, Tb, A, unit, target, w):
    """One projection of the violated triangles ``Tb`` (int array; signed areas ``A``, same length),
    all at once: the least move (each vertex's weighted by ``w`` (n,)) that brings every one onto its
    linearised constraint, its area along the rest normal at ``AIM`` of its ``target`` (m,). With
    ``G`` the areas' gradients (k, 3v): ``dx = W G^T (G W G^T)^-1 (AIM target - A)``, a Gauss-Newton
    step of the constraints together. ``X`` (n, 3) changed in place. Returns the vertices touched
    (sorted, unique).

    Each triangle moved on its own, the moves of a shared vertex averaged (Jacobi, as position-based
    dynamics does), undid part of every move in a cluster of small triangles: the menpo3d
    template's mouthRollUpper took 12,055 sweeps (2.4 s), and on the template subdivided to 213k
    vertices it stopped at the 20,000-sweep cap with 3 triangles still turned."""
    x0, x1, x2 = X[F[Tb, 0]], X[F[Tb, 1]], X[F[Tb, 2]]
    u = unit[Tb]
    grads = np.stack([0.5 * cross_rows(x1 - x2, u), 0.5 * cross_rows(x2 - x0, u),
                      0.5 * cross_rows(x0 - x1, u)], axis=1)          # (k, 3 corners, 3)
    verts, local = np.unique(F[Tb], return_inverse=True)
    k, nv = len(Tb), len(verts)
    cols = (3 * local.reshape(k, 3)[:, :, None] + np.arange(3)).reshape(k, 9)
    G = sp.csr_matrix((grads.reshape(k, 9).ravel(), (np.repeat(np.arange(k), 9), cols.ravel())), shape=(k, 3 * nv))
    wv = np.repeat(w[verts], 3)
    K = (G @ sp.diags(wv) @ G.T).tocsc()
    # a triangle whose corners are all fixed has a zero row: the ridge keeps K invertible, and that
    # row's multiplier meets only zero weights
    ridge = 1e-12 * max(float(K.diagonal().max(initial=0.0)), 1e-300)
    lam = np.atleast_1d(spsolve(K + ridge * sp.identity(k, format="csc"), AIM * target[Tb] - A))
    X[verts] += (wv * (G.T @ lam)).reshape(nv, 3)
    return verts


def unfold_shapes(V, F, deltas, names, fixed=None, **options):
    """:func:`unfold` on every shape of a set, a shape of :data:`ON_TOP` judged on top of its base.

    Parameters
    ----------
    V : (n, 3) float, F : (m, 3) int
        The head at rest, any frame and units.
    deltas : (k, n, 3) float
        Displacements at weight 1, one per name, same frame and units.
    names : sequence of k str
        ARKit names of ``deltas`` (``mouthClose`` is judged with ``jawOpen`` under it when both are given).
    fixed : (n,) bool, optional
        Vertices never changed.
    **options
        Passed to :func:`unfold`.

    Returns
    -------
    deltas : (k, n, 3) float64
        Repaired (bases first, so a shape on top is judged on its repaired base).
    report : dict name -> dict
        :func:`unfold`'s report per name, plus ``on_top_of`` (the base's name or None).
    """
    D = np.asarray(deltas, dtype=np.float64)
    names = list(names)
    if len(names) != len(D):
        raise AutobonesError(f"fold repair: {counted(len(names), 'name')} for {counted(len(D), 'displacement field')}")
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    ctx = _Context(V, F)
    out = D.copy()
    report = {}
    later = [j for j, n in enumerate(names) if ON_TOP.get(n) is not None and ON_TOP.get(n) in names]
    first = [j for j in range(len(names)) if j not in later]
    folded = dict(zip(first, folded_each(V, F, D[first], ctx.rest)))  # a shape on top waits for its base
    for j in first + later:
        under = ON_TOP.get(names[j]) if j in later else None
        base = out[names.index(under)] if under else None
        out[j], rep = unfold(V, F, D[j], base=base, fixed=fixed, folded=folded.get(j), context=ctx, **options)
        rep["on_top_of"] = under
        report[names[j]] = rep
    return out, report
