"""An articulated jaw prior for the correspondence: the source skin's jaw opened as far as the
target's landmarks say, before the thin-plate-spline warp.

Beyond the seeds (issue #13, item 3). The landmark TPS of Orvalho, Zacur & Susin 2008 (§3.1) is a
smooth warp; a jaw turned about its joint is not, so a closed-mouth generic skin warped onto an
open-mouth head drags the lower face, the chin and the neck (benchmarks/README.md, ``--families``).
Here the source skin is first posed with its own jaw bone, the way the rig itself opens the jaw
(:func:`autobones.expressions.bones.turn_jaw`: each vertex turned about the hinge by its jaw weight
times the angle, blending the angle rather than the positions, so half-weighted skin under the chin
does not collapse toward the pivot, and moved by its weight times the condyle's glide, down and
forward along the articular eminence, per degree: the definitions' ``model.jaw_glide``), and the
posed skin is what the TPS warps and what the fit's shape term keeps
(:func:`autobones.rig_transfer.correspondence.fit_surface`, ``jaw=``). The correspondence is still a
map of the source's own vertices. The glide took ICT's jawOpen neck from 1.57 / 4.01 to 1.09 / 3.13 %
of ex-ex and its scalp from 0.76 / 3.42 to 0.44 / 2.09 (benchmarks/README.md, ``--families``).

The weight the prior turns (:func:`jaw_prior`) is the rig's jaw weight spread below the mouth
(:func:`spread_jaw_weight`, over :data:`SPREAD` face units): an open jaw also stretches the floor of
the mouth, the inside of the lips and the neck under the chin, which a rig's animation weight (a step
at the lip line, a short falloff under the chin) leaves behind. On ICT's jawOpen the rig's own weight
made the neck worse than no prior (p95 9.4 -> 24 % of ex-ex); the spread weight brings it to 4.3.
Above the mouth plane the rig's own weight is kept, or the upper lip and nose would turn too (on the
built-in generic's compact face the spread reached the eyes and the angle came out 0).

The angle (:func:`estimate_jaw_angle`): the landmarks the jaw does not carry (jaw weight below
:data:`UPPER_WEIGHT`) give a similarity (Umeyama 1991) bringing the target's landmarks into the
source's frame; the angle is then the least-squares fit of the jaw-carried landmarks, turned by their
own jaw weight times the angle, to the target's (a 2.5-degree scan, then a bounded 1-D search). A
closed mouth gives about 0 whatever the face's proportions (ICT identities: within 0.3 degrees; a
pucker up to 2.1), and an estimate within :data:`DEAD_ZONE` degrees of 0 is taken as 0, so
closed-mouth targets are fitted exactly as without the prior. The search does not close the jaw past
rest: from the built-in generic rig a pucker or a smile reads as -2 to -3.3 degrees (lip shape, not
the jaw). Tried: the angle minimising the TPS
bending energy (ICT jawOpen 17 degrees, pucker 4-4.5: more false opening) and a similarity of all
landmarks refitted at each angle (jawOpen 18-19, pucker 2.7-3.0); the least squares after the upper
face's similarity separates best (jawOpen 19.6-20.6, pucker 1.8-2.1).

Frames and units: the source mesh's own (the rig's); angles in degrees, positive opens the jaw.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import minimize_scalar

from ..errors import AutobonesError, counted
from ..geometry.rotations import similarity

UPPER_WEIGHT = 0.05        # landmarks with less jaw weight than this place the upper face (the similarity)
LOWER_WEIGHT = 0.5         # the angle needs at least one landmark this much on the jaw
MIN_UPPER = 4              # landmarks needed for the similarity
ANGLE_RANGE = (0.0, 45.0)  # degrees searched: the jaw does not close past rest (the teeth meet)
SPREAD = 0.4               # face units the prior's jaw weight is spread over (spread_jaw_weight)
MOUTH_BAND = 0.1           # face units: the spread weight hands over to the rig's own across the mouth plane
DEAD_ZONE = 3.0            # degrees: an estimate this near 0 is 0 (closed-mouth targets fit as before)


def jaw_hinge(skeleton):
    """The jaw's hinge from a skeleton with ``jaw`` and ``head`` bones.

    Parameters
    ----------
    skeleton : autobones.skeleton.Skeleton
        Bones in the skin's frame and units.

    Returns
    -------
    pivot : (3,) float
        The jaw bone's head (its joint).
    axis : (3,) float
        Unit hinge axis, normal to the plane of the jaw bone and the head bone (the midsagittal
        plane of a symmetric rig), signed so that a positive turn moves the jaw's tail (the chin)
        away from the head bone's tail (the skull): opens the mouth.

    Raises
    ------
    AutobonesError
        No ``jaw`` or ``head`` bone, or the two bones parallel.
    """
    pivot, chin, up = _jaw_bones(skeleton)
    axis = np.cross(up, chin)   # turns ``up`` toward ``chin``: the chin turns on, away from the skull
    norm = np.linalg.norm(axis)
    if not np.isfinite(norm) or norm <= 1e-9 * np.linalg.norm(up) * np.linalg.norm(chin):
        raise AutobonesError("the jaw prior: the rig's jaw and head bones are parallel, no hinge axis")
    return pivot, axis / norm


def _jaw_bones(skeleton):
    """The jaw's joint (3,), the jaw bone (joint to chin, (3,)) and the head bone (3,) of a skeleton."""
    names = list(skeleton.names)
    if "jaw" not in names or "head" not in names:
        raise AutobonesError("the jaw prior needs a rig with 'jaw' and 'head' bones; "
                             f"this one has {', '.join(names) or 'none'}")
    j, h = names.index("jaw"), names.index("head")
    pivot = np.asarray(skeleton.heads[j], dtype=np.float64)
    chin = np.asarray(skeleton.tails[j], dtype=np.float64) - pivot
    up = np.asarray(skeleton.tails[h], dtype=np.float64) - np.asarray(skeleton.heads[h], dtype=np.float64)
    return pivot, chin, up


def _down_forward(glide):
    """(down, forward) floats from a glide given as 0-2 numbers (missing ones 0)."""
    return tuple((list(np.ravel(glide).astype(float)) + [0.0, 0.0])[:2])


def jaw_glide_vector(skeleton, glide, fu):
    """(3,) float: the jaw's translation per degree of opening, in the skeleton's frame and units.

    ``glide`` = (down, forward) in face units per degree (the expression definitions'
    ``model.jaw_glide``; :func:`autobones.expressions.jaw.jaw_glide` is the same in the canonical
    frame); down is against the head bone, forward the jaw bone's direction (joint to chin) normal
    to it; ``fu`` the face unit in mesh units. Raises AutobonesError as :func:`jaw_hinge`.
    """
    jaw_hinge(skeleton)  # the bones it needs, checked (not parallel)
    _, chin, up = _jaw_bones(skeleton)
    up /= np.linalg.norm(up)
    ahead = chin - (chin @ up) * up
    ahead /= np.linalg.norm(ahead)
    down, forward = _down_forward(glide)
    return float(fu) * (forward * ahead - down * up)


def shipped_jaw_glide():
    """(down, forward) face units per degree: ``model.jaw_glide`` of the shipped
    ``generic_rig/expressions.json`` ((0, 0) when it has none), how ``pose`` glides the jaw."""
    import json

    from ..generic_rig import expressions_path

    try:
        with open(expressions_path(), encoding="utf-8") as fh:
            glide = json.load(fh)["model"].get("jaw_glide", [0.0, 0.0])
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise AutobonesError(f"{expressions_path()}: cannot read model.jaw_glide ({exc})") from None
    return _down_forward(glide)


def spread_jaw_weight(V, F, weight, length):
    """The jaw weight spread over the skin: what the prior turns, not what the rig animates.

    A rig's jaw weight is shaped for animation: a sharp step at the lip line, a short falloff under
    the chin. An open jaw also stretches the skin around it (the floor of the mouth, the neck under
    the chin, the inside of the lips), so the prior turns a smoothed copy: one implicit heat step
    over ``length`` (:func:`autobones.geometry.laplacian.diffuse`), divided by its median over the
    jaw's core (weight >= 0.95, not on a small closed part: a tooth) so that the chin still turns with
    the jaw, clipped to [0, 1].

    Parameters
    ----------
    V, F : (n, 3) float, (m, 3) int
        The skin (any frame and units).
    weight : (n,) float
        The rig's jaw weight, 0..1.
    length : float
        Smoothing length, mesh units (the field spreads over about this distance); 0: unchanged.

    Returns
    -------
    (n,) float64
    """
    from ..geometry.laplacian import diffuse, laplacian
    from ..geometry.rigid_parts import closed_small_parts

    w = np.clip(np.asarray(weight, dtype=np.float64), 0.0, 1.0)
    # the core is the skin's: a separate rigid part (a lower tooth, all jaw) keeps its weight through the
    # heat step and would raise the median (ICT's teeth on the jaw: the chin's spread weight fell and the
    # angle read off jawOpen rose from 20 to 36 degrees)
    core = w >= 0.95
    for rows in closed_small_parts(V, F):
        core[rows] = False
    if length <= 0 or not core.any():
        return w
    L, M = laplacian(np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64))
    ws = diffuse(w, L, M, float(length) ** 2)
    c = float(np.median(ws[core]))
    return np.clip(ws / c, 0.0, 1.0) if c > 0 else w


def jaw_prior(rig, spread=SPREAD, glide=None):
    """The jaw prior of a rig for :func:`autobones.rig_transfer.correspondence.fit_surface` (``jaw=``).

    The weight is the rig's jaw weight spread over ``spread`` face units (:func:`spread_jaw_weight`)
    below the mouth plane (``stomion`` and both ``cheilion``, :func:`autobones.rig_transfer.jaw.mouth_frame`)
    and the rig's own above it, blended over :data:`MOUTH_BAND` face units across the plane; without
    those landmarks, spread everywhere.

    Parameters
    ----------
    rig : LabelledRig or Rig
        Anything with ``vertices``, ``faces``, ``landmarks`` (for the face unit, the exocanthion
        distance), ``skeleton`` (``jaw`` and ``head`` bones) and ``weights`` (n, b).
    spread : float
        Face units the jaw weight is spread over (:func:`spread_jaw_weight`); 0: the rig's own.
    glide : (2,) float, optional
        (down, forward) face units per degree the jaw glides as it opens; None: the shipped
        definitions' (:func:`shipped_jaw_glide`), (0, 0): a pure hinge.

    Returns
    -------
    dict
        ``weight`` (n,) float, the (spread) jaw weight of each skin vertex in [0, 1]; ``pivot`` (3,)
        and ``axis`` (3,) as :func:`jaw_hinge`, and ``glide`` (3,) as :func:`jaw_glide_vector`, in the
        rig's frame and units.
    """
    from .jaw import face_unit, mouth_frame

    pivot, axis = jaw_hinge(rig.skeleton)
    w = np.asarray(rig.weights, dtype=np.float64)[:, list(rig.skeleton.names).index("jaw")]
    lm = {k: np.asarray(v, dtype=np.float64) for k, v in dict(rig.landmarks or {}).items()}
    fu = face_unit(rig.vertices, lm)
    ws = spread_jaw_weight(rig.vertices, rig.faces, w, spread * fu)
    mouth = mouth_frame(lm)
    if mouth is not None:
        # the spread stays below the mouth: above it (upper lip, face, skull) the rig's own weight,
        # blended over MOUTH_BAND face units across the plane so the field has no step
        h = (np.asarray(rig.vertices, dtype=np.float64) - mouth["stomion"]) @ mouth["normal"] / (MOUTH_BAND * fu)
        t = np.clip(0.5 + 0.5 * h, 0.0, 1.0)
        ws = (1.0 - t) * ws + t * np.clip(w, 0.0, 1.0)
    glide = jaw_glide_vector(rig.skeleton, shipped_jaw_glide() if glide is None else glide, fu)
    return {"weight": ws, "pivot": pivot, "axis": axis, "glide": glide}


def check_prior(jaw, n):
    """``jaw`` (dict as :func:`jaw_prior`) checked for a skin of ``n`` vertices: (weight (n,), pivot (3,),
    unit axis (3,), glide (3,)) float arrays; a dict without ``glide`` is a pure hinge (zeros).
    Raises AutobonesError naming what is wrong."""
    try:
        w = np.asarray(jaw["weight"], dtype=np.float64).reshape(-1)
        pivot = np.asarray(jaw["pivot"], dtype=np.float64).reshape(3)
        axis = np.asarray(jaw["axis"], dtype=np.float64).reshape(3)
        glide = np.asarray(jaw.get("glide", np.zeros(3)), dtype=np.float64).reshape(3)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise AutobonesError("jaw: expected a dict with 'weight' (n,), 'pivot' (3,), 'axis' (3,) and "
                             f"optionally 'glide' (3,) (see rig_transfer.jaw_prior.jaw_prior): {exc}") from None
    if len(w) != n:
        raise AutobonesError(f"jaw: 'weight' has {counted(len(w), 'value')} for a source of {counted(n, 'vertex', 'vertices')}")
    norm = np.linalg.norm(axis)
    if not (np.isfinite(w).all() and np.isfinite(pivot).all() and np.isfinite(norm) and norm > 0
            and np.isfinite(glide).all()):
        raise AutobonesError("jaw: weights, pivot, axis and glide must be finite and the axis non-zero")
    return np.clip(w, 0.0, 1.0), pivot, axis / norm, glide


def open_jaw(V, weight, pivot, axis, angle, glide=None):
    """Vertices with the jaw opened: each turned about the hinge by its weight times ``angle``, then
    moved by its weight times ``glide`` per degree.

    Parameters
    ----------
    V : (n, 3) float
        Rest vertices (any frame and units; the hinge's).
    weight : (n,) float
        Jaw weight of each vertex, 0..1.
    pivot, axis : (3,) float
        A point on the hinge and its unit axis.
    angle : float
        Degrees, positive opens (about ``axis``, right-handed).
    glide : (3,) float, optional
        Translation per degree (:func:`jaw_glide_vector`); None: a pure hinge.

    Returns
    -------
    (n, 3) float64
        New array; ``V`` itself (copied) where the weight is 0 or the angle 0.
    """
    V = np.asarray(V, dtype=np.float64)
    a = np.radians(float(angle)) * np.asarray(weight, dtype=np.float64)
    out = V.copy()
    rows = np.flatnonzero(a != 0)
    if len(rows) == 0:
        return out
    k = np.asarray(axis, dtype=np.float64)
    r = V[rows] - pivot
    c, s = np.cos(a[rows])[:, None], np.sin(a[rows])[:, None]
    # Rodrigues, one angle per vertex
    out[rows] = pivot + r * c + np.cross(k, r) * s + np.outer(r @ k, k) * (1.0 - c)
    if glide is not None and np.any(glide):
        step = np.asarray(glide, dtype=np.float64) * float(angle)
        out[rows] += np.asarray(weight, dtype=np.float64)[rows, None] * step
    return out


def estimate_jaw_angle(P, Q, weight, pivot, axis, details=None, glide=None):
    """The jaw opening (degrees) that brings the source landmarks ``P`` closest to the target's ``Q``.

    Parameters
    ----------
    P : (k, 3) float
        Source landmarks on the rest (closed-mouth) skin, the hinge's frame and units.
    Q : (k, 3) float
        The same landmarks on the target, row by row (target frame and units: any).
    weight : (k,) float
        Jaw weight at each source landmark (0..1; the skin's weight at its point).
    pivot, axis : (3,) float
        The hinge (:func:`jaw_hinge`), unit axis.
    glide : (3,) float, optional
        The jaw's glide per degree (:func:`jaw_glide_vector`); None: a pure hinge.
    details : dict, optional
        Filled with ``raw`` (float, degrees: the estimate before :data:`DEAD_ZONE`), ``upper`` and
        ``lower`` (int, landmark counts used), ``residual`` (float, RMS distance of the jaw-carried
        landmarks at the estimate, source units).

    Returns
    -------
    float
        Degrees in :data:`ANGLE_RANGE`, 0 within :data:`DEAD_ZONE` of 0 and when the landmarks cannot
        tell (fewer than :data:`MIN_UPPER` off the jaw, or none at least :data:`LOWER_WEIGHT` on it).
    """
    P, Q = np.asarray(P, dtype=np.float64), np.asarray(Q, dtype=np.float64)
    w = np.clip(np.asarray(weight, dtype=np.float64), 0.0, 1.0)
    upper, lower = w < UPPER_WEIGHT, w >= UPPER_WEIGHT
    info = {"raw": 0.0, "upper": int(upper.sum()), "lower": int(lower.sum()), "residual": float("nan")}
    if details is not None:
        details.update(info)
    if upper.sum() < MIN_UPPER or not (w >= LOWER_WEIGHT).any():
        return 0.0
    # the target's landmarks in the source frame, placed by the face the jaw does not move
    s, R = similarity(Q[upper], P[upper])
    t = P[upper].mean(axis=0) - s * Q[upper].mean(axis=0) @ R.T
    Qs = s * Q[lower] @ R.T + t
    Pl, wl = P[lower], w[lower]

    def cost(angle):
        return float(((open_jaw(Pl, wl, pivot, axis, angle, glide) - Qs) ** 2).sum())

    # a coarse scan, then a bounded refinement around the best cell: the cost is smooth but need
    # not be unimodal over the whole range
    grid = np.arange(ANGLE_RANGE[0], ANGLE_RANGE[1] + 1e-9, 2.5)
    g = grid[int(np.argmin([cost(a) for a in grid]))]
    res = minimize_scalar(cost, bounds=(max(g - 2.5, ANGLE_RANGE[0]), min(g + 2.5, ANGLE_RANGE[1])),
                          method="bounded", options={"xatol": 1e-3})
    angle = float(res.x)
    info.update(raw=angle, residual=float(np.sqrt(res.fun / len(Pl))))
    if details is not None:
        details.update(info)
    return 0.0 if abs(angle) < DEAD_ZONE else angle
