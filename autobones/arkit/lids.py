"""The lid margins of two heads, and where each shape puts a one-surface head's eye opening.

Goes beyond the seeds (issue #15). Deformation transfer carries a shape's *gradients*; closing
an eye is a *relative* move of two curves (the upper lid margin down to the lower one) that no
gradient field states. On a scan whose lids and visible eye are one surface, the gradients of
the lids and of the eye surface between them hold the margins apart (the menpo3d james scan's
left blink closed 33 % of its lid gap, vertically at the landmarks; ICT's own blink 82 %). This
module states the move on the head's own lids:

* each margin is the curve through the eye's landmarks (``endocanthion``,
  ``palpebrale_superius`` or ``palpebrale_inferius``, ``exocanthion``): the quadratic through the
  three points parametrised by ``t`` along the canthal axis (0 inner corner, 1 outer), laid on the
  surface by closest point (:func:`margin_curves`), the same way on the source and the target.
  Upper ``U(t)`` and lower ``L(t)`` face each other across the eye, the gap ``b(t) = U(t) - L(t)``;
* in each source shape the source's gap ``a(t)`` changes by ``delta(t)``: its part along ``a`` is
  a fraction ``kappa = -(delta . a) / |a|^2`` of the gap closed, the rest a slide of the lids past
  each other. The source's lids are thick: closed, its margins stay a lid's thickness apart (ICT's
  blink closes 0.82-0.89 of the gap mid-eye at its landmark curves), while a one-surface head's
  margins are lines that can meet; so ``kappa`` is divided, per ``t``, by the largest any shape
  reaches (when above 0.5: the source's "closed") and multiplied by ``meet`` (0.9: not quite 1, so
  the squashed eye surface keeps its rows in order and does not fold; 0.95 and 1 closed james a
  few points more and folded 1-6 more small triangles); at most 1;
* every target vertex in the eye's opening (between the margins and a quarter gap beyond; not
  near the corners, where the gap is too narrow for a place across it to mean much) is at a
  fraction ``s`` of the way from ``U(t)`` down to ``L(t)`` (clamped to [0, 1]); it is placed at
  ``d_low(t) + (1 - s) (-kappa b(t) + M slide)``: ``d_low`` where the transfer without these
  constraints puts the lower lid's skin a quarter gap below its margin, ``M`` the similarity
  (scale times rotation) of the two eyes' four landmarks. The eye surface closes like a curtain
  whose rows keep their order, the upper margin coming down to the lower one as far as the
  source's does and the lower lid going where its own gradients put it.

:func:`autobones.arkit.targets.deformation_targets` uses it only on heads without separate
eyeballs, only for the eyes whose blink the gradients alone close less than 0.8 of what the
source's closes (:meth:`LidClosure.needed`; measured ratios: james 0.64 left, 0.98 right;
LeePerrySmith 0.86 / 0.13; demosthenes 0.16 / 0.06; remeshed ICT skins without eyeballs
0.85-0.93, whose modelled lids the pins would damage: placed as a scan's, ICT identity011's
blink kept 32-38 % of its truth instead of 85 %), and only for the shapes that change some lid
gap by more than 5 % of the eye's widest (:meth:`LidClosure.moving_shapes`: the 14 eye shapes,
smiles, cheek squints and sneers); those are solved a second time with the opening's vertices
pinned (:class:`autobones.arkit.deformation_transfer.DeformationTransfer` ``pinned`` and
``pins``: soft positional terms, a second factorisation). Measured on james's left eye
(:func:`gap_closure`): vertically at the landmarks 33 % -> 79 %; between the landmarks' points
36 % -> 71 %; between their nearest vertices 37 % -> 65 % (ICT's own blink on its own head: 82,
74, 77 %); triangles folded at weight 1 over all shapes: 7 -> 6 on james, 131 -> 131 on
LeePerrySmith.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import AutobonesError
from ..geometry.closest import closest_points
from ..geometry.topology import mesh_parts
from ..geometry.rotations import similarity

# vertices where the gap is narrower than this fraction of the eye's widest are not placed (the
# corners): there s is ill-defined, and pinned they folded a few of LeePerrySmith's small triangles
CORNER = 0.5
EYE = ("endocanthion", "palpebrale_superius", "exocanthion", "palpebrale_inferius")


def eye_sides(landmarks):
    """Sides (``"l"``, ``"r"``) whose four eye landmarks are all in ``landmarks``."""
    return [s for s in ("l", "r") if all(f"{n}_{s}" in landmarks for n in EYE)]


def margin_points(landmarks, side, t):
    """Points of one eye's upper and lower lid margin curves at parameters ``t``: (2, len(t), 3) float64.

    The quadratic through ``endocanthion`` (t = 0), ``palpebrale_superius|inferius`` (at its own
    projection on the canthal axis) and ``exocanthion`` (t = 1); ``t`` (k,) is the projection
    on the canthal axis, so an upper and a lower point at the same ``t`` face each other across
    the eye. Row 0 the upper, 1 the lower margin; same frame and units as ``landmarks`` (name ->
    (3,)), off the surface between the landmarks (:func:`margin_curves` lays them on it).
    """
    E, X = (np.asarray(landmarks[f"{n}_{side}"], dtype=np.float64) for n in ("endocanthion", "exocanthion"))
    axis = X - E
    if axis @ axis <= 0:
        raise AutobonesError(f"lid margins: endocanthion_{side} and exocanthion_{side} coincide")
    t = np.asarray(t, dtype=np.float64)
    out = []
    for mid in ("palpebrale_superius", "palpebrale_inferius"):
        P = np.asarray(landmarks[f"{mid}_{side}"], dtype=np.float64)
        tp = float(np.clip((P - E) @ axis / (axis @ axis), 0.05, 0.95))
        l0 = (t - tp) * (t - 1.0) / tp  # Lagrange basis through t = 0, tp, 1
        l1 = t * (t - 1.0) / (tp * (tp - 1.0))
        l2 = t * (t - tp) / (1.0 - tp)
        out.append(l0[:, None] * E + l1[:, None] * P + l2[:, None] * X)
    return np.stack(out)


def canthal_parameter(P, landmarks, side):
    """``t`` of points ``P`` (k, 3): their projection on the canthal axis (0 inner, 1 outer corner), (k,)."""
    E, X = (np.asarray(landmarks[f"{n}_{side}"], dtype=np.float64) for n in ("endocanthion", "exocanthion"))
    axis = X - E
    return (np.asarray(P, dtype=np.float64) - E) @ axis / max(axis @ axis, 1e-300)


def margin_curves(V, F, landmarks, side, t, faces=None):
    """:func:`margin_points` laid on the mesh: (points (2, k, 3), rows (2, k, n) sparse interpolating vertices).

    ``faces``: the triangles to lay them on (None: all; pass the skin's, so a separate eyeball
    in front of a lid margin is not taken for it).
    """
    V, F = np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64)
    faces = np.arange(len(F)) if faces is None else np.asarray(faces)
    Q = margin_points(landmarks, side, t).reshape(-1, 3)
    C, face, bary, _ = closest_points(Q, V, F[faces])
    face = faces[face]
    k = len(Q)
    R = sp.csr_matrix((bary.ravel(), (np.repeat(np.arange(k), 3), F[face].ravel())), shape=(k, len(V)))
    h = k // 2
    return C.reshape(2, h, 3), (R[:h], R[h:])


def skin_faces(V, F):
    """Triangles (indices into ``F`` (m, 3)) of the largest connected part: the skin, without
    separate eyeballs, teeth or lashes. ``V`` (n, 3)."""
    part = mesh_parts(len(V), F)
    return np.flatnonzero(part[F[:, 0]] == np.argmax(np.bincount(part)))


class LidClosure:
    """Where each shape puts the vertices of a one-surface target's eye openings (module docstring).

    Parameters
    ----------
    samples : int
        Parameters ``t`` between the corners at which the source's gaps are measured.
    meet : float
        Fraction of the target's gap the source's most-closed shape closes (1: the margins meet;
        a little less keeps the squashed eye surface's rows in order, so nothing folds).
    beyond : float
        How far past the margins (in gaps) a vertex still counts as in the opening.
    below : float
        The lower lid's own motion is read this far below the lower margin (in gaps), on lid skin.
    ratio : float
        An eye whose lids the gradients alone close this fraction of what the source's close is
        left alone (:meth:`needed`).
    min_change : float
        Shapes that change no gap by more than this fraction of the eye's widest are left as
        the gradients give them.

    Attributes (after :meth:`fit`)
    ----------
    sides_ : list of str
        Eyes with all four landmarks on both heads.
    vertices_ : (p,) int64
        Target vertices in an eye's opening or on its margins.
    gradient_ratio_ : (sides,) float
        After :meth:`needed`: the fraction of the source's closing the gradients alone reach.
    """

    def __init__(self, samples=24, meet=0.9, beyond=0.25, below=0.25, min_change=0.05, ratio=0.8):
        self.ratio = ratio
        self.samples = samples
        self.meet = meet
        self.beyond = beyond
        self.below = below
        self.min_change = min_change

    def fit(self, V_src, F_src, lm_src, V_tgt, F_tgt, lm_tgt):
        """Find the margins on both heads (each on its largest connected part, the skin).

        ``V_src`` (n_s, 3) float, ``F_src`` (m_s, 3) int, ``lm_src`` (name -> (3,)) in the
        source's frame and units; ``V_tgt``, ``F_tgt``, ``lm_tgt`` in the target's.
        """
        V_src, V_tgt = np.asarray(V_src, dtype=np.float64), np.asarray(V_tgt, dtype=np.float64)
        F_src, F_tgt = np.asarray(F_src, dtype=np.int64), np.asarray(F_tgt, dtype=np.int64)
        self.sides_ = [s for s in eye_sides(lm_src) if s in eye_sides(lm_tgt)]
        self.t_ = np.linspace(0.0, 1.0, self.samples + 2)[1:-1]
        skin_s, skin_t = skin_faces(V_src, F_src), skin_faces(V_tgt, F_tgt)
        n_t = len(V_tgt)
        self._src, self._turn, self._tgt = [], [], []
        verts, low, tv, sv, gaps, side_of = [], [], [], [], [], []
        for i, side in enumerate(self.sides_):
            # the source's margins at the sample parameters: gap rows u - l
            C, (Ru, Rl) = margin_curves(V_src, F_src, lm_src, side, self.t_, skin_s)
            self._src.append(((Ru - Rl).tocsr(), C[0] - C[1]))
            s, R = similarity(np.array([lm_src[f"{n}_{side}"] for n in EYE], dtype=np.float64),
                              np.array([lm_tgt[f"{n}_{side}"] for n in EYE], dtype=np.float64))
            self._turn.append(s * R)
            # the lower lid's skin a little below its margin, at the sample parameters: where the
            # gradients put the lower lid (read on a smooth curve, so the opening's rows keep order)
            P, (Ru_t, Rl_t) = margin_curves(V_tgt, F_tgt, lm_tgt, side, self.t_, skin_t)
            self._tgt.append(((Ru_t - Rl_t).tocsr(), P[0] - P[1]))
            _, face, bary, _ = closest_points(P[1] - self.below * (P[0] - P[1]), V_tgt, F_tgt[skin_t])
            low.append(sp.csr_matrix((bary.ravel(), (np.repeat(np.arange(len(face)), 3), F_tgt[skin_t][face].ravel())),
                                     shape=(len(face), n_t)))
            # the target's vertices in the opening: between the canthi, near the segment U(t) L(t)
            t = canthal_parameter(V_tgt, lm_tgt, side)
            near = np.flatnonzero((t > 0.0) & (t < 1.0))
            near = near[np.isin(near, F_tgt[skin_t])]
            if not len(near):
                continue
            P, _ = margin_curves(V_tgt, F_tgt, lm_tgt, side, t[near], skin_t)
            U, L = P[0], P[1]
            b = U - L
            bb = np.maximum(np.einsum("ij,ij->i", b, b), 1e-300)
            s_v = np.einsum("ij,ij->i", U - V_tgt[near], b) / bb  # 0 at U, 1 at L
            off = np.linalg.norm(V_tgt[near] - (U - s_v[:, None] * b), axis=1)
            fissure = np.linalg.norm(np.asarray(lm_tgt[f"exocanthion_{side}"], dtype=np.float64)
                                     - np.asarray(lm_tgt[f"endocanthion_{side}"], dtype=np.float64))
            ok = (s_v > -self.beyond) & (s_v < 1.0 + self.beyond) & (off < 0.1 * fissure + 0.25 * np.sqrt(bb))
            # near the corners the gap is too narrow for a vertex's place across it to mean much
            ok &= np.sqrt(bb) > CORNER * np.sqrt(bb).max()
            idx = np.flatnonzero(ok)
            verts.append(near[idx])
            tv.append(t[near[idx]])
            sv.append(np.clip(s_v[idx], 0.0, 1.0))
            gaps.append(b[idx])
            side_of.append(np.full(len(idx), i))
        cat = (lambda a, empty: np.concatenate(a) if a else empty)
        self.vertices_ = cat(verts, np.zeros(0, dtype=np.int64))
        self._low = low
        self._t, self._s = cat(tv, np.zeros(0)), cat(sv, np.zeros(0))
        self._b, self._side = cat(gaps, np.zeros((0, 3))), cat(side_of, np.zeros(0, dtype=np.int64))
        return self

    def closing(self, deltas):
        """The source's closing fraction ``kappa`` (k, sides, samples) and slide (k, sides, samples, 3).

        ``deltas`` (k, n_s, 3) source displacements; ``kappa`` 1: the gap at ``t_`` closed.
        """
        deltas = np.asarray(deltas, dtype=np.float64)
        kap, slide = [], []
        for Rg, a in self._src:
            d = np.stack([Rg @ D for D in deltas])  # (k, samples, 3)
            kp = -np.einsum("kpc,pc->kp", d, a) / np.maximum(np.einsum("pc,pc->p", a, a), 1e-300)
            kap.append(kp)
            slide.append(d + kp[:, :, None] * a[None])
        k = len(deltas)
        if not kap:
            return np.zeros((k, 0, len(self.t_))), np.zeros((k, 0, len(self.t_), 3))
        return np.stack(kap, axis=1), np.stack(slide, axis=1)

    def needed(self, deltas, X):
        """Eyes whose lids the gradients alone do not close as the source's do: (sides,) bool.

        ``X`` (k, n_t, 3) the shapes ``deltas`` (k, n_s, 3) transferred without the constraints.
        For the shape that closes each eye most in the source, the fraction of the target's gap
        ``X`` closes is compared with the source's own, over the middle half of the eye: a head
        whose lids are modelled (ICT's skin, a sculpt) closes ``ratio`` of it or more and is left
        as the gradients give it; a one-surface scan's lids stay apart and are closed here.
        """
        kap, _ = self.closing(deltas)
        out = np.zeros(len(self.sides_), dtype=bool)
        self.gradient_ratio_ = np.full(len(self.sides_), np.nan)
        mid = slice(len(self.t_) // 4, len(self.t_) - len(self.t_) // 4)
        for i, (Rg, b) in enumerate(self._tgt):
            j = int(np.argmax(kap[:, i, mid].mean(axis=1)))
            if kap[j, i, mid].mean() <= 0.5:
                continue  # no shape of the set closes this eye
            d = Rg @ np.asarray(X[j], dtype=np.float64)
            k0 = -np.einsum("pc,pc->p", d, b) / np.maximum(np.einsum("pc,pc->p", b, b), 1e-300)
            self.gradient_ratio_[i] = np.median(k0[mid]) / np.median(kap[j, i, mid])
            out[i] = self.gradient_ratio_[i] < self.ratio
        return out

    def moving_shapes(self, deltas):
        """Shapes that change some gap by more than ``min_change`` of the eye's widest: (k,) bool."""
        deltas = np.asarray(deltas, dtype=np.float64)
        out = np.zeros(len(deltas), dtype=bool)
        for Rg, a in self._src:
            d = np.stack([Rg @ D for D in deltas])  # (k, samples, 3)
            widest = max(np.linalg.norm(a, axis=1).max(), 1e-300)
            out |= np.linalg.norm(d, axis=2).max(axis=1) > self.min_change * widest
        return out

    def targets(self, deltas, X, sides=None):
        """Displacements of :attr:`vertices_` per shape: (k, p, 3), target units.

        ``deltas`` (k, n_s, 3) the source shapes, ``X`` (k, n_t, 3) the same shapes transferred
        without these constraints: the lower lid goes where ``X`` puts its skin below the margin
        (``d_low(t_v)``), and vertex ``v`` to ``d_low + (1 - s_v) (-kappa b + M slide)``, ``M`` the
        eye's similarity (scale times rotation), ``kappa`` and the slide interpolated at ``t_v``.
        ``sides`` (sides,) bool: the eyes to close (:meth:`needed`); the others' vertices are
        asked to stay where ``X`` puts them. None: all.
        """
        kap, slide = self.closing(deltas)
        k = len(kap)
        if self.meet and kap.shape[1]:
            top = kap.max(axis=0)  # (sides, samples): the source's closed state per t
            kap = kap * np.where(top > 0.5, self.meet / np.maximum(top, 1e-300), 1.0)[None]
        kap = np.minimum(kap, 1.0)
        out = np.zeros((k, len(self._t), 3))
        for i in range(len(self.sides_)):
            m = self._side == i
            if not m.any():
                continue
            if sides is not None and not sides[i]:
                out[:, m] = np.asarray(X, dtype=np.float64)[:, self.vertices_[m]]
                continue
            tv = self._t[m]
            kv = np.stack([np.interp(tv, self.t_, kap[j, i]) for j in range(k)])  # (k, pm)
            sl = np.stack([[np.interp(tv, self.t_, slide[j, i, :, c]) for c in range(3)] for j in range(k)])
            sl = np.einsum("ij,kjp->kpi", self._turn[i], sl)
            low = np.stack([self._low[i] @ np.asarray(x, dtype=np.float64) for x in X])  # (k, samples, 3)
            out[:, m] = np.stack([[np.interp(tv, self.t_, low[j, :, c]) for c in range(3)] for j in range(k)]
                                 ).transpose(0, 2, 1)
            out[:, m] += (1.0 - self._s[m])[None, :, None] * (-kv[:, :, None] * self._b[m][None] + sl)
        return out


def gap_closure(V, F, D, landmarks, side, up=None):
    """How much of one eye's lid gap a displacement field closes, three ways: dict of floats (1: closed).

    ``V`` (n, 3), ``F`` (m, 3), ``D`` (n, 3) the displacements (same units), ``landmarks`` with
    ``palpebrale_superius_<side>`` and ``palpebrale_inferius_<side>``, ``up`` (3,) the head's up
    direction (None: ``vertical`` not computed). On the largest connected part (the skin):

    * ``vertices``: ``1 - |gap after| / |gap before|`` between the skin vertices nearest the two
      landmarks (on a coarse mesh these may sit an edge apart sideways, which no blink closes);
    * ``points``: the same between the landmarks' own surface points, ``D`` interpolated there;
    * ``vertical``: the landmark points' gap along ``up`` only;
    * ``margins``: between the upper margin at ``palpebrale_superius`` and the lower margin
      across from it (:func:`margin_curves`, the same ``t``): how far the upper margin came to the
      lower one. ``points`` also counts the two landmarks' offset along the eye (they need not
      face each other), which no closing removes.
    """
    V, D = np.asarray(V, dtype=np.float64), np.asarray(D, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    faces = skin_faces(V, F)
    skin = np.unique(F[faces])
    Q = np.array([landmarks[f"palpebrale_superius_{side}"], landmarks[f"palpebrale_inferius_{side}"]],
                 dtype=np.float64)
    near = skin[np.argmin(np.linalg.norm(V[skin][None] - Q[:, None], axis=2), axis=1)]
    g0, g1 = V[near[0]] - V[near[1]], V[near[0]] + D[near[0]] - V[near[1]] - D[near[1]]
    out = {"vertices": 1.0 - np.linalg.norm(g1) / max(np.linalg.norm(g0), 1e-300)}
    C, face, bary, _ = closest_points(Q, V, F[faces])
    d = np.einsum("kcd,kc->kd", D[F[faces][face]], bary)
    g0, g1 = C[0] - C[1], C[0] + d[0] - C[1] - d[1]
    out["points"] = 1.0 - np.linalg.norm(g1) / max(np.linalg.norm(g0), 1e-300)
    t = canthal_parameter(Q[:1], landmarks, side)
    M, (Ru, Rl) = margin_curves(V, F, landmarks, side, t, faces)
    g0, g1 = M[0, 0] - M[1, 0], M[0, 0] - M[1, 0] + ((Ru - Rl) @ D)[0]
    out["margins"] = 1.0 - np.linalg.norm(g1) / max(np.linalg.norm(g0), 1e-300)
    if up is not None:
        up = np.asarray(up, dtype=np.float64)
        out["vertical"] = 1.0 - float(g1 @ up) / (float(g0 @ up) or 1e-300)
    return {k: float(v) for k, v in out.items()}
