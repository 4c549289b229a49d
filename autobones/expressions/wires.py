"""Wire deformers (Bibliowicz 2005, §4.2, "Wires"; Singh and Fiume 1998, simplified), and the muscle wires.

A wire deformer is a base wire B and a deforming wire D of equal parameter range,
a dropoff distance d0 and the dropoff function f(x) = (1 - x^2)^2 on [0, 1]. A
skin point P within d0 of the base wire, whose closest base-wire parameter is u,
moves by

    f(|P - B(u)| / d0) * (D(u) - B(u)).

The wires are linear curves through their control vertices (Bibliowicz found linear
wires as good as cubic NURBS and cheaper), so D(u) - B(u) is the linear
interpolation of the control-vertex displacements at u, and the whole deformation
is a fixed sparse matrix applied to those displacements: the closest parameters
and dropoff weights depend on the base wire only and are computed once.

:func:`muscle_basis` builds the expression model's muscle stage from them: one wire per muscle,
point-constrained to locators riding the muscle joints.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..errors import AutobonesError
from ..geometry.laplacian import factor_spd
from .sphincters import is_sheet, is_sphincter, sphincter_field


def dropoff(x):
    """The dropoff f(x) = (1 - x^2)^2 for x in [0, 1], 0 beyond; ``x`` any shape."""
    x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    return (1.0 - x * x) ** 2


def closest_on_polyline(P, C):
    """Closest points of a linear curve to points.

    Parameters
    ----------
    P : (n, 3) float
        Query points.
    C : (k, 3) float
        Control vertices of the polyline (k >= 2), same frame and units.

    Returns
    -------
    dist : (n,) float
        Distance from each point to the polyline.
    seg : (n,) int
        Index of the closest segment (between C[seg] and C[seg + 1]).
    t : (n,) float
        Position on that segment in [0, 1].
    """
    P = np.asarray(P, dtype=np.float64)
    A, B = C[:-1], C[1:]
    AB = B - A
    ab2 = np.maximum((AB * AB).sum(axis=1), 1e-300)
    # (n, s) projections; s is small (a handful of segments per wire)
    t = np.clip(np.einsum("nsj,sj->ns", P[:, None, :] - A[None], AB) / ab2, 0.0, 1.0)
    Q = A[None] + t[..., None] * AB[None]
    d2 = ((P[:, None, :] - Q) ** 2).sum(axis=2)
    seg = np.argmin(d2, axis=1)
    rows = np.arange(len(P))
    return np.sqrt(d2[rows, seg]), seg, t[rows, seg]


def wire_weights(V, base, d0, gate=None, tree=None):
    """The sparse matrix of one wire deformer.

    Parameters
    ----------
    V : (n, 3) float
        Skin points (any frame and unit).
    base : (k, 3) float
        Base wire control vertices, same frame and units.
    d0 : float
        Dropoff distance, same units.
    gate : (n,) float, optional
        Per-point factor in [0, 1] multiplied into the dropoff (0 cuts a point
        out of this wire, e.g. across the mouth line); default 1.
    tree : scipy.spatial.cKDTree of V, optional
        Reused when several wires deform the same points.

    Returns
    -------
    scipy.sparse.csr_matrix (n, k)
        ``W @ (D - B)`` is the (n, 3) displacement of the skin for a deforming
        wire D with control vertices of the same count.
    """
    base = np.asarray(base, dtype=np.float64)
    if base.ndim != 2 or base.shape[1] != 3 or len(base) < 2:
        raise AutobonesError(f"wire: the base wire needs (k >= 2, 3) control vertices, got {base.shape}")
    if not d0 > 0:
        raise AutobonesError(f"wire: the dropoff distance must be positive, got {d0}")
    n, k = len(V), len(base)
    tree = tree or cKDTree(V)
    # candidates: within d0 of some point of the wire (balls around sample points of each segment)
    seg_len = np.linalg.norm(np.diff(base, axis=0), axis=1)
    samples = [base[:1]]
    for a, b, L in zip(base[:-1], base[1:], seg_len):
        m = max(1, int(np.ceil(L / d0)))
        samples.append(a + np.linspace(0.0, 1.0, m + 1)[1:, None] * (b - a))
    S = np.concatenate(samples)
    step = max(float(seg_len.max() / max(1, np.ceil(seg_len.max() / d0))), 0.0)
    near = tree.query_ball_point(S, d0 + 0.5 * step + 1e-12)
    idx = np.unique(np.concatenate([np.asarray(i, dtype=np.int64) for i in near])) if len(near) else np.zeros(0, int)
    if len(idx) == 0:
        return sp.csr_matrix((n, k))
    dist, seg, t = closest_on_polyline(V[idx], base)
    f = dropoff(dist / d0)
    if gate is not None:
        f = f * np.asarray(gate, dtype=np.float64)[idx]
    keep = f > 0
    idx, seg, t, f = idx[keep], seg[keep], t[keep], f[keep]
    rows = np.concatenate([idx, idx])
    cols = np.concatenate([seg, seg + 1])
    vals = np.concatenate([f * (1.0 - t), f * t])
    return sp.csr_matrix((vals, (rows, cols)), shape=(n, k))


class WireDeformer:
    """One wire deformer, scikit-learn style: configure, ``fit`` on the base wire, ``deform``.

    Parameters
    ----------
    dropoff_distance : float
        d0, in the units of the points.

    Attributes
    ----------
    weights_ : scipy.sparse.csr_matrix (n, k)
        Dropoff weight of every skin point on every control vertex.
    base_ : (k, 3) float
        The base wire.

    Example
    -------
    >>> w = WireDeformer(0.5).fit(V, base)
    >>> V2 = V + w.displacement(base + [0.0, 0.1, 0.0])
    """

    def __init__(self, dropoff_distance):
        self.dropoff_distance = dropoff_distance

    def fit(self, V, base, gate=None):
        self.base_ = np.asarray(base, dtype=np.float64)
        self.weights_ = wire_weights(np.asarray(V, dtype=np.float64), self.base_, float(self.dropoff_distance), gate)
        return self

    def displacement(self, deformed):
        """(n, 3) skin displacement for the deforming wire ``deformed`` (k, 3)."""
        deformed = np.asarray(deformed, dtype=np.float64)
        if deformed.shape != self.base_.shape:
            raise AutobonesError(f"wire: the deforming wire has shape {deformed.shape}, the base wire {self.base_.shape}")
        return self.weights_ @ (deformed - self.base_)


def locator_weights(t, own, influence, sides, rest_weight, cross_talk, galea_anchor=None):
    """Point-constraint weights of one wire's control vertices on the muscles' locators.

    Parameters
    ----------
    t : (c,) float
        Control vertex positions as fractions of the way origin -> insertion of the wire's muscle.
    own : int
        The wire's muscle.
    influence : (c, k) float
        Every muscle's influence field at the control vertices.
    sides : list of str
        ``l``, ``r`` or ``m`` per muscle.
    rest_weight, cross_talk : float
        Weight of the unparented rest locator; factor on the neighbours' influence.
    galea_anchor : float, optional
        For a muscle on the galea aponeurotica: its own locator weighs fully before this fraction.

    Returns
    -------
    (c, k) float
        The weights, normalised together with the rest locator (rows sum to below 1). The own
        locator follows the force profile of Lee, Terzopoulos & Waters 1995 along the muscle,
        sin(pi/2 t^0.48), fading over a quarter length past the insertion.
    """
    prof = np.where(t <= 1.0, np.sin(0.5 * np.pi * np.clip(t, 0, 1) ** 0.48),
                    np.cos(0.5 * np.pi * np.clip((t - 1.0) / 0.25, 0.0, 1.0)))
    if galea_anchor is not None:
        # the aponeurosis above the muscle is pulled along as one sheet: its own locator
        # weighs fully from the wire's start over the galea down to the anchor
        prof = np.where(t < float(galea_anchor), 1.0, prof)
    cw = cross_talk * influence
    cw[:, own] = prof
    for j2 in range(cw.shape[1]):                          # neighbours pull from their own side only
        if j2 != own and sides[j2] != sides[own] and "m" not in (sides[j2], sides[own]):
            cw[:, j2] = 0.0
    return cw / (rest_weight + cw.sum(axis=1, keepdims=True))


def muscle_wires(V, skin, joints, influence, types, mouth, fu, params):
    """The wires of every muscle and the skin displacement each muscle's contraction makes.

    Bibliowicz 2005, §4.2: every muscle joint pulls one wire along the skin over the muscle; each
    control vertex is point-constrained to locators riding the joints (:func:`locator_weights`),
    so the skin displacement is a fixed linear map of the contractions. A wire on one lip is
    cut off the other lip within the mouth zone.

    Parameters
    ----------
    V : (n, 3) float
        Vertices, canonical frame (+Y up, +Z front), head sizes.
    skin : (n,) bool
        Vertices the wires may move.
    joints : MuscleJoints
        The k muscles, canonical frame, head sizes.
    influence : (k, n) float
        Each muscle's influence field (0 where the rig has none).
    types : dict
        Muscle type -> :func:`definitions.muscle_types` (``wire``, ``dropoff`` in muscle widths...).
    mouth : MouthLine
        The mouth line and zone.
    fu : float
        Face unit in head sizes.
    params : dict
        Resolved model parameters: ``cvs``, ``rest_weight``, ``cross_talk``, ``lips.cut_width`` (fu).

    Returns
    -------
    fields : (k, n, 3) float
        Skin displacement per unit contraction of each muscle (head sizes), unsmoothed.
    coverage : (n,) float
        Sum of all wires' dropoff weights per vertex.
    wires : list of dict
        Per wire: ``muscle``, ``base`` (cvs, 3), ``vertices`` (cvs,) int, ``dropoff`` (head
        sizes), ``side`` (``upper``, ``lower`` or ``both``: the lip it pulls).
    """
    n, k = len(V), len(joints)
    cvs = int(params["cvs"])
    cut_width = float(params["lips"]["cut_width"]) * fu
    skin_idx = np.flatnonzero(skin)
    skin_tree = cKDTree(V[skin_idx])
    all_tree = cKDTree(V)
    st, hw = mouth.stomion, mouth.half_width
    G = np.zeros((k, n, 3))
    total = np.zeros(n)
    wires = []
    for i, nm in enumerate(joints.names):
        spec = types.get(joints.types[i])
        if spec is None or is_sphincter(spec):
            continue
        o, ip = joints.origins[i], joints.insertions[i]
        o_skin = V[skin_idx[skin_tree.query(np.atleast_2d(o))[1]][0]]
        t = np.linspace(float(spec["wire"][0]), float(spec["wire"][1]), cvs)
        cv_idx = skin_idx[skin_tree.query(np.atleast_2d(o_skin[None] + t[:, None] * (ip - o_skin)[None]))[1]]
        Q = V[cv_idx]
        # which lip the wire belongs to: its insertion inside the mouth zone's width
        ins_s = ip[1] - mouth.height(ip[0])
        if abs(ip[0] - st[0]) < 0.9 * hw and abs(ins_s) > cut_width:
            gate = 1.0 - mouth.zone * ((1.0 - mouth.upper) if ins_s > 0 else mouth.upper)
            side = "upper" if ins_s > 0 else "lower"
        else:
            gate, side = None, "both"
        d0 = float(spec["dropoff"]) * joints.widths[i]
        Wm = wire_weights(V, Q, d0, gate=skin * (1.0 if gate is None else gate), tree=all_tree)
        galea = spec["galea"]
        cw = locator_weights(t, i, influence[:, cv_idx].T, joints.sides, float(params["rest_weight"]),
                             float(params["cross_talk"]), None if galea is None else galea["anchor"])
        for j2 in np.flatnonzero(cw.max(axis=0) > 0):
            spec2 = types.get(joints.types[j2])
            sh = 0.0 if spec2 is None else float(spec2["shortening"])
            if sh == 0.0:
                continue
            # frontalis, on the galea: the scalp slides down toward a raised brow
            anchor = None if spec2["galea"] is None else spec2["galea"].get("anchor")
            d = joints.locator_displacements(Q, j2, anchor=anchor) * (sh * cw[:, j2:j2 + 1])
            G[j2] += Wm @ d
        total += np.asarray(Wm.sum(axis=1)).ravel()
        wires.append({"muscle": nm, "base": Q, "vertices": cv_idx, "dropoff": d0, "side": side})
    return G, total, wires


def smooth_muscle_fields(G, one_lip, surface, mouth, t):
    """The muscle fields after heat diffusion over the skin (an implicit step of length ``t``).

    A wire's dropoff varies faster than the tiny triangles of the mouth and eye corners can
    follow without folding, so the fields are diffused with the intrinsic Laplacian; the fields
    of muscles whose wire pulls one lip (``one_lip`` (k,) bool) diffuse with the edges across
    the mouth line weakened in the mouth zone, the others (the corner muscles) without.

    ``G`` (k, n, 3) float, canonical head sizes; ``surface`` the SkinSurface; ``mouth`` the
    MouthLine; ``t`` the diffusion time (head sizes squared, > 0). Returns a new (k, n, 3) array.
    """
    index, first = surface.index, surface.first
    Lp, M = surface.laplacian, surface.mass
    nw, n = len(first), G.shape[1]
    C = Lp.tocoo()
    off = C.row != C.col
    # an edge across the mouth line conducts less the more it lies in the mouth zone
    zw, uw, sw = mouth.zone[first], mouth.upper[first], surface.skin[first]
    conduct = (1.0 - np.minimum(zw[C.row], zw[C.col]) * np.abs(uw[C.row] - uw[C.col])) * (sw[C.row] & sw[C.col])
    keep = off & (conduct > 0)
    Loff = sp.csr_matrix((C.data[keep] * conduct[keep], (C.row[keep], C.col[keep])), shape=(nw, nw))
    Lc = Loff - sp.diags(np.asarray(Loff.sum(axis=1)).ravel())
    G = G.copy()
    for sel, lap_ in ((one_lip, Lc), (~one_lip, Lp)):
        if not sel.any():
            continue
        solve = factor_spd(M + t * lap_)
        flat = G[sel][:, first].transpose(1, 0, 2).reshape(nw, -1)
        flat = solve(np.asarray(M @ flat))[index]
        G[sel] = flat.reshape(n, int(sel.sum()), 3).transpose(1, 0, 2)
    return G


def muscle_basis(V, skin, joints, influence, types, mouth, fu, params, surface):
    """The muscle stage of the model: wires (:func:`muscle_wires`) and sphincters
    (:func:`sphincters.sphincter_field`), smoothed
    (:func:`smooth_muscle_fields`, over ``params["smoothing"]`` fu) and, with
    ``params["normalise_overlaps"]``, damped where wires overlap (dropoffs summing to at most 1).

    Arguments as for :func:`muscle_wires`, plus ``surface`` (SkinSurface). Returns the fields
    (k, n, 3) float (canonical, head sizes per unit contraction) and the wires.
    """
    # sphincters and sheets have no wire and no line to pull a neighbour's locators along: their own field
    sph = np.array([is_sphincter(types.get(t)) for t in joints.types], dtype=bool)
    G, coverage, wires = muscle_wires(V, skin, joints, np.where(sph[:, None], 0.0, influence), types, mouth, fu,
                                      params)
    for i in np.flatnonzero(sph):
        G[i] = sphincter_field(V, joints.origins[i], joints.insertions[i], influence[i] * skin,
                               types[joints.types[i]])
    t_s = (float(params["smoothing"]) * fu) ** 2
    if t_s > 0:
        # muscles whose wire pulls one lip are smoothed with the mouth line cut, the corner
        # muscles (wires on both lips) without it
        sides = {w["muscle"]: w["side"] for w in wires}
        # a sheet (mentalis) lifts the lower lip against the upper one: cut at the mouth line too
        one_lip = np.array([sides.get(nm, "both") != "both" or is_sheet(types.get(t))
                            for nm, t in zip(joints.names, joints.types)])
        G = smooth_muscle_fields(G, one_lip, surface, mouth, t_s)
    if bool(params["normalise_overlaps"]):
        G *= (1.0 / np.maximum(coverage, 1.0))[None, :, None]
    return G, wires
