"""Eyelids: four lid joints turning about the eye pivots, and the small parts riding the lids.

The lid joints (upper/lower, left/right, order :data:`LIDS`) rotate about the canonical +X axis
through the eye pivots (Bibliowicz 2005, §4.2, eyelid joints). Near the margins they hinge instead
on the line through the eye's two corners (:func:`lid_hinges`, issue #16): the tarsal plate is
held at the canthi by the canthal tendons, so the margin and the lash row on it turn as one piece
about the corners (as ICT-FaceKit's upper lash rows do, 90 % rigidly about an axis through the
outer corner), while the lid skin above rolls over the eyeball about its pivot. The lower lids,
whose tarsal plates are a third as tall, keep the pivot's turn unless ``hinge_lower``. A lid that opens
wider (a negative amount: the levator retracting the tarsal plate over the globe) turns about
the pivot only. Their weights are built from the
palpebral landmarks: an ellipse about the fissure, the fissure opening as 1 - u^2 between the
fixed medial eye corner and the looser lateral one. Separate small parts touching the lids
(eyelashes, eye-occlusion or tear-line shells) follow the skin where they touch it.

All inputs and outputs in the canonical frame (+Y up, +Z front), head sizes; ``fu`` is the face
unit (the exocanthion distance) in head sizes; the definitions' lengths are in fu.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..geometry.smooth import ramp

LIDS = ("upper_l", "upper_r", "lower_l", "lower_r")


def fissure_gaps(V, F, skin, landmarks):
    """(2,) float: distance from each fissure's midpoint (between the palpebrale landmarks; l, r)
    to the skin surface. Open lids leave the midpoint in a hole of the skin, far from it.

    ``V`` (n, 3), ``F`` (m, 3), ``skin`` (n,) bool, ``landmarks`` name -> (3,) canonical points
    (missing palpebrale points: the mean vertex stands in).
    """
    import igl

    skinF = F[skin[F].all(axis=1)]
    mids = []
    for s in "lr":
        nm_ = [f"palpebrale_superius_{s}", f"palpebrale_inferius_{s}"]
        mids.append(0.5 * (landmarks[nm_[0]] + landmarks[nm_[1]]) if all(x in landmarks for x in nm_)
                    else V.mean(axis=0))
    if not len(skinF):
        return np.zeros(2)
    return np.sqrt(igl.point_mesh_squared_distance(np.array(mids), np.ascontiguousarray(V),
                                                   np.ascontiguousarray(skinF))[0])


def eye_corners(landmarks, centre, side, fu):
    """(exocanthion, endocanthion, palpebrale superius, palpebrale inferius) of one eye, each (3,).

    From the landmarks ``{name}_{side}`` when all four exist, else placed about the eye pivot
    ``centre`` (3,) at typical offsets in fu.
    """
    need = [f"{b}_{side}" for b in ("exocanthion", "endocanthion", "palpebrale_superius", "palpebrale_inferius")]
    if all(nm_ in landmarks for nm_ in need):
        return tuple(landmarks[nm_] for nm_ in need)
    c = centre
    sign = 1.0 if side == "l" else -1.0
    ex, en = c + [sign * 0.15 * fu, 0, 0.08 * fu], c + [-sign * 0.15 * fu, 0, 0.08 * fu]
    ps, pi = c + [0, 0.05 * fu, 0.12 * fu], c + [0, -0.01 * fu, 0.12 * fu]
    return ex, en, ps, pi


def fissure_height(V, corners, fu, through=None):
    """Signed height (n,) of each vertex above the fissure's line (canonical +Y, head sizes) and
    the fissure height (float): the line runs endocanthion -> ``through`` (3,) (default the
    palpebrale points' midpoint; a palpebrale point gives that margin's line) -> exocanthion,
    piecewise linear in X. ``V`` (n, 3); ``corners`` :func:`eye_corners`."""
    ex, en, ps, pi = corners
    mid = 0.5 * (ps + pi) if through is None else through
    gap = max(float(np.linalg.norm(ps - pi)), 1e-3 * fu)
    xo = np.array([en[0], mid[0], ex[0]])
    oo = np.argsort(xo)
    return V[:, 1] - np.interp(V[:, 0], xo[oo], np.array([en[1], mid[1], ex[1]])[oo]), gap


def closing_angle(ps, pi, point, axis):
    """Degrees of the right-handed turn about the line through ``point`` (3,) along the unit
    ``axis`` (3,) that brings the upper margin ``ps`` (3,) onto the half-plane of the lower
    margin ``pi`` (3,)."""
    a, b = ps - point, pi - point
    a = a - (a @ axis) * axis
    b = b - (b @ axis) * axis
    return float(np.degrees(np.arctan2(np.cross(a, b) @ axis, a @ b)))


def lid_hinges(V, skin, landmarks, eyes, fu, lid, surface):
    """Where the lids hinge on the line through the eye corners instead of the eye pivot's axis.

    Each eye with both corner landmarks (``endocanthion_{s}``, ``exocanthion_{s}``) hinges on the
    line through them, the endocanthion raised by ``lid["hinge_medial_height"]`` of its height
    below the fissure's middle (the palpebrale midpoint; 0 keeps the corner itself); the line is
    oriented toward the subject's left (+X), so a positive turn closes an upper lid as a turn
    about +X does. The hinge's share of a skin vertex's turn is 1 between the margins' lines
    (each through the corners and its palpebrale point), fading to 0 at ``lid["hinge_band"]``
    fissure heights above the upper one or below the lower one (the tarsal plates), diffused as
    the lid weights are and rescaled to its peak before the diffusion; the rest of the turn is about the eye pivot's +X axis. ``lid["hinge"]``
    other than "corners", or a missing corner landmark: no hinge for that eye (share 0, the
    turn of Bibliowicz 2005).

    Parameters
    ----------
    V : (n, 3) float
        Vertices, canonical frame (+Y up, +Z front), head sizes.
    skin : (n,) bool
        Skin vertices.
    landmarks : dict
        Name -> (3,) canonical point.
    eyes : dict
        Side (``l``/``r``) -> eye pivot (3,).
    fu : float
        Face unit (head sizes).
    lid : dict
        Resolved ``model.eyelids`` (``hinge``, ``hinge_medial_height``, ``hinge_band``, ``smoothing``).
    surface : SkinSurface
        For the diffusion (:mod:`surface`).

    Returns
    -------
    points, axes : (2, 3) float
        A point (the exocanthion) and the unit direction of each eye's hinge (l, r; +X through
        the eye pivot, or the origin, where there is none).
    close_deg : (2,) float
        The turn about the hinge that brings the upper margin (palpebrale superius) to the lower
        one, degrees (0 where there is no hinge).
    share : (n,) float
        The hinge's share in [0, 1] of each vertex's lid turn (skin only).
    joints : (4,) bool
        Which lid joints (:data:`LIDS` order) hinge: the upper ones, and the lower ones with
        ``lid["hinge_lower"]``.
    """
    n = len(V)
    points = np.zeros((2, 3))
    axes = np.tile([1.0, 0.0, 0.0], (2, 1))
    close = np.zeros(2)
    share = np.zeros((2, n))
    for e, s in enumerate("lr"):
        c = eyes.get(s)
        if c is None:
            continue
        points[e] = c
        hinge = _corner_hinge(V, skin, landmarks, c, s, fu, lid)
        if hinge is not None:
            points[e], axes[e], close[e], share[e] = hinge
    share = _spread_share(share.max(axis=0), skin, fu, lid, surface)
    lower = bool(lid.get("hinge_lower", False))
    return points, axes, close, share, np.array([True, True, lower, lower])


def _corner_hinge(V, skin, landmarks, c, s, fu, lid):
    """One eye's hinge on the line through its corners (see :func:`lid_hinges`), or None when it
    has none (``lid["hinge"]`` not "corners", a corner landmark missing, the corners together).

    ``V`` (n, 3), ``skin`` (n,) bool, ``landmarks`` name -> (3,), ``c`` (3,) the eye pivot, all
    canonical, head sizes; ``s`` the side (``l``/``r``). Returns the hinge's point (3,) (the
    exocanthion), its unit axis (3,) toward +X, the closing turn (degrees) and the hinge's
    undiffused share (n,) (0 everywhere when ``lid["hinge_band"]`` is 0).
    """
    need = [f"{b}_{s}" for b in ("exocanthion", "endocanthion", "palpebrale_superius", "palpebrale_inferius")]
    if str(lid.get("hinge", "pivot")) != "corners" or not all(k in landmarks for k in need[:2]):
        return None
    corners = eye_corners(landmarks, c, s, fu)   # the palpebrale points placed when missing
    ex, medial = np.asarray(corners[0], dtype=np.float64), np.array(corners[1], dtype=np.float64)
    if all(k in landmarks for k in need[2:]):
        medial[1] += float(lid.get("hinge_medial_height", 0.0)) * (0.5 * (corners[2][1] + corners[3][1]) - medial[1])
    u = ex - medial
    norm = float(np.linalg.norm(u))
    if not np.isfinite(norm) or norm <= 1e-6 * fu:
        return None
    u = u / norm if u[0] >= 0 else -u / norm
    share = np.zeros(len(V))
    band = float(lid.get("hinge_band", 0.0))
    if band > 0:
        s_up, gap = fissure_height(V, corners, fu, corners[2])
        s_lo, _ = fissure_height(V, corners, fu, corners[3])
        outside = np.maximum(s_up, 0.0) + np.maximum(-s_lo, 0.0)     # 0 between the margins
        # the eye's own skin: as far from its centre as the lid weights reach, in front of the pivot
        half = 0.5 * abs(ex[0] - corners[1][0])
        near = ((np.abs(V[:, 0] - 0.5 * (ex[0] + corners[1][0])) < float(lid["width_margin"]) * half)
                & (V[:, 2] > c[2]))
        share = ramp(outside, band * gap, 0.0) * near * skin
    return ex, u, closing_angle(corners[2], corners[3], ex, u), share


def _spread_share(share, skin, fu, lid, surface):
    """The hinge's share (n,) in [0, 1] diffused over the skin as the lid weights are (over
    ``lid["smoothing"]`` fu; ``surface`` a :class:`SkinSurface`), then rescaled to its peak."""
    t_l = (float(lid["smoothing"]) * fu) ** 2
    if t_l > 0 and share.any():
        peak = share.max()
        share = surface.diffuse(share[:, None], t_l)[:, 0]
        # back to a full share on the margins (the diffusion lowers the peak)
        share = np.clip(share * (peak / max(share.max(), 1e-12)), 0.0, 1.0) * skin
        share[share < 1e-3] = 0.0            # the diffusion reaches the whole skin: keep to the lids
    return share


def eye_lid_weights(V, skin, centre, corners, gap_to_skin, fu, lid):
    """Upper and lower lid joint weights of one eye, and its closing angle.

    Parameters
    ----------
    V : (n, 3) float
        Vertices.
    skin : (n,) bool
        Skin vertices.
    centre : (3,) float
        The eye pivot.
    corners : tuple of four (3,) float
        :func:`eye_corners`.
    gap_to_skin : float
        The fissure midpoint's distance to the skin (:func:`fissure_gaps`): open lids when it is
        over a quarter of the fissure height, else one surface spans the fissure.
    fu : float
        Face unit.
    lid : dict
        Resolved ``model.eyelids``: ``width_margin``, ``upper_height``, ``lower_height``, ``depth``,
        ``lateral_reach``, ``corner_exponent``, ``corner_release``.

    Returns
    -------
    upper, lower : (n,) float
        Weights in [0, 1] (unsmoothed).
    close_deg : float
        The angle (degrees) about +X that brings the upper margin to the lower one.
    """
    c = centre
    ex, en, ps, pi = corners
    s_f, gap = fissure_height(V, corners, fu)
    a = float(lid["width_margin"]) * 0.5 * abs(ex[0] - en[0])
    cx = 0.5 * (ex[0] + en[0])
    depth = float(lid["depth"]) * fu
    front = ramp(V[:, 2], c[2] - depth, c[2] + 0.04 * fu)
    ru = np.sqrt(((V[:, 0] - cx) / a) ** 2 + (s_f / (float(lid["upper_height"]) * fu)) ** 2)
    rl = np.sqrt(((V[:, 0] - cx) / a) ** 2 + (s_f / (float(lid["lower_height"]) * fu)) ** 2)
    if gap_to_skin > 0.25 * gap:
        up_step, low_step = ramp(s_f, 0.0, 0.15 * gap), ramp(-s_f, 0.0, 0.15 * gap)
    else:  # closed lids (one surface across the fissure): spread so nothing folds over
        up_step, low_step = ramp(s_f, -0.5 * gap, 1.5 * gap), ramp(-s_f, -0.5 * gap, 1.5 * gap)
    # the fissure opens as 1 - u^2 between the corners, so the lid joints turn less there
    u = (V[:, 0] - cx) / (0.5 * abs(ex[0] - en[0]))
    # the medial canthus is tied to bone, the lateral one is looser: toward (and past) the
    # outer corner the lids keep turning over ``lateral_reach`` half fissure widths
    u = np.where(u * np.sign(ex[0] - en[0]) > 0, u / float(lid["lateral_reach"]), u)
    h = np.clip(1.0 - u * u, 0.0, 1.0) ** float(lid["corner_exponent"])
    # above the margin the upper lid turns as one sheet: the corners hold the margin only,
    # so their hold fades over ``corner_release`` fissure heights up the lid
    rel = float(lid["corner_release"])
    h_up = 1.0 - (1.0 - h) * (1.0 - ramp(s_f, 0.0, rel * gap)) if rel > 0 else h
    upper = ramp(ru, 1.0, 0.55) * up_step * front * skin * h_up
    lower = ramp(rl, 1.0, 0.55) * low_step * front * skin * h
    phi = lambda p: np.arctan2(p[1] - c[1], p[2] - c[2])  # noqa: E731
    return upper, lower, np.degrees(phi(ps) - phi(pi))


def lid_weights(V, F, skin, landmarks, eyes, fu, lid, surface):
    """The four lid joints of a head.

    ``V`` (n, 3), ``F`` (m, 3), ``skin`` (n,) bool, ``landmarks`` name -> (3,), ``eyes`` side
    (``l``/``r``) -> eye pivot (3,) (an eye without a pivot gets no lids), ``lid`` the resolved
    ``model.eyelids`` (also ``smoothing``, fu), ``surface`` the SkinSurface (its Laplacian).

    Returns
    -------
    weights : (4, n) float
        In :data:`LIDS` order, in [0, 1]; diffused over ``smoothing`` (a lid joint turns its skin
        by the whole closing angle: a weight changing within a few of the eye corners' tiny
        triangles would fold them), kept where above 1e-3, skin only.
    close_deg : (2,) float
        Closing angle of the upper lid (l, r), degrees.
    pivots : (2, 3) float
        Eye pivots (l, r; zero where there is no eye).
    """
    n = len(V)
    W = np.zeros((4, n))
    close_deg = np.zeros(2)
    pivots = np.zeros((2, 3))
    gaps = fissure_gaps(V, F, skin, landmarks)
    for e, s in enumerate("lr"):
        c = eyes.get(s)
        if c is None:
            continue
        W[e], W[2 + e], close_deg[e] = eye_lid_weights(V, skin, c, eye_corners(landmarks, c, s, fu), gaps[e], fu, lid)
        pivots[e] = c
    t_l = (float(lid["smoothing"]) * fu) ** 2
    if t_l > 0:
        lw = surface.diffuse(W.T, t_l).T
        # diffusion reaches the whole skin with vanishing weights: the lids keep their own area
        W = np.where(lw > 1e-3, np.clip(lw, 0.0, 1.0), 0.0) * skin
    return W, close_deg, pivots


def margin_release(weights, margin_hold):
    """(n,) float: the share of the muscles' pull each vertex keeps, 1 - ``margin_hold`` times its
    largest lid weight (``weights`` (4, n)). The lid margins ride the eyeball: the muscles
    around (frontalis, zygomatics) stretch the lids' skin but leave the margins to the lid joints."""
    return 1.0 - float(margin_hold) * weights.max(axis=0)


def lid_attachments(V, skin, part, eye_weight, lid_any, fu, max_size):
    """Small separate parts held where they touch the lid skin (lashes, eye shells).

    Parameters
    ----------
    V : (n, 3) float
        Vertices.
    skin : (n,) bool
        Skin vertices.
    part : (n,) int
        Connected part of each vertex.
    eye_weight : (n,) float
        Summed eye-bone weights (eyeballs are not attached parts).
    lid_any : (n,) float
        Largest lid weight per vertex.
    fu : float
        Face unit.
    max_size : float
        Largest attached part (fu).

    Returns
    -------
    attached : (n,) bool
        Vertices of the attached parts.
    source : (n,) int64
        For each vertex the skin vertex it follows: the skin under the nearest of its part's
        touching vertices (for other vertices, simply the nearest skin vertex).
    parts : list of ((p,) int64, (r,) int64)
        Per attached part its vertices and its touching vertices (roots).
    """
    n = len(V)
    attached = np.zeros(n, dtype=bool)
    skin_idx = np.flatnonzero(skin)
    d_skin, near = cKDTree(V[skin_idx]).query(V)
    near = skin_idx[near]
    size = float(max_size) * fu
    parts = []
    for p_ in np.unique(part[~skin]):
        rows = np.flatnonzero((part == p_) & ~skin)
        if (eye_weight[rows].mean() >= 0.5 or np.ptp(V[rows], axis=0).max() > size
                or d_skin[rows].min() > 0.01 * fu or lid_any[near[rows]].max() < 0.1):
            continue
        attached[rows] = True
        roots = rows[d_skin[rows] <= d_skin[rows].min() + 0.01 * fu]
        near[rows] = near[roots[cKDTree(V[roots]).query(V[rows])[1]]]
        parts.append((rows, roots))
    return attached, near, parts


def attach_lid_weights(weights, attached, source, parts):
    """Lid weights (4, n) with the attached parts following the lids (a new array).

    Each attached vertex takes the weights of its ``source``; then a part rooted on one lid only
    (a row of lashes on its tarsal plate) turns as one piece with the margin, corners included
    (the largest weight at its roots), while a part rooted on both (a shell across the fissure)
    stretches between them. ``attached``, ``source``, ``parts``: :func:`lid_attachments`.
    """
    W = weights.copy()
    rows = np.flatnonzero(attached)
    W[:, rows] = W[:, source[rows]]
    for part_rows, roots in parts:
        rw = W[:, roots]
        on_upper = np.mean(rw[:2].max(axis=0) >= rw[2:].max(axis=0))
        if on_upper >= 0.9 or on_upper <= 0.1:
            W[:, part_rows] = rw.max(axis=1)[:, None]
    return W


def attach_hinge_share(share, weights, attached, source, parts):
    """The hinge share (n,) with the attached parts following (a new array): each attached vertex
    takes its ``source``'s share, and a part that turns as one piece with one lid (a lash row,
    as :func:`attach_lid_weights` decides from the lid ``weights`` (4, n)) turns all about the
    hinge when the largest share at its roots is at least 1/2 (it hinges with the margin it sits
    on), else all about the pivot. ``attached``, ``source``, ``parts``:
    :func:`lid_attachments`."""
    out = share.copy()
    rows = np.flatnonzero(attached)
    out[rows] = share[source[rows]]
    W = weights.copy()
    W[:, rows] = W[:, source[rows]]
    for part_rows, roots in parts:
        rw = W[:, roots]
        on_upper = np.mean(rw[:2].max(axis=0) >= rw[2:].max(axis=0))
        if on_upper >= 0.9 or on_upper <= 0.1:
            # one rigid turn: all about the hinge or all about the pivot (a blend of two
            # turns about different axes would bend the part)
            out[part_rows] = float(out[roots].max() >= 0.5)
    return out


def ride_lids(G, creases, release, attached, source):
    """Muscle and crease fields with the lid margins released and the attached parts following.

    ``G`` (k, n, 3) muscle fields and ``creases`` (muscle index -> (n, 3)) are scaled per vertex
    by ``release`` (n,) (:func:`margin_release`); then each ``attached`` (n,) bool vertex takes
    the fields of its ``source`` (n,) int skin vertex (:func:`lid_attachments`). New arrays.
    """
    G = G * release[None, :, None]
    creases = {i: K * release[:, None] for i, K in creases.items()}
    rows = np.flatnonzero(attached)
    G[:, rows] = G[:, source[rows]]
    for K in creases.values():
        K[rows] = K[source[rows]]
    return G, creases
