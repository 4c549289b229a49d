"""The head's share of the skin weights: a still neck base, a head/neck blend through the head joint.

One operation for both rigs (``place``'s :mod:`autobones.placement.locality` and ``transfer``'s
:mod:`autobones.rig_transfer.neck`): a rigger expects a head turn to leave the neck's base still and
to bend the neck around the head joint (the occiput-C1 pivot), whatever the weights came from (bone
heat splits the neck from the head wherever the two bones' segments are equidistant; a carried
generic rig puts its own blend wherever the warp took it).

:func:`head_share` is each vertex's share of the head and its children, from where it lies: 0
below a boundary through the head joint and 1 above it, a smooth step across a band centred on the
boundary. Behind the pivot the boundary is level with it (the suboccipital region: the skull above
turns, the nape below stays); in front it descends to pass under the chin, so the jaw, chin and
lips turn with the head and the throat stays with the neck. Given the jaw's angle (the gonions), it
also passes under the angle and along the mandible's lower border: a line from the pivot to the chin
passes over a low angle, which then stayed with the neck and the jaw folded along its border. The
band is measured across the boundary (a signed distance in the midline plane), so it does not thin
into a seam where the boundary falls steeply.

The neck base is pure neck: the share is 0 up to the higher of the lowest ``NECK_BASE`` of the
vertices and ``NECK_BASE`` of the mesh's height (and near a planar neck cut, which an animal's
slanted neck lifts above the lowest heights), rising over the next ``NECK_RISE`` of the way to the
joint. Where those vertices reach the chin (a face far denser than its neck: ICT's reach 0.04 head
sizes above its menton) they are no neck's base: held still up to the chin, the neck sheared the
whole head turn across a band under the jaw. The base is then the lower ``DENSE_BASE`` of the neck
under the chin, the rest of the neck bending. The face and its band keep the whole share wherever
they hang (a long muzzle below any boundary through the pivot), down to the chin, which keeps it
even inside the base.

:func:`apply_head_share` then moves weight between the neck and the rest so each row's head side
sums to the share: the neck gets ``1 - share``; the head and its children keep their weights where
these sum to less than the share (the head bone takes the rest) and are scaled down alike where
more. Rows stay non-negative and sum to one. Everything is per vertex in the canonical frame (head
sizes, +Y up, +Z front), so it is unit- and frame-free, and near-linear in the vertex count.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .normals import triangle_normals
from .smooth import smoothstep
from .topology import used_vertices

NECK_BASE = 0.05     # of the vertices and of the height: the neck base, kept still
NECK_RISE = 0.30     # of the way from the neck base to the joint: the head's share rises over it
HEAD_BAND = 0.10     # head sizes: half-width of the neck/head blend across the boundary
BAND_SHARE = 0.4     # ... and at most this share of the height from the neck base to the joint
CHIN_MARGIN = 0.05   # head sizes: the boundary passes this far under the chin
ANGLE_MARGIN = 2.0   # half-bands: the boundary passes this far under the jaw's angle (0.8-1 there after smoothing)
ROUND = 0.05         # head sizes: the boundary's bend at the pivot is rounded over this depth
OPEN_FACE = 0.22     # vector area / area above which a forward-facing open shell is a face mask
SAMPLES = 200_000    # at most this many points along the boundary's curve (_across)
SMOOTH_RINGS = 6     # Jacobi steps of :func:`smooth_share`: every band at least a few edges wide
DENSE_BASE = 0.5     # of the neck under the chin: its still base where the lowest vertices reach the chin
STILL = 0.01         # a share this low moves a vertex by at most about 1% of a head turn's peak: kept
CHUNK = 65536


def neck_base_height(heights, share=NECK_BASE):
    """Top of the neck base: the higher of the lowest ``share`` of the vertices (a dense bust base,
    a coarse neck under a dense face) and ``share`` of the height above the lowest vertex.
    ``heights``: (k,) heights of the used vertices."""
    heights = np.asarray(heights, dtype=np.float64)
    low = float(heights.min())
    return max(float(np.quantile(heights, share)), low + share * (float(heights.max()) - low))


def face_only(V, F):
    """True for a face mask: an open shell whose opening faces back or front (the vector area of a
    closed head sums to zero, a neck cut's points down, a face-only capture's along the depth axis).
    ``V`` canonical."""
    N = triangle_normals(np.asarray(V, dtype=np.float64), np.asarray(F))
    area = np.linalg.norm(N, axis=1).sum()
    vec = N.sum(axis=0)
    size = np.linalg.norm(vec)
    return bool(size > OPEN_FACE * max(area, 1e-300) and abs(vec[2]) > 0.7 * size)


def mask_distance(C, mask, bound):
    """(n,) distance of each point of ``C`` (n, 3) to the points under ``mask`` (n,) bool: 0 on it,
    inf beyond ``bound`` and everywhere when the mask is empty (one k-d tree query bounded by it)."""
    mask = np.asarray(mask, dtype=bool)
    if not mask.any():
        return np.full(len(C), np.inf)
    d, _ = cKDTree(C[mask]).query(C, distance_upper_bound=bound)
    d[mask] = 0.0
    return d


def head_share(C, joint, faces=None, chin=None, face_only=False, face=None, band=HEAD_BAND,
               neck_base=NECK_BASE, neck_rise=NECK_RISE, cut=None, keep_chin=False, chin_base=False,
               jaw_angle=None, angle_estimated=False):
    """The head's share of each vertex (module docstring): (n,) in [0, 1].

    Parameters
    ----------
    C : (n, 3) float
        Canonical vertices (head sizes, +Y up, +Z front).
    joint : (3,) float
        The head joint (the pivot); the boundary runs through it.
    faces : (m, 3) int, optional
        Triangles: the neck base is measured on the vertices they use.
    chin : (float, float), optional
        The menton's height and the chin's front depth: in front of the pivot the boundary descends
        to ``CHIN_MARGIN`` under that point (its slope kept between 0.3 and 2); default slope 1.
    face_only : bool
        A face-only mesh: its face turns with the head down to its lowest vertices (the chin of a
        mask, when ``chin`` is not above the neck base); a neck below the chin keeps its base still.
    face : (n,) float, optional
        1 on the facial mask falling to 0 across its band: the face turns with the head wherever
        it hangs (a long muzzle below any boundary through the pivot).
    band : float
        Half-width of the blend across the boundary, head sizes (at most ``BAND_SHARE`` of the
        height from the neck base to the joint).
    neck_base, neck_rise : float
        See the module docstring.
    cut : ((3,) float, (3,) float), optional
        A planar neck cut's centre and unit normal (pointing out of the mesh, canonical frame;
        :func:`autobones.cut_cues.cut_cues`): the vertices within ``neck_base`` of the height from it
        are neck base too, the head's share rising over the next ``neck_rise`` of the way to the
        joint. A cut slanted to the head's up (an animal's neck leaves its skull backwards: the
        cow's by 39 degrees) puts some of its edge above the lowest heights, which a head turn then
        dragged.
    keep_chin : bool
        The face keeps its share down to the chin (``chin``'s height, fading over ``CHIN_MARGIN``
        below it) even inside the neck base: a measured menton (``transfer``'s landmark) is on the
        jaw, whose weight must stay there, while the lowest ``neck_base`` of the vertices of a face
        far denser than its neck reach above it (ICT: 0.03 head sizes). With ``chin_base`` (either
        one), such a base drops to the lower ``DENSE_BASE`` of the neck under the chin (not on a
        face-only mesh).
    jaw_angle : (float, float), optional
        The gonions' height (the lower) and depth (their mean): in front of the pivot the boundary
        also passes ``ANGLE_MARGIN`` half-bands under the angle and from there along the mandible's
        lower border to under the chin, so the angle turns with the head (:func:`_under_jaw`); under
        a low angle the share rises from the neck base's top.
    angle_estimated : bool
        ``jaw_angle`` is an estimate (``place``'s, from the proportions of human heads), not a landmark:
        the boundary under it stays two half-bands above the neck base, so the share is 0 a half-band
        above the base. Down to the base itself (a landmark's angle may lie there), a short neck under a
        low estimate turned its base by 2.6-7.7 % of the peak motion on a head turn in the frame of the
        head's landmarks (the SMPL man's, cut 0.1 head sizes under his angle: the zoo's check 3).
    chin_base : bool
        The face's share rises from under the chin (``chin``'s height less ``CHIN_MARGIN``, or the
        neck base when that is lower) to whole at the chin, never inside the lowest ``neck_base`` of
        the height or of the height above a planar ``cut``: ``place``'s estimated menton (0.01-0.04
        head sizes under the landmarked one on the shared human heads; on some animals the step of
        the throat into the neck, 0.16-0.43 under the chin: the ogre, the chess knight), which
        unlike a measured one does not hold the face's share up inside those bases.
    """
    C = np.asarray(C, dtype=np.float64)
    y, z = C[:, 1], C[:, 2]
    used = y if faces is None or len(faces) == 0 else y[used_vertices(np.asarray(faces), len(C))]
    yj, zj = float(joint[1]), float(joint[2])
    base = min(neck_base_height(used, neck_base), yj - 1e-6)
    lowest = min(float(used.min()) + neck_base * float(np.ptp(used)), yj - 1e-6)   # the lowest share of the height
    if chin is not None and (keep_chin or chin_base) and not face_only and base > chin[0] - CHIN_MARGIN:
        # the lowest share of the vertices reaches the chin (a face far denser than its neck): no neck's base,
        # which is then the lower half of the neck under the chin, the rest of it bending
        base = max(lowest, min(base, lowest + DENSE_BASE * (chin[0] - lowest)))
    half = max(min(band, BAND_SHARE * (yj - base)), 1e-6)
    across = _across(y, z, yj, zj, chin, jaw_angle, half, floor=base + 2.0 * half if angle_estimated else -np.inf)
    face_base = face is not None and chin_base and chin is not None and not face_only
    slant, slant_face = _cut_rises(C, joint, None if face_only else cut, float(np.ptp(used)), neck_base, neck_rise,
                                   chin if face_base else None)
    rise = smoothstep((y - base) / max(neck_rise * (yj - base), 1e-12)) * slant
    if jaw_angle is not None and chin is not None:
        # the angle turns with the head (the boundary passes under it, :func:`_across`); the rise under a
        # low angle (a big animal jaw) starts no lower than the neck base
        ya = float(jaw_angle[0])
        a0 = max(base, ya - (1.0 + ANGLE_MARGIN) * half)   # never in the neck base
        if ya > a0:
            rise = np.maximum(rise, smoothstep((y - a0) / (ya - a0)) * slant)
    share = smoothstep((across + half) / (2.0 * half)) * rise
    if face_base:
        # the face's own base stops under the chin and its share is whole at the chin: the lowest share
        # of the vertices reaches above the chin on a face far denser than its neck (ICT: 0.04 head
        # sizes) or a neck cut close under it, and there, or rising over the neck's height, the chin
        # stayed behind on a head turn (share 0.0-0.6 on ICT's and the SMPL bodies' mentons). The
        # lowest share of the height, and of the height above a planar cut, stay still
        b0 = max(lowest, min(base, chin[0] - CHIN_MARGIN))
        rise = smoothstep((y - b0) / max(chin[0] - b0, CHIN_MARGIN / 4)) * slant_face
    if face is not None:
        # a face-only mesh's lowest vertices are its chin, which turns with the head, unless a neck
        # hangs below the chin (James' scan runs 0.18 of its height further down: its face's band
        # reached the neck's base and a head turn moved it 3.8% of the peak); a neck's base is still
        # even where the face's band reaches it
        whole = face_only and (chin is None or chin[0] - CHIN_MARGIN <= base)
        if not whole and keep_chin and chin is not None:
            rise = np.maximum(rise, smoothstep((y - chin[0]) / CHIN_MARGIN + 1.0))
        share = np.maximum(share, face if whole else face * rise)
    return share


def _cut_rises(C, joint, cut, height, neck_base, neck_rise, chin=None):
    """((n,), (n,)): the share's rise above a planar neck ``cut`` (centre, outward normal; None: none),
    0 within ``neck_base`` of the mesh's ``height`` from it and whole ``neck_rise`` of the way from there
    to the ``joint``; and the face's, whole at the ``chin`` (height, depth; None: the share's), never
    inside the cut's own base."""
    ones = np.ones(len(C))
    if cut is None:
        return ones, ones
    centre, normal = np.asarray(cut[0], dtype=np.float64), np.asarray(cut[1], dtype=np.float64)
    above = (C - centre) @ -normal
    top = float((np.asarray(joint, dtype=np.float64) - centre) @ -normal)
    low = neck_base * height
    if top <= low:
        return ones, ones
    slant = smoothstep((above - low) / max(neck_rise * (top - low), 1e-12))
    if chin is None:
        return slant, ones
    chin_above = float((np.array([0.0, chin[0], chin[1]]) - centre) @ -normal)
    l0 = max(0.0, min(low, chin_above - CHIN_MARGIN))
    return slant, smoothstep((above - l0) / max(chin_above - l0, CHIN_MARGIN / 4))


def _across(y, z, yj, zj, chin, jaw_angle, half, floor=-np.inf):
    """(n,) each point's signed distance from the boundary in the midline plane (``y`` height, ``z``
    depth; positive above it), so the band is ``half`` wide across the boundary everywhere: measured
    vertically, it thinned where the boundary falls steeply (in front of the pivot, down to under the
    jaw's angle) into a seam a head turn creased (ICT's neck).

    The boundary is level with the pivot ``(yj, zj)`` behind it and descends in front to
    ``CHIN_MARGIN`` under the ``chin`` (height, depth; slope 1 without it, kept within 2), the bend
    rounded (softplus). Given the ``jaw_angle`` too, it runs no higher than :func:`_under_jaw`: a line
    from the pivot to the chin passed over the mandible's angle (gonion share 0.0-0.45 on 26 of the 27
    landmarked shared heads), which then stayed with the neck and the jaw folded along its border on a
    head turn. That piece runs no lower than ``floor`` (height). The curve is sampled every ``half / 40``
    along its length (one k-d tree query per point)."""
    slope = 1.0
    if chin is not None:
        slope = float(np.clip((yj - (chin[0] - CHIN_MARGIN)) / max(chin[1] - zj, ROUND), -2.0, 2.0))

    def height(zz):
        b = yj - slope * ROUND * np.logaddexp(0.0, (zz - zj) / ROUND)
        if jaw_angle is None or chin is None:
            return b
        return np.minimum(b, np.maximum(_under_jaw(zz, yj, zj, jaw_angle, chin, half), floor))

    # the curve sampled evenly along its length (a steep stretch sampled evenly in depth left gaps); the
    # samples capped at ``SAMPLES``: a band a millionth of the head wide (a pivot on the neck base's top)
    # asked for billions, which no shared head's band comes near (head sizes 0.03-0.1: 2,000-20,000)
    lo, hi = float(z.min()) - 4.0 * half, float(z.max()) + 4.0 * half
    zz = np.arange(lo, hi, max(half / 400.0, (hi - lo) / SAMPLES))
    curve = np.column_stack([zz, height(zz)])
    length = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(curve, axis=0), axis=1))]
    at = np.arange(0.0, length[-1], max(half / 40.0, length[-1] / SAMPLES))
    curve = np.column_stack([np.interp(at, length, curve[:, 0]), np.interp(at, length, curve[:, 1])])
    d, _ = cKDTree(curve).query(np.column_stack([z, y]))
    return np.where(y >= height(z), d, -d)


def _under_jaw(z, yj, zj, angle, chin, half):
    """(n,) the boundary under the mandible's lower border: from the pivot down to ``ANGLE_MARGIN *
    half`` under the jaw's angle (``angle``: the gonions' height and depth), then along the border to
    ``CHIN_MARGIN`` under the chin (``chin``: height, depth), so the angle turns with the head."""
    yg, zg = float(angle[0]) - ANGLE_MARGIN * half, float(angle[1])
    yc, zc = float(chin[0]) - CHIN_MARGIN, float(chin[1])
    down = (yj - yg) / max(zg - zj, ROUND)
    to_angle = yj - down * ROUND * np.logaddexp(0.0, (z - zj) / ROUND)
    along = yg + (z - zg) * (yc - yg) / max(zc - zg, ROUND)
    return np.maximum(to_angle, along)


def smooth_share(share, C, F, rings=SMOOTH_RINGS, weld_tol=1e-6):
    """``share`` (n,) averaged over its mesh neighbours ``rings`` times, its zeros kept (a new array).

    The share's bands are set in head sizes; on a coarse mesh (a 2k-vertex robot, a statue whose
    jaw reaches the neck base) a band one or two edges wide steps a carried jaw weight by up to 1
    across an edge. Jacobi steps of the uniform graph Laplacian widen every step to a few edges
    whatever the mesh's resolution, and the vertices at 0 (the neck base, the nape below the
    boundary) stay 0, so the base stays still. Coincident vertices (seams of an unwelded mesh,
    ``C`` canonical, welded within ``weld_tol`` head sizes) are one node, so no seam opens.
    """
    from scipy.sparse import coo_matrix

    from .topology import mesh_edges, weld

    share = np.asarray(share, dtype=np.float64)
    if rings <= 0 or len(F) == 0:
        return share.copy()
    _, Fw, index = weld(np.asarray(C, dtype=np.float64), np.asarray(F), weld_tol)
    k = int(index.max()) + 1
    E = mesh_edges(Fw)
    A = coo_matrix((np.ones(2 * len(E)), (np.r_[E[:, 0], E[:, 1]], np.r_[E[:, 1], E[:, 0]])), shape=(k, k)).tocsr()
    deg = np.asarray(A.sum(axis=1)).ravel()
    u = np.zeros(k)
    np.maximum.at(u, index, share)    # a welded node takes its highest copy (copies agree but for rounding)
    fixed = u <= STILL
    for _ in range(rings):
        # only ever lowered: a share near the base never rises toward a turning neighbour
        u = np.where(fixed | (deg == 0), u, np.minimum(u, 0.5 * u + 0.5 * (A @ u) / np.maximum(deg, 1.0)))
    return u[index]


def apply_head_share(W, share, neck=0, head=1):
    """Give each row of ``W`` (n, b) the head side ``share`` (n,) (module docstring); in place, returned.

    ``neck`` and ``head`` are the columns of the neck bone and of the head bone; every other column
    is the head's side (the head's children: jaw, eyes, facial bones). Rows must be non-negative
    and sum to one; they still do after.
    """
    n, b = W.shape
    others = np.array([j for j in range(b) if j != neck], dtype=np.int64)
    head_col = int(np.flatnonzero(others == head)[0])
    for s in range(0, n, CHUNK):
        blk, h = W[s:s + CHUNK][:, others], share[s:s + CHUNK]
        total = blk.sum(axis=1)
        # too much weight above the share: all scaled down alike; too little: the head bone takes the
        # rest (scaling the children up would steepen their own steps beyond the weights')
        over = total > h
        blk[over] *= (h[over] / total[over])[:, None]
        blk[~over, head_col] += (h - total)[~over]
        W[s:s + CHUNK, others] = blk
        W[s:s + CHUNK, neck] = 1.0 - h
    return W
