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
spring (1, then doubled each round up to :data:`SPRING_CAP`, at most :data:`ROUNDS` rounds); the springs matter where the
Laplacian's own weights do not reach (long edges of sliver triangles, the robot's fans) and spread
a falloff ring by ring. Where the carried weight is already smooth and agrees with the landmarks
nothing but the mild data-term smoothing changes. Only the jaw's surroundings are solved: vertices
farther than :data:`REACH` face units from any jaw weight keep theirs (0), and the rounds after the
first re-solve only :data:`RINGS` rings of edges around the springs, the rest held (on a dense scan a
whole-face solve per round took seconds).

Seeds (what the landmarks say), each the vertex nearest a landmark, or a band of vertices:

- lower (jaw 1): ``pogonion``, ``labiale_inferius``, ``sublabiale``, and the lower lip along the
  lip line (below the mouth plane through ``stomion`` and both ``cheilion``, in front of the line
  between the corners, within a thin band of the plane). Not the ``menton``: under the chin the
  jaw weight may fade toward the neck, and on a short face (the robot's) a menton pinned to 1 a
  few edges from a ``pronasale`` pinned to 0 would force a step; it keeps the carried weight,
  smoothed;
- a mouth interior (:func:`inner_mouth_sides`: ICT's, a game head's mouth bag; a closed-mouth scan
  has none): its floor, facing up across the mouth plane, is jaw 1 and its roof, facing down, jaw 0.
  Without them the interior was left to the smooth field between the outer lips' seeds: about half
  jaw on both, so an opened jaw dragged the inside of the upper lip down and left the inside of the
  lower lip behind;
- upper (jaw 0): the upper lip along the lip line (above the mouth plane, same band), the upper
  lip, nose, eye, brow, forehead, ear and skull landmarks, and every vertex more than
  :data:`ABOVE_MARGIN` face units above the jaw's top plane (``stomion`` and both ``gonion``; without
  gonions the mouth plane): the upper face, the eyes, the skull.

The lip line is the one place the field may jump: its edges (:func:`lip_line_edges`) join an
upper and a lower lip seed across the mouth plane, or cross the plane just behind the corners.
Missing landmarks drop their seeds; without ``stomion`` and both cheilions there is no lip line
and no band, and without ``stomion`` no plane: this is the fallback to what the carried weights
give (documented in the brief's terms): the carried weight is then only smoothed where it
jumps, with any chin or lip landmarks still pinned (the robot has none: only its upper-face
landmarks are pinned, and its carried jaw weight is smoothed). Vertices with eye
weight (eyeballs bound to the eye bones) keep their jaw weight.

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

MAX_JUMP = 0.3          # the largest jaw-weight step allowed on an edge off the lip line
TARGET_JUMP = 0.27      # what the repair aims for (a margin below MAX_JUMP)
ROUNDS = 16             # smoothing rounds at most
SPRING_CAP = 64.0        # the strongest spring, in the Laplacian's weights (an infeasible step stays local)
ABOVE_MARGIN = 0.12     # fu above the jaw's top plane: jaw 0 there
CORNER = 0.06           # fu: edges this near a mouth corner belong to the lip line
RINGS = 8               # rings of edges around the springs that later rounds re-solve
REACH = 0.4             # fu: vertices farther than this from any jaw weight keep theirs (0), unsolved
INNER_DEPTH = 0.5       # fu behind the corners' line: how deep a mouth interior is seeded
INNER_BAND = 0.25       # fu either side of the mouth plane
INNER_FACING = 0.7      # cos 45 degrees: a floor faces up across the plane, a roof down
LOWER = ("pogonion", "labiale_inferius", "sublabiale")  # not the menton: see the module doc
UPPER = ("vertex", "opisthocranion", "glabella", "nasion", "pronasale", "subnasale", "labiale_superius",
         *(f"{n}_{s}" for n in ("exocanthion", "endocanthion", "palpebrale_superius", "palpebrale_inferius",
                                "brow_inner", "brow_middle", "brow_outer", "alare", "crista_philtri",
                                "zygion", "tragion", "superaurale", "subaurale", "frontotemporale")
           for s in ("l", "r")))


def face_unit(V, landmarks):
    """The face unit (float, mesh units): the exocanthion distance, else a quarter of the bounding
    box diagonal of ``V`` (n, 3)."""
    if "exocanthion_l" in landmarks and "exocanthion_r" in landmarks:
        fu = float(np.linalg.norm(np.subtract(landmarks["exocanthion_l"], landmarks["exocanthion_r"])))
        if fu > 0:
            return fu
    return 0.25 * float(np.linalg.norm(np.ptp(V, axis=0)))


def _up_hint(landmarks):
    """(3,) a point on the upper face (mean of the upper landmarks given), or None."""
    pts = [landmarks[n] for n in UPPER if n in landmarks and n not in ("opisthocranion",)]
    return np.mean(pts, axis=0) if pts else None


def _plane(a, b, c, up_point):
    """Unit normal (3,) of the plane through ``a``, ``b``, ``c`` pointing to ``up_point``'s side."""
    n = np.cross(np.subtract(b, a), np.subtract(c, a))
    norm = np.linalg.norm(n)
    if norm == 0:
        return None
    n = n / norm
    return -n if up_point is not None and np.dot(np.subtract(up_point, a), n) < 0 else n


def mouth_frame(landmarks):
    """The mouth plane, or None without ``stomion`` and both ``cheilion``.

    Returns a dict: ``stomion`` (3,), ``normal`` (3,) unit, toward the upper face; ``lateral`` (3,)
    unit, right to left corner; ``forward`` (3,) unit, in the plane, from the corners' midpoint
    toward the stomion; ``mid`` (3,) the corners' midpoint; ``half_width`` (float) half the
    corner distance.
    """
    if not all(n in landmarks for n in ("stomion", "cheilion_l", "cheilion_r")):
        return None
    st, cl, cr = (np.asarray(landmarks[n], dtype=np.float64) for n in ("stomion", "cheilion_l", "cheilion_r"))
    normal = _plane(st, cl, cr, _up_hint(landmarks))
    if normal is None:
        return None
    lateral = (cl - cr) / np.linalg.norm(cl - cr)
    mid = 0.5 * (cl + cr)
    forward = np.cross(normal, lateral)
    if np.dot(st - mid, forward) < 0:
        forward = -forward
    return dict(stomion=st, normal=normal, lateral=lateral, forward=forward, mid=mid,
                half_width=0.5 * float(np.linalg.norm(cl - cr)))


def _mean_edge_length(n, E, V):
    """(n,) mean length of each vertex's edges (0 for a vertex on none)."""
    length = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    total = np.bincount(E.ravel(), weights=np.r_[length, length], minlength=n)
    count = np.bincount(E.ravel(), minlength=n)
    return total / np.maximum(count, 1)


def _lip_sides(V, mouth, band, behind):
    """(n,) int8: +1 upper lip side, -1 lower lip side, 0 elsewhere: vertices within ``band`` of the
    mouth plane, in front of the corners' line less ``behind`` and within the mouth's half-width
    plus ``behind`` of the midline (mesh units)."""
    d = V - mouth["mid"]
    s = (V - mouth["stomion"]) @ mouth["normal"]
    zone = ((d @ mouth["forward"] > -behind) & (np.abs(d @ mouth["lateral"]) < mouth["half_width"] + behind)
            & (np.abs(s) < band))
    return np.where(zone, np.where(s > 0, 1, -1), 0).astype(np.int8)


def inner_mouth_sides(V, F, landmarks):
    """Which vertices line a mouth interior: (n,) int8, +1 its roof (jaw 0), -1 its floor (jaw 1), 0
    elsewhere; all 0 without ``stomion`` and both ``cheilion``.

    A vertex lines the interior when it lies behind the corners' line (at most :data:`INNER_DEPTH`
    face units), between the corners, within :data:`INNER_BAND` face units of the mouth plane, and
    faces across the mouth plane: a floor vertex below the plane facing up (within 45 degrees of the
    plane's normal), a roof vertex above it facing down. A closed-mouth scan has no surface there,
    and cheeks, chin and nose face other ways, so only the insides of the lips, the mouth's floor and
    roof (and teeth, tongue or a mouth bag, when they are part of the mesh) are seeded. The mesh's
    orientation is read at the lips, whose outer surface faces forward.
    ``V`` (n, 3), ``F`` (m, 3), ``landmarks`` name -> (3,), mesh units and frame.
    """
    from ..geometry.normals import vertex_normals

    V = np.asarray(V, dtype=np.float64)
    lm = {k: np.asarray(v, dtype=np.float64) for k, v in landmarks.items()}
    mouth = mouth_frame(lm)
    out = np.zeros(len(V), dtype=np.int8)
    if mouth is None:
        return out
    fu = face_unit(V, lm)
    d = V - mouth["mid"]
    ahead = d @ mouth["forward"]
    s = (V - mouth["stomion"]) @ mouth["normal"]
    zone = ((ahead < 0) & (ahead > -INNER_DEPTH * fu) & (np.abs(d @ mouth["lateral"]) < mouth["half_width"])
            & (np.abs(s) < INNER_BAND * fu))
    if not zone.any():
        return out   # a closed mouth (most heads): no normals needed
    N = vertex_normals(V, np.asarray(F))
    lips = [lm[n] for n in ("labiale_superius", "labiale_inferius", "stomion") if n in lm]
    at = [int(np.argmin(((V - p) ** 2).sum(axis=1))) for p in lips]
    if (N[at] @ mouth["forward"]).mean() < 0:
        N = -N   # inward-facing triangles
    facing = N @ mouth["normal"]
    out[zone & (s > 0) & (facing < -INNER_FACING)] = 1
    out[zone & (s < 0) & (facing > INNER_FACING)] = -1
    return out


def lip_line_edges(V, F, landmarks):
    """Which edges cross the lip line: ``(E, on_line)``, ``E`` (k, 2) int the mesh's unique edges
    (:func:`autobones.geometry.topology.mesh_edges` of ``F``) and ``on_line`` (k,) bool.

    An edge is on the lip line when it joins a vertex above the mouth plane (``stomion``, both
    ``cheilion``) to one below it, both within 0.1 face units of the plane and no further than that
    behind the corners' line or outside the corners, or when it touches a vertex within
    :data:`CORNER` face units (at least two median edge lengths) of a mouth corner, where the weight
    turns from the upper lip's to the lower lip's in a ring or two whichever way an edge runs. All
    False without those three landmarks.
    ``V`` (n, 3), ``F`` (m, 3), ``landmarks`` name -> (3,), mesh units and frame.
    """
    V = np.asarray(V, dtype=np.float64)
    E = mesh_edges(np.asarray(F))
    mouth = mouth_frame(landmarks)
    if mouth is None:
        return E, np.zeros(len(E), dtype=bool)
    fu = face_unit(V, landmarks)
    side = _lip_sides(V, mouth, 0.1 * fu, 0.1 * fu)
    on_line = (side[E[:, 0]] * side[E[:, 1]]) < 0
    # the line's ends: around a mouth corner the weight turns from the upper lip's to the lower
    # lip's within a ring or two of edges, whichever way the edges run
    length = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    radius = max(CORNER * fu, 2.0 * float(np.median(length))) if len(E) else 0.0
    for name in ("cheilion_l", "cheilion_r"):
        d = V - np.asarray(landmarks[name], dtype=np.float64)
        near = np.einsum("ij,ij->i", d, d) < radius * radius
        on_line |= near[E[:, 0]] | near[E[:, 1]]
    return E, on_line


def repair_jaw(V, F, jaw, landmarks, keep=None, details=None):
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
    details : dict, optional
        Filled with ``lower`` / ``upper`` (n,) bool (the seeds), ``on_line`` (k,) bool and ``edges``
        (k, 2) (:func:`lip_line_edges`), ``rounds`` (int) and ``max_jump`` (float, off the lip line).

    Returns
    -------
    (n,) float
        The repaired jaw weight, 0..1.
    """
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

    # --- seeds -----------------------------------------------------------------------------------
    lower = np.zeros(nw, dtype=bool)
    upper = np.zeros(nw, dtype=bool)
    from scipy.spatial import cKDTree

    tree = cKDTree(Vw)
    for names, mask in ((LOWER, lower), (UPPER, upper)):
        given = [lm[name] for name in names if name in lm]
        if given:
            mask[tree.query(np.array(given), workers=-1)[1]] = True
    mouth = mouth_frame(lm)
    side = np.zeros(nw, dtype=np.int8)
    if mouth is not None:
        # the lips on either side of the mouth plane, between the corners: the cut itself
        side = _lip_sides(Vw, mouth, max(0.05 * fu, 1.5 * h_med), 0.0)
        upper |= side > 0
        lower |= side < 0
        # a mouth interior (ICT's, a game head's mouth bag): its floor goes with the jaw, its roof stays
        inner = inner_mouth_sides(Vw, Fw, lm)
        upper |= inner > 0
        lower |= inner < 0
    if "stomion" in lm:
        # the upper face: well above the jaw's top plane (the gonions' when given)
        top = None
        if "gonion_l" in lm and "gonion_r" in lm:
            top = _plane(lm["stomion"], lm["gonion_l"], lm["gonion_r"], _up_hint(lm))
        if top is None and mouth is not None:
            top = mouth["normal"]
        if top is not None:
            upper |= (Vw - lm["stomion"]) @ top > ABOVE_MARGIN * fu
    both = lower & upper
    lower &= ~both  # a vertex both sides claim (a thin lip) is left to the solve
    upper &= ~both

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

    # edges allowed to jump: the lip line (across the mouth plane between the corners, and around them)
    on_line_w = lip_line_edges(Vw, Fw, lm)[1]
    check = ~on_line_w & ~(fixed[Ew[:, 0]] & fixed[Ew[:, 1]])  # two fixed ends: nothing to solve

    # --- the region that can change: free vertices near the jaw --------------------------------
    # the data term holds a vertex far from any jaw weight at 0 (the screened field decays within a
    # few edges), so the scalp, a bust's chest and the back of the neck need no solve; the solve and
    # its Laplacian cover only the jaw's surroundings, a fraction of a dense scan
    source = (ww > 0) | lower
    if source.any() and (~fixed).any():
        reach = max(REACH * fu, 30.0 * h_med)
        far = np.isinf(cKDTree(Vw[source]).query(Vw, distance_upper_bound=reach, workers=-1)[0])
        settled = ~fixed & far
        value = np.where(settled, ww, value)
        fixed |= settled
    # the Laplacian of the faces around free vertices: complete rows for every free vertex
    sub_f = (~fixed[Fw]).any(axis=1)
    on_sub = np.zeros(nw, dtype=bool)
    on_sub[Fw[sub_f].ravel()] = True
    rows = np.flatnonzero(on_sub)
    L, m = sp.csr_matrix((nw, nw)), np.zeros(nw)
    if len(rows):
        Fs = (np.cumsum(on_sub) - 1)[Fw[sub_f]]
        Ls = clipped_cotangent_laplacian(Vw[rows], Fs).tocoo()
        L = sp.csr_matrix((Ls.data, (rows[Ls.row], rows[Ls.col])), shape=(nw, nw))
        m[rows] = vertex_areas(Vw[rows], Fs)

    # --- screened Laplace solve, smoothing length doubled where edges still jump -----------------
    x = value.copy()
    m = np.where(m > 0, m, h ** 2)  # vertices on no face: a nominal area
    free = np.flatnonzero(~fixed)
    spring = np.zeros(len(Ew))
    # the data term holds the jaw's core harder than its rim: the falloff widens outward (into the
    # neck and the cheeks) instead of eating into the chin
    lam = (0.1 + 0.9 * ww) * m / h ** 2
    rounds = 0
    solve_at = free
    for rounds in range(1, ROUNDS + 1):
        if len(solve_at):
            # springs on edges that jumped in earlier rounds: on sliver triangles the Laplacian's
            # weight of a long edge is near zero, and only a spring evens its two ends
            on = spring > 0
            Es, ks = Ew[on], spring[on]
            S = sp.csr_matrix((np.r_[ks, ks], (np.r_[Es[:, 0], Es[:, 1]], np.r_[Es[:, 1], Es[:, 0]])), shape=(nw, nw))
            # the rows being solved only: the rest of the surface is held where it is
            r = np.arange(len(solve_at))
            degree = sp.csr_matrix((np.asarray(S.sum(axis=1)).ravel()[solve_at], (r, solve_at)),
                                   shape=(len(solve_at), nw))
            K = L[solve_at] + degree - S[solve_at]
            held = x.copy()
            held[solve_at] = 0.0
            A = K[:, solve_at] + sp.diags(lam[solve_at])
            x[solve_at] = factor_spd(A)(lam[solve_at] * ww[solve_at] - K @ held)
        x = np.clip(x, 0.0, 1.0)
        jump = np.abs(x[Ew[:, 0]] - x[Ew[:, 1]])
        bad = check & (jump > TARGET_JUMP)
        if not bad.any():
            break
        # a step against a fixed vertex that the strongest spring could not even out (the robot's
        # nose tip, pinned at 0, a few edges above its chin): the free end is pinned one allowed
        # step from the fixed one, and the next rounds spread the rest of the falloff behind it
        stuck = bad & (spring >= SPRING_CAP) & (fixed[Ew[:, 0]] != fixed[Ew[:, 1]])
        if stuck.any():
            a = np.where(fixed[Ew[stuck, 0]], Ew[stuck, 0], Ew[stuck, 1])
            b = np.where(fixed[Ew[stuck, 0]], Ew[stuck, 1], Ew[stuck, 0])
            step = np.clip(x[b], x[a] - TARGET_JUMP, x[a] + TARGET_JUMP)
            pin = np.full(nw, np.inf)
            np.minimum.at(pin, b, np.where(step < x[b], step, np.inf))   # lowered: the lowest bound
            high = np.full(nw, -np.inf)
            np.maximum.at(high, b, np.where(step > x[b], step, -np.inf))
            x = np.where(np.isfinite(pin), pin, np.where(np.isfinite(high), high, x))
            fixed[b] = True
            check = ~on_line_w & ~(fixed[Ew[:, 0]] & fixed[Ew[:, 1]])
        spring[bad] = np.minimum(np.maximum(2.0 * spring[bad], 1.0), SPRING_CAP)
        # later rounds re-solve only around the springs (RINGS rings of edges): the screened field
        # decays within a few edges, and a whole face's solve per round took seconds on dense scans
        near = np.zeros(nw, dtype=bool)
        near[Ew[spring > 0].ravel()] = True
        for _ in range(RINGS):
            near[Ew[near[Ew].any(axis=1)].ravel()] = True
        solve_at = np.flatnonzero(near & ~fixed)

    out = x[index]
    if keep is not None:
        out = np.where(keep, w, out)
    if details is not None:
        E, on_line = lip_line_edges(V, F, lm)
        jump = np.abs(out[E[:, 0]] - out[E[:, 1]])
        details.update(lower=lower[index], upper=upper[index], edges=E, on_line=on_line, rounds=rounds,
                       max_jump=float(jump[~on_line].max()) if (~on_line).any() else 0.0)
    return out


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


def repair_jaw_weights(V, F, W, names, landmarks, details=None):
    """Skin weights ``W`` (n, b) (bone ``names``, list of b str) with the jaw column repaired by
    :func:`repair_jaw` and the head bone taking up the difference (:func:`with_jaw`); eyeball
    vertices (any ``eye_l`` / ``eye_r`` weight) keep theirs. A copy of ``W`` without a ``jaw`` bone.
    Rows keep their sums (1)."""
    W = np.asarray(W, dtype=np.float64)
    if "jaw" not in names:
        return W.copy()
    j = names.index("jaw")
    eyes = [names.index(e) for e in ("eye_l", "eye_r") if e in names]
    keep = (W[:, eyes].sum(axis=1) > 0) if eyes else None
    jaw = repair_jaw(V, F, W[:, j], landmarks, keep=keep, details=details)
    return with_jaw(W, j, names.index("head") if "head" in names else None, jaw)
