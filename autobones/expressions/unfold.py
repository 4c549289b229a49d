"""Unfolding: skin triangles the lids or the jaw turn over, relaxed or moved as one piece.

Beyond the cited methods: a wide jaw opening turns each vertex by its own angle, and where the
jaw weight changes fast (under the chin, the mouth corners) neighbouring skin can swing past
each other. Skin cannot fold through itself, so around the turned-over triangles the displacement
is relaxed toward its neighbours' mean (:func:`unfold`); what that leaves folded (slivers where
the surface itself folds sharply, as in the mouth corners' commissure) moves as one piece with
the rigid or affine motion of the skin around it (:func:`rigid_patches`).

Displacements are canonical (+Y up, +Z front), head sizes; the welded-mesh quantities come from
the model's :class:`~autobones.expressions.surface.SkinSurface`.
"""
from __future__ import annotations

import numpy as np
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..geometry.normals import triangle_normals
from ..geometry.rotations import similarity


def turned_faces(P, F, n0):
    """(m,) bool: triangles ``F`` (m, 3) at positions ``P`` (n, 3) whose normal turned from the
    rest normals ``n0`` (m, 3) by over 90 degrees."""
    return (n0 * triangle_normals(P, F)).sum(axis=1) <= 0


def flipped_faces(V0, V1, F, min_area=0.0):
    """Boolean (m,): triangles whose normal turned by more than 90 degrees from ``V0`` to ``V1``.

    ``V0``, ``V1`` (n, 3) rest and posed vertices, ``F`` (m, 3); triangles whose rest area is
    not above ``min_area`` (units of V0 squared; degenerate ones at the default 0) never count.
    """
    n0 = triangle_normals(V0, F)
    return (0.5 * np.linalg.norm(n0, axis=1) > min_area) & turned_faces(V1, F, n0)


def _relax(Vw, dw, surface, reach, rounds, passes):
    """The relaxation rounds of :func:`unfold` on the welded displacement ``dw`` (nw, 3), in place.
    Returns the state with the least folded area and the vertices relaxed to reach it."""
    A, skin_w, Fs, n0, area = (surface.adjacency, surface.skin_welded, surface.skin_faces, surface.rest_normals,
                               surface.rest_areas)
    Wu, wdeg = surface.relax_weights, surface.relax_degree
    touched = np.zeros(len(Vw), dtype=bool)
    grow = np.zeros(len(Vw), dtype=bool)
    faces = np.arange(len(Fs))                # faces whose vertices may have moved
    last, stale, allowed = None, 0, None
    for _ in range(rounds):
        bad = faces[turned_faces(Vw + dw, Fs[faces], n0[faces])]
        amount = float(area[bad].sum())
        if last is None or amount < last:       # keep the state with the least folded area
            best, best_touched = dw.copy(), touched.copy()
        if not len(bad):
            break
        # stop when relaxing no longer helps (a fold the mean cannot undo)
        stale = stale + 1 if last is not None and amount >= last else 0
        last = amount if last is None else min(last, amount)
        if stale >= 8:
            break
        grow[Fs[bad].ravel()] = True
        if allowed is None:   # the relaxation stays within ``reach`` of the first folds
            seeds = np.unique(Fs[bad].ravel())
            near = cKDTree(Vw[seeds]).query(Vw, distance_upper_bound=reach)[0]
            allowed = np.isfinite(near) & skin_w
        for _ring in range(2):
            grow |= (A @ grow.astype(np.float64)) > 0
        grow &= allowed
        # only skin within ``reach`` of the folds left now relaxes further: where folds are
        # undone (under the chin) the skin is not dragged on toward the harmonic fill while
        # folds elsewhere (the mouth corners) persist
        G = np.flatnonzero(grow)
        near_now = cKDTree(Vw[np.unique(Fs[bad].ravel())]).query(Vw[G], distance_upper_bound=reach)[0]
        active = np.zeros(len(Vw), dtype=bool)
        active[G[np.isfinite(near_now)]] = True
        touched |= active
        rows = np.flatnonzero(active)
        faces = np.flatnonzero(grow[Fs].any(axis=1))
        rows = rows[wdeg[rows] > 0]
        Wr = Wu[rows]
        for _p in range(passes):
            dw[rows] = (Wr @ dw) / np.maximum(wdeg[rows], 1e-300)[:, None]
    return best, best_touched


def _keep_helpful(Vw, d0, best, touched, surface):
    """Undo each connected relaxed patch of ``best`` that does not leave less skin folded than
    the unrelaxed ``d0`` (a patch grown around a few slivers must not fold their larger
    neighbours instead). Updates ``best`` and ``touched`` in place."""
    A, Fs, n0, area = surface.adjacency, surface.skin_faces, surface.rest_normals, surface.rest_areas
    T = np.flatnonzero(touched)
    n_c, lab = connected_components(A[T][:, T], directed=False)
    comp = np.full(len(Vw), n_c)
    comp[T] = lab
    face_c = comp[Fs].min(axis=1)              # a face touches at most one patch
    before, after = (np.bincount(face_c, weights=area * turned_faces(Vw + q, Fs, n0), minlength=n_c + 1)
                     for q in (d0, best))
    undo = np.flatnonzero(after[:n_c] >= before[:n_c])
    if len(undo):
        back = np.isin(comp, undo)
        best[back] = d0[back]
        touched &= ~back


def unfold(d, V, surface, reach, rounds=40, passes=8):
    """Relax the canonical displacement ``d`` (n, 3) where skin triangles turned over.

    Around every skin triangle whose normal turned by more than 90 degrees (and the two rings of
    vertices about it) the displacement is replaced by its neighbours' mean, weighted by the
    intrinsic Laplacian (Jacobi passes, the ring outside held), the region growing (never farther
    than ``reach`` from the first folds; each round relaxing only its part within ``reach`` of the
    folds left, so skin whose folds are undone is not smoothed on while others persist) until
    nothing is turned over, ``rounds`` run out or eight rounds in a row leave no less folded area;
    the state with the least folded area (rest area of the turned triangles) is kept, and of it
    each connected relaxed patch only where it leaves less folded area than before (never more
    anywhere). What still folds then moves as one piece with the skin around it
    (:func:`rigid_patches`). Vertices away from folds keep their displacement exactly.

    Parameters
    ----------
    d : (n, 3) float
        Displacement, canonical frame, head sizes.
    V : (n, 3) float
        Rest vertices, canonical frame, head sizes.
    surface : SkinSurface
        The welded skin and its operators.
    reach : float
        Head sizes (the definitions' ``unfold_reach`` times the face unit).

    Returns
    -------
    (n, 3) float
        The displacement (``d`` itself when nothing needed unfolding).
    """
    index, first = surface.index, surface.first
    Vw = V[first]
    best, best_touched = _relax(Vw, d[first].copy(), surface, reach, rounds, passes)
    if not best_touched.any():
        best, rigid = rigid_patches(Vw, d[first].copy(), surface, reach)
        if not rigid.any():
            return d
        out = d.copy()
        out[rigid[index]] = best[index[rigid[index]]]
        return out
    _keep_helpful(Vw, d[first], best, best_touched, surface)
    best, rigid = rigid_patches(Vw, best, surface, reach)
    best_touched |= rigid
    out = d.copy()
    moved = best_touched[index]
    out[moved] = best[index[moved]]
    return out


def rigid_patches(Vw, dw, surface, reach, rings=6, sweeps=12):
    """Move what relaxation left folded as one piece.

    Slivers where the surface itself folds sharply (the mouth corners' commissure, where the
    upper lip overhangs the lower one; the mouth's lining between the lips) stay turned over
    under any averaging of the displacement. Each connected cluster of still-folded triangles is
    grown ring by ring; its vertices take the rigid motion (rotation and translation, least
    squares), or else the orientation-preserving affine map, that best fits the displacement of
    the ring of vertices around it, so the cluster turns and stretches only as its surroundings
    do, the next feather rings blending back to their own displacement. The first candidate that
    leaves no triangle about the cluster folded is kept (else the one removing the most folded
    area, if any; never beyond ``reach`` of the cluster); sweeps repeat while they change anything.

    ``Vw`` (nw, 3) welded rest vertices and ``dw`` (nw, 3) their displacement (canonical, head
    sizes; ``dw`` is updated in place), ``surface`` the SkinSurface, ``reach`` head sizes.
    Returns the displacement (nw, 3) and the vertices moved (nw,) bool.
    """
    moved = np.zeros(len(Vw), dtype=bool)
    for _ in range(sweeps):
        dw, m = rigid_sweep(Vw, dw, surface, reach, rings)
        if not m.any():
            break
        moved |= m
    return dw, moved


def _ring_maps(X, Y):
    """Maps ``y ~ M (x - mx) + my`` fitted to ring points ``X`` -> ``Y`` (r, 3): the rigid one,
    and the affine one when it keeps orientation. Returns (list of (3, 3), mx, my)."""
    mx, my = X.mean(axis=0), Y.mean(axis=0)
    maps = [similarity(Y, X)[1].T]   # takes Y onto X as columns: its transpose takes X onto Y
    if len(X) >= 4:
        Aff = np.linalg.lstsq(X - mx, Y - my, rcond=None)[0].T
        if np.linalg.det(Aff) > 0:
            maps.append(Aff)
    return maps, mx, my


def _try_maps(Vw, dw, shells, fitted, surface, feathers, best):
    """Try each map of ``fitted`` on the cluster ``shells[0]``, feathered over each of
    ``feathers`` rings. ``best`` is (gain, (rows, values) or None). Returns the updated best and
    whether a candidate left nothing folded about the cluster."""
    Fs, n0, area = surface.skin_faces, surface.rest_normals, surface.rest_areas
    maps, mx, my = fitted
    best_gain, best_q = best
    for fe in feathers:
        near = shells[fe + 1]
        local = np.flatnonzero(near[Fs].any(axis=1))
        before = float((area[local] * turned_faces(Vw + dw, Fs[local], n0[local])).sum())
        alpha = np.zeros(len(Vw))
        for k in range(fe + 1):      # 1 on the core, fading over the feather rings
            alpha[shells[k] & (alpha == 0)] = 1.0 - k / (fe + 1.0)
        rows = np.flatnonzero(alpha > 0)
        for Mm in maps:
            q = dw.copy()
            target = (Vw[rows] - mx) @ Mm.T + my - Vw[rows]
            q[rows] = alpha[rows, None] * target + (1.0 - alpha[rows, None]) * dw[rows]
            amount = float((area[local] * turned_faces(Vw + q, Fs[local], n0[local])).sum())
            if before - amount > best_gain:
                best_gain, best_q = before - amount, (rows, q[rows])
            if amount == 0.0 and before > 0.0:
                return (best_gain, best_q), True
    return (best_gain, best_q), False


def rigid_sweep(Vw, dw, surface, reach, rings, feathers=(0, 1, 2, 4)):
    """One sweep of :func:`rigid_patches` over the clusters folded now (same arguments; ``dw``
    updated in place). Returns ``dw`` and the vertices moved (nw,) bool."""
    A, skin_w, Fs, n0 = surface.adjacency, surface.skin_welded, surface.skin_faces, surface.rest_normals
    moved = np.zeros(len(Vw), dtype=bool)
    bad = np.flatnonzero(turned_faces(Vw + dw, Fs, n0))
    if not len(bad):
        return dw, moved

    def grow(mask):
        return (((A @ mask.astype(np.float64)) > 0) | mask) & skin_w

    V_bad = np.unique(Fs[bad].ravel())
    n_c, lab = connected_components(A[V_bad][:, V_bad], directed=False)
    for c in range(n_c):
        seed = V_bad[lab == c]
        core = np.zeros(len(Vw), dtype=bool)
        core[seed] = True
        centre = Vw[seed].mean(axis=0)
        best = (0.0, None)
        for _r in range(rings):
            shells = [core]
            for _f in range(max(feathers) + 1):
                shells.append(grow(shells[-1]))
            R_ = np.flatnonzero(shells[1] & ~core)
            if len(R_) < 3 or np.linalg.norm(Vw[R_] - centre, axis=1).max() > reach:
                break
            best, done = _try_maps(Vw, dw, shells, _ring_maps(Vw[R_], Vw[R_] + dw[R_]), surface, feathers, best)
            if done:
                break
            core = shells[1]
        if best[1] is not None:
            dw[best[1][0]] = best[1][1]
            moved[best[1][0]] = True
    return dw, moved
