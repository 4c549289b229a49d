"""The blink's lid margins brought together on the head's own lids, after the transfer.

Goes beyond the seeds (issues #31 check 7 and #34 item 3). ARKit's ``eyeBlinkLeft`` / ``eyeBlinkRight``
at weight 1 are the eye closed: the upper lid margin on the lower one. Deformation transfer
carries a shape's gradients, not that relation, and the source's own blink (ICT-FaceKit's) leaves
its thick lids' front edges apart; carried onto other heads the blink brought the upper margin
71-83 % of the way to the lower one (james, the menpo3d template, ICT identities, LeePerrySmith;
:func:`autobones.arkit.lids.gap_closure`'s ``margins``). This module closes the rest on the blink
shape itself:

* each eye's margins are the curves of :func:`autobones.arkit.lids.margin_curves` (through the
  canthi and the palpebrale landmark, laid on the skin); every skin vertex near the eye has a
  canthal parameter ``t`` and, as the shape leaves it, a place ``x`` across the eye: 0 on the
  lower margin, 1 on the upper (:func:`lid_region`);
* the vertices above the lower margin move, the rest stay: a small sparse least-squares solve
  (:func:`_meeting_move`) asks the margins at ``samples`` parameters to come to ``1 - meet`` of
  the gap the shape leaves, each moving vertex to take its share of its own upper margin point's
  move (``x`` across the eye surface between the margins, so a one-surface scan's eye closes like
  a curtain, its rows in order; 1 on the upper margin and falling smoothly to 0 at ``reach`` rest
  gaps above it, so the lid carries its margin and the brow stays), and the move to be smooth
  (a membrane on the mesh's edges);
* a vertex the move would take inside a separate eyeball (``eyeballs``: centre, radius, fitted
  to the eyeball's vertices) is put back on the eyeball's surface or at its rest distance,
  whichever is smaller: the lid slides over the eye, not through it.

:func:`autobones.arkit.targets.arkit_targets` calls it before its fold repair: squashed to 5 % of
its height, a one-surface eye's surface turns a few triangles over where the solve misses the
exact curtain by a few percent of that height, and the repair turns them back (measured after it:
the margins 94-99 % of the way, no triangle turned over, on the heads above).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

from ..geometry.topology import mesh_edges
from .lids import canthal_parameter, eye_sides, margin_curves, skin_faces

BLINKS = {"eyeBlinkLeft": "l", "eyeBlinkRight": "r"}  # ARKit's Left is the subject's own left
BLINK_CLOSED = 0.9  # a blink closes at least this fraction of the gap (issue #34), else the sidecar says why


def lids_note(apart):
    """One line for the sidecar and the log: the blinks of ``apart`` (name -> :func:`meet_lids`'s
    report) whose margins stay more than ``1 - BLINK_CLOSED`` of the gap apart, and why."""
    parts = []
    for name, r in apart.items():
        why = (f"the eye opening is one triangle high at {r['one_triangle']:.0%} of the lid (no vertex between "
               "the margins to part them; more vertices across the eye close more)") if r["one_triangle"] >= 0.5 else \
            "the move that closes them was held back (eyeball or folds)"
        parts.append(f"{name} leaves its lid margins {r['open']:.0%} of the open gap apart: {why}")
    return "; ".join(parts)


def _smooth_fall(x):
    """1 at x <= 0, 0 at x >= 1, a cosine between: (k,)."""
    x = np.clip(x, 0.0, 1.0)
    return 0.5 * (1.0 + np.cos(np.pi * x))


def lid_region(V, F, landmarks, side, corner=0.15, depth=0.5, faces=None):
    """Skin vertices near one eye (those a blink's lid move may reach) and their margin points.

    ``V`` (n, 3) float, ``F`` (m, 3) int, ``landmarks`` name -> (3,) with the eye's four
    (``endocanthion``, ``palpebrale_superius``, ``exocanthion``, ``palpebrale_inferius``), same
    frame and units. ``corner``: how far past the canthi (in canthal lengths); ``depth``: vertices
    farther than this many canthal lengths from the line across the eye at their ``t`` are left
    out (the socket behind the lids). ``faces``: the skin's triangles (:func:`skin_faces`), when known.

    Returns ``(vertices (p,) int64, Ru, Rl)``: ``Ru`` / ``Rl`` (p, n) sparse, each vertex's point
    on the upper / lower margin at its own ``t``.
    """
    E, X = (np.asarray(landmarks[f"{n}_{side}"], dtype=np.float64) for n in ("endocanthion", "exocanthion"))
    fissure = float(np.linalg.norm(X - E))
    faces = skin_faces(V, F) if faces is None else faces
    skin = np.unique(F[faces])
    t = canthal_parameter(V[skin], landmarks, side)
    near = (t > -corner) & (t < 1.0 + corner) & (np.linalg.norm(V[skin] - 0.5 * (E + X), axis=1) < fissure)
    cand, t = skin[near], t[near]
    (U, L), (Ru, Rl) = margin_curves(V, F, landmarks, side, np.clip(t, 0.0, 1.0), faces)
    b = U - L
    h = np.einsum("ij,ij->i", V[cand] - L, b) / np.maximum(np.einsum("ij,ij->i", b, b), 1e-300)
    off = np.linalg.norm(V[cand] - (L + h[:, None] * b), axis=1)
    # deep behind the line across the eye is the socket, not the lid
    keep = off < depth * fissure
    return cand[keep], Ru[keep].tocsr(), Rl[keep].tocsr()


def _off_eyeballs(P, rest, eyeballs):
    """``P`` (p, 3) moved points, ``rest`` (p, 3) their rest positions: put back outside each
    eyeball (centre (3,), radius) they were outside of at rest; (p, 3)."""
    P = P.copy()
    for c, radius in eyeballs:
        d_rest = np.linalg.norm(rest - c, axis=1)
        v = P - c
        d = np.linalg.norm(v, axis=1)
        floor = np.minimum(d_rest, radius)
        inside = (d_rest >= 0.98 * radius) & (d < floor) & (d > 0)
        P[inside] = c + v[inside] * (floor[inside] / d[inside])[:, None]
    return P


def _meeting_move(n, F, free, rows, want, curtain=None, weight=1e3):
    """The smoothest move of the ``free`` vertices that brings the margin rows to ``want``.

    ``n`` the vertex count, ``F`` (m, 3) the triangles; ``rows`` (k, n) sparse: the margins' gap at k parameters (upper point minus lower point, as
    interpolated from the vertices); ``want`` (k, 3) the change of that gap asked for. Minimises
    ``sum over edges |c_i - c_j|^2 + weight |rows c - want|^2`` over ``c`` on ``free`` (p,) int,
    zero elsewhere (the edges to fixed vertices hold the move's rim at 0): a membrane, so the move
    falls off linearly from the margin to the rim. ``curtain``: ``(vertices (q,), share (q,), Ru (q, n))``,
    vertices asked (same weight) to move by ``share`` times their upper margin point's move (``Ru``
    its row). Returns (p, 3).
    """
    E = mesh_edges(F)
    p = len(free)
    pos = np.full(n, -1, dtype=np.int64)
    pos[free] = np.arange(p)
    E = E[(pos[E] >= 0).any(axis=1)]
    a, b = pos[E[:, 0]], pos[E[:, 1]]
    # graph Laplacian on the free vertices; an edge to a fixed vertex adds only its diagonal
    both = (a >= 0) & (b >= 0)
    diag = np.bincount(a[a >= 0], minlength=p) + np.bincount(b[b >= 0], minlength=p)
    L = sp.coo_matrix((np.r_[-np.ones(2 * both.sum()), diag.astype(np.float64)],
                       (np.r_[a[both], b[both], np.arange(p)], np.r_[b[both], a[both], np.arange(p)])),
                      shape=(p, p)).tocsc()
    R = sp.csr_matrix(rows)[:, free]
    A = L + weight * (R.T @ R)
    if curtain is not None:
        # the eye surface between the margins as a curtain: each of its vertices takes the fraction
        # x of its upper margin point's move, so its rows keep their order (a membrane alone, over
        # a strip the shape has already squashed, tilted hundreds of its triangles past edge-on)
        at, share, Ru = curtain
        C = sp.csr_matrix((np.ones(len(at)), (np.arange(len(at)), pos[at])), shape=(len(at), p)) \
            - sp.diags(share) @ sp.csr_matrix(Ru)[:, free]
        A = A + weight * (C.T @ C)
    return spsolve(A.tocsc(), weight * (R.T @ want))


def meet_lids(V, F, landmarks, targets, meet=0.95, eyeballs=(), samples=24, reach=1.0):
    """The blink shapes with their lid margins brought together (module docstring).

    Parameters
    ----------
    V : (n, 3) float, F : (m, 3) int
        The head, its own frame and units.
    landmarks : dict str -> (3,)
        The head's landmarks; an eye without its four lid landmarks is left as it is.
    targets : dict str -> (n, 3) float
        Displacements per ARKit name; ``eyeBlinkLeft`` / ``eyeBlinkRight`` are changed (copies).
    meet : float
        Fraction of the margins' remaining gap closed (1: they touch; a little less keeps a
        one-surface eye's squashed rows apart, so nothing folds).
    eyeballs : sequence of (centre (3,), radius)
        Separate eyeballs the lids must stay out of.
    samples : int
        Parameters between the canthi at which the margins are asked to meet.
    reach : float
        Rest gaps above the upper margin over which the lid's share of the move falls to 0.

    Returns
    -------
    targets : dict str -> (n, 3) float64
        The same dict's entries, the blinks replaced.
    report : dict str -> dict
        Per blink changed: ``open``, the median fraction of the rest gap its margins still leave
        open at the samples (0: touching); ``one_triangle``, the fraction of the samples where the
        upper and lower margin points lie on triangles that share a vertex (an opening one
        triangle high, which moving vertices cannot close: demosthenes' carved eyes, all 24).
    """
    V, F = np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64)
    out, report = dict(targets), {}
    sides = set(eye_sides(landmarks))
    t = np.linspace(0.0, 1.0, samples + 2)[1:-1]
    skin = None
    for name, side in BLINKS.items():
        if name not in targets or side not in sides:
            continue
        skin = skin_faces(V, F) if skin is None else skin
        idx, Ru, Rl = lid_region(V, F, landmarks, side, faces=skin)
        if not len(idx):  # no skin near the eye's landmarks: nothing to close
            continue
        D = np.array(targets[name], dtype=np.float64)
        # the vertices above the lower margin as the shape leaves them move; the lower lid stays
        U, L = Ru @ (V + D), Rl @ (V + D)
        up = (Ru - Rl) @ V
        # past the canthi the gap is nil: a floor (a millionth of the mean square gap) keeps x finite
        across, size2 = np.einsum("ij,ij->i", U - L, up), np.einsum("ij,ij->i", up, up)
        floor = 1e-6 * size2.mean() + 1e-300
        x = np.einsum("ij,ij->i", V[idx] + D[idx] - L, up) / np.maximum(across, floor)
        above = x > 0.0
        free = idx[above]
        if not len(free):
            continue
        _, (Su, Sl) = margin_curves(V, F, landmarks, side, t, skin)
        G = (Su - Sl).tocsr()
        gap0 = G @ V
        # each vertex takes its share of its own margin point's move: x across the eye surface
        # between the margins (a curtain, its rows in order), falling from 1 to 0 over ``reach``
        # rest gaps above the upper margin (the lid carries its margin, the brow stays)
        rise = (x - 1.0) * across / np.maximum(size2, floor)
        share = np.where(x <= 1.0, x, _smooth_fall(rise / reach))[above]
        c = _meeting_move(len(V), F, free, G, -meet * (gap0 + G @ D), curtain=(free, share, Ru[above]))
        D[free] = _off_eyeballs(V[free] + D[free] + c, V[free], eyeballs) - V[free]
        out[name] = D
        left = np.linalg.norm(gap0 + G @ D, axis=1) / np.maximum(np.linalg.norm(gap0, axis=1), 1e-300)
        # where the two margin points lie on triangles sharing a vertex, the opening is one
        # triangle high: no move of the vertices parts one margin from the other
        shared = np.asarray((abs(Su).astype(bool).multiply(abs(Sl).astype(bool))).sum(axis=1)).ravel() > 0
        report[name] = {"open": round(float(np.median(left)), 4), "one_triangle": round(float(shared.mean()), 4)}
    return out, report
