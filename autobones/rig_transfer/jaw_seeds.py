"""The mouth read from a head's landmarks, and the seeds of the jaw repair
(:func:`autobones.rig_transfer.jaw.repair_jaw`): which vertices the landmarks say go with the jaw
(1) and which stay on the skull (0), and which edges cross the lip line (the one place the jaw
weight may step).

The mouth surface is the plane through ``stomion`` and both ``cheilion``, bent in front of the
stomion when the named chin and nose landmarks there lie on the wrong side of it: on a long snout
whose lips meet at a tip ahead of the stomion (the camel: the ``pogonion`` 0.07 face units ahead of
the stomion and 0.02 above the plane, the ``pronasale`` 0.05 above it) the plane put the chin on the
upper lip's side, and the repair pinned it to 0. The bend (:func:`_front_lift`) is a lift that grows
linearly from 0 at the stomion to its full height at the front landmarks, chosen to pass midway
between the highest lower and the lowest upper landmark there; on a human face (lower lip and chin
below the plane, nose above) it is 0 and nothing changes.

A vertex within ``tol`` of the mouth surface (:data:`ON_SURFACE` times the mouth landmarks'
coordinates: about 16 float32 rounding steps, 1-5e-6 face units on the shared heads, far below any
edge) is on it and counts as the lower lip's: hand-placed landmarks sit on vertices, so the stomion's vertex (and its mirror image) lies
exactly on the plane, and the rounding of its coordinates (a float32 glTF, a rotated copy) put it
on either side, moving which edges were the lip line (the cow: 6 edges stepping by 1.0 off the line
read back from the glb, none in memory).

Frames and units: the head's own (any frame, any unit); lengths in face units ``fu`` (the exocanthion
distance) unless stated. Arrays numpy; deterministic.
"""
from __future__ import annotations

import numpy as np

from ..geometry.topology import mesh_edges

ABOVE_MARGIN = 0.12     # fu above the jaw's top plane: jaw 0 there
CORNER = 0.06           # fu: edges this near a mouth corner belong to the lip line
OPEN = 0.5              # fu: how far off the mouth surface an edge crossing it between the lips may reach
ON_SURFACE = 1e-6       # of the mouth landmarks' coordinates: this near the mouth surface is on it (~16 float32 ulps)
STEADY = 0.3            # half-widths: a stomion nearer the corners' line tilts the mouth plane at random
GAP_EDGES = 5           # edges between opposite seeds: 1 -> 0 in steps of at most 0.25 (< 0.27)
INNER_DEPTH = 0.5       # fu behind the corners' line: how deep a mouth interior is seeded
INNER_BAND = 0.25       # fu either side of the mouth plane
INNER_FACING = 0.7      # cos 45 degrees: a floor faces up across the plane, a roof down
# the menton is a lower seed (issue 31's check: jaw >= 0.9 there); on heads without a mouth (the
# robot) it is left to the carried weight, see :func:`seeds`
LOWER = ("pogonion", "labiale_inferius", "sublabiale", "menton")
UPPER = ("vertex", "opisthocranion", "glabella", "nasion", "pronasale", "subnasale", "labiale_superius",
         *(f"{n}_{s}" for n in ("exocanthion", "endocanthion", "palpebrale_superius", "palpebrale_inferius",
                                "brow_inner", "brow_middle", "brow_outer", "alare", "crista_philtri",
                                "zygion", "tragion", "superaurale", "subaurale", "frontotemporale")
           for s in ("l", "r")))
# the landmarks in front of the mouth that say where its surface runs at a snout's tip
FRONT_LOWER = ("pogonion", "labiale_inferius", "sublabiale")
FRONT_UPPER = ("pronasale", "subnasale", "labiale_superius")


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


def _front_lift(landmarks, frame):
    """(lift, at): how far the mouth surface rises (mesh units, along the normal; negative: sinks)
    at ``at`` (mesh units ahead of the stomion, along ``forward``) and beyond, so that the front
    lower landmarks lie below it and the upper ones above; (0, 1) when the plane already separates
    them, or no lift can (then the plane is kept)."""
    st, n, fwd = frame["stomion"], frame["normal"], frame["forward"]
    ahead = {k: float((landmarks[k] - st) @ fwd) for k in FRONT_LOWER + FRONT_UPPER if k in landmarks}
    ahead = {k: a for k, a in ahead.items() if a > 0}
    if not ahead:
        return 0.0, 1.0
    at = max(ahead.values())
    # the height each landmark asks of the full lift: its own height over its share of the ramp
    need = {k: float((landmarks[k] - st) @ n) * at / a for k, a in ahead.items()}
    lo = max((need[k] for k in FRONT_LOWER if k in need), default=-np.inf)
    hi = min((need[k] for k in FRONT_UPPER if k in need), default=np.inf)
    if (lo < 0 < hi) or not lo < hi:
        return 0.0, at
    if not np.isfinite(lo):
        return 0.0, at   # only upper landmarks, all above the plane: nothing to move
    if not np.isfinite(hi):
        return lo + 0.5 * abs(lo), at   # only lower ones: just above the highest
    return 0.5 * (lo + hi), at


def _face_up(lm, st):
    """(3,) from the stomion ``st`` toward the upper face: the ``nasion`` (else the ``glabella``,
    else the upper landmarks' mean), or None."""
    for name in ("nasion", "glabella"):
        if name in lm:
            return lm[name] - st
    hint = _up_hint(lm)
    return None if hint is None else hint - st


def _steady_forward(lm, st, mid, lateral, forward, normal):
    """The mouth's (forward, normal) (3,) unit each, steadied where the stomion lies almost on the
    corners' line: the plane through the three then turns about that line with every tenth of a
    millimetre (the stuffed toy's stomion is 0.09 half-widths off it; its plane was 60 degrees off
    the face's and took the chin for the lips). Below :data:`STEADY` half-widths the direction from
    the stomion to the nasion (:func:`_face_up`, made orthogonal to the corners' line; 0-8 degrees
    from the mouth plane's normal on the human heads) takes over as the normal, fully at 0; human
    mouths (0.38-0.52 half-widths) and snouts (0.8-2) keep the plane of the three."""
    off = float(np.linalg.norm((st - mid) - ((st - mid) @ lateral) * lateral))
    half = 0.5 * float(np.linalg.norm(lm["cheilion_l"] - lm["cheilion_r"]))
    t = 1.0 - (off / (STEADY * half)) ** 2
    up = _face_up(lm, st)
    if t <= 0 or up is None:
        return forward, normal
    up = up - (up @ lateral) * lateral
    if np.linalg.norm(up) == 0:
        return forward, normal
    n = (1.0 - t) * normal + t * up / np.linalg.norm(up)
    n /= np.linalg.norm(n)
    f = np.cross(n, lateral)
    return (f if f @ forward >= 0 else -f), n


def mouth_frame(landmarks):
    """The mouth surface, or None without ``stomion`` and both ``cheilion``.

    Returns a dict: ``stomion`` (3,), ``normal`` (3,) unit, toward the upper face; ``lateral`` (3,)
    unit, right to left corner; ``forward`` (3,) unit, in the plane, from the corners' midpoint
    toward the stomion; ``mid`` (3,) the corners' midpoint; ``half_width`` (float) half the
    corner distance; ``lift`` and ``lift_at`` (float, mesh units): the surface's rise in front of
    the stomion (module doc, :func:`mouth_height`); ``tol`` (float, mesh units): how near the
    surface a vertex is on it.
    """
    if not all(n in landmarks for n in ("stomion", "cheilion_l", "cheilion_r")):
        return None
    lm = {k: np.asarray(v, dtype=np.float64) for k, v in landmarks.items()}
    st, cl, cr = lm["stomion"], lm["cheilion_l"], lm["cheilion_r"]
    normal = _plane(st, cl, cr, _up_hint(lm))
    if normal is None:
        return None
    lateral = (cl - cr) / np.linalg.norm(cl - cr)
    mid = 0.5 * (cl + cr)
    forward = np.cross(normal, lateral)
    if np.dot(st - mid, forward) < 0:
        forward = -forward
    forward, normal = _steady_forward(lm, st, mid, lateral, forward, normal)
    frame = dict(stomion=st, normal=normal, lateral=lateral, forward=forward, mid=mid,
                 half_width=0.5 * float(np.linalg.norm(cl - cr)))
    frame["lift"], frame["lift_at"] = _front_lift(lm, frame)
    # rounding the coordinates (a float32 glTF) must not move a vertex across the surface
    frame["tol"] = ON_SURFACE * max(float(np.abs(np.r_[st, cl, cr]).max()), 2.0 * frame["half_width"])
    return frame


def mouth_height(V, mouth):
    """(n,) signed height (mesh units) of the points ``V`` (n, 3) above the mouth surface of
    ``mouth`` (:func:`mouth_frame`): the plane's, less the lift ramped in front of the stomion."""
    d = np.asarray(V, dtype=np.float64) - mouth["stomion"]
    s = d @ mouth["normal"]
    if mouth.get("lift", 0.0):
        s = s - mouth["lift"] * np.clip((d @ mouth["forward"]) / mouth["lift_at"], 0.0, 1.0)
    return s


def _lip_sides(V, mouth, band, behind):
    """(n,) int8: +1 upper lip side, -1 lower lip side (on the surface, within ``mouth["tol"]``, included),
    0 elsewhere: vertices within ``band`` of the mouth surface, in front of the corners' line less
    ``behind`` and within the mouth's half-width plus ``behind`` of the midline (mesh units)."""
    d = V - mouth["mid"]
    s = mouth_height(V, mouth)
    zone = ((d @ mouth["forward"] > -behind) & (np.abs(d @ mouth["lateral"]) < mouth["half_width"] + behind)
            & (np.abs(s) < band))
    return np.where(zone, np.where(s > mouth["tol"], 1, -1), 0).astype(np.int8)


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
    s = (V - mouth["stomion"]) @ mouth["normal"]   # behind the corners' line: the lift is 0 there
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

    An edge is on the lip line when

    - it joins a vertex on or above the mouth surface (:func:`mouth_height`; ``stomion``, both
      ``cheilion``) to one on or below it (on: within the frame's ``tol``, :data:`ON_SURFACE`, so that
      rounding the coordinates does not move the line), both within 0.1 face units (two median
      edge lengths on a coarse head) of the surface and no further than that behind the corners'
      line or outside the corners;
    - or it crosses the surface between the corners and in front of their line with both ends
      within :data:`OPEN` face units of it (an open mouth on a coarse head: the edges from the
      upper lip into the mouth run down past the lower lip);
    - or it touches a vertex within :data:`CORNER` face units (at least two median edge lengths) of
      a mouth corner, where the weight turns from the upper lip's to the lower lip's in a ring or
      two whichever way an edge runs.

    All False without those three landmarks.
    ``V`` (n, 3), ``F`` (m, 3), ``landmarks`` name -> (3,), mesh units and frame.
    """
    V = np.asarray(V, dtype=np.float64)
    E = mesh_edges(np.asarray(F))
    mouth = mouth_frame(landmarks)
    if mouth is None:
        return E, np.zeros(len(E), dtype=bool)
    fu = face_unit(V, landmarks)
    d = V - mouth["mid"]
    s = mouth_height(V, mouth)
    length = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    h_edge = float(np.median(length)) if len(E) else 0.0
    # as wide as the repair's lip seeds reach on a coarse head (seed_band), with a margin
    band = max(0.1 * fu, 2.0 * h_edge)
    zone = ((d @ mouth["forward"] > -band) & (np.abs(d @ mouth["lateral"]) < mouth["half_width"] + band)
            & (np.abs(s) < band))
    tol = mouth["tol"]
    up, low = zone & (s > -tol), zone & (s <= tol)
    on_line = (up[E[:, 0]] & low[E[:, 1]]) | (low[E[:, 0]] & up[E[:, 1]])
    # an open mouth on a coarse head: an edge from the upper lip into the mouth, down past the
    # lower lip's seeds, crosses the surface between the lips with its ends farther off it
    sa, sb = s[E[:, 0]], s[E[:, 1]]
    cross = ((((sa > -tol) & (sb <= tol)) | ((sa <= tol) & (sb > -tol)))
             & (np.maximum(np.abs(sa), np.abs(sb)) < OPEN * fu))
    if cross.any():
        Ec, t = E[cross], np.clip(sa[cross] / np.where(sa[cross] != sb[cross], sa[cross] - sb[cross], 1.0), 0.0, 1.0)
        p = V[Ec[:, 0]] + t[:, None] * (V[Ec[:, 1]] - V[Ec[:, 0]]) - mouth["mid"]   # where it crosses
        on_line[np.flatnonzero(cross)] |= ((p @ mouth["forward"] > -band)
                                           & (np.abs(p @ mouth["lateral"]) < mouth["half_width"] + band))
    # the line's ends: around a mouth corner the weight turns from the upper lip's to the lower
    # lip's within a ring or two of edges, whichever way the edges run
    radius = max(CORNER * fu, 2.0 * h_edge)
    for name in ("cheilion_l", "cheilion_r"):
        d = V - np.asarray(landmarks[name], dtype=np.float64)
        near = np.einsum("ij,ij->i", d, d) < radius * radius
        on_line |= near[E[:, 0]] | near[E[:, 1]]
    return E, on_line


def jaw_note(landmarks):
    """What the landmarks cannot give the jaw repair (str, "" when nothing): without ``stomion``
    and both ``cheilion`` there is no lip line, so the jaw weight may step nowhere and a mouth
    opened by the jaw bone stretches the face between the chin and the nose instead of parting the
    lips; without them and any chin or lower lip landmark nothing pins the jaw either."""
    missing = [n for n in ("stomion", "cheilion_l", "cheilion_r") if n not in landmarks]
    if missing:
        pinned = "" if any(n in landmarks for n in LOWER) else ", and no chin landmark pins it"
        return f"no lip line (no {', '.join(missing)}): the jaw weight may step nowhere{pinned}"
    if mouth_frame(landmarks) is None:
        return "stomion and cheilions in one line: no mouth plane, no lip line"
    return ""


def seeds(V, F, E, on_line, landmarks, h, tree):
    """The repair's seeds (module doc of :mod:`autobones.rig_transfer.jaw`): ``(lower, upper,
    notes)``, (n,) bool each, jaw 1 and jaw 0, on the welded surface ``V`` (n, 3), ``F`` (m, 3),
    and the names (list of str) of the chin landmarks that had to yield. ``E`` (k, 2) its edges and
    ``on_line`` (k,) bool the lip line (:func:`lip_line_edges`), ``h`` (n,) each vertex's mean edge
    length and ``tree`` a ``cKDTree`` of ``V`` (mesh units).

    The landmarks, the lips on either side of the mouth surface and a mouth interior's floor and
    roof are firm seeds; a vertex firm seeds of both sides claim (a thin lip) is in neither. Seeds
    of the two sides fewer than :data:`GAP_EDGES` edges apart with no lip line between force a
    step, so the weaker one yields: the upper face (well above the jaw's top plane, a broad guess)
    near a firm lower seed (the ogre's and the beast's mouth floors lay 1-3 edges from vertices
    above the top plane through their stomion and gonions: steps of 0.46 on 13 and 21 edges), and a
    chin landmark near a firm upper seed (the robot's menton two edges below its nose tip, the cat's
    pogonion next to its nose with no mouth corners to draw a lip line): it keeps the carried
    weight, smoothed, and the note says so.
    """
    lm = landmarks
    fu = face_unit(V, lm)
    n = len(V)
    named_lower = np.zeros(n, dtype=bool)
    upper = np.zeros(n, dtype=bool)
    for names, mask in ((LOWER, named_lower), (UPPER, upper)):
        given = [lm[name] for name in names if name in lm]
        if given:
            mask[tree.query(np.array(given), workers=-1)[1]] = True
    lower = np.zeros(n, dtype=bool)
    mouth = mouth_frame(lm)
    if mouth is not None:
        # the lips on either side of the mouth surface, between the corners: the cut itself
        side = _lip_sides(V, mouth, seed_band(fu, float(np.median(h))), 0.0)
        upper |= side > 0
        lower |= side < 0
        # a mouth interior (ICT's, a game head's mouth bag): its floor goes with the jaw, its roof
        # stays; where floor and roof (or a lip of the other side) are a few edges apart (a coarse
        # head's open mouth: the beast decimated to 5k, 2-3 edges up its cheeks' inner walls) both
        # yield there and the walls fall off smoothly
        inner = inner_mouth_sides(V, F, lm)
        floor, roof = inner < 0, inner > 0
        floor_near = _rings(E, on_line, roof | upper, GAP_EDGES - 1)
        roof_near = _rings(E, on_line, floor | lower, GAP_EDGES - 1)
        upper |= roof & ~roof_near
        lower |= floor & ~floor_near
    notes = []
    # a chin landmark within a few edges of a firm upper seed, no lip line between: it yields
    near_upper = _rings(E, on_line, upper, GAP_EDGES - 1)
    for name in LOWER:
        if name in lm:
            i = int(tree.query(lm[name])[1])
            if near_upper[i] and not upper[i]:
                notes.append(name)
            else:
                lower[i] = True
    both = lower & upper
    lower &= ~both
    upper &= ~both
    # the broad upper face keeps its distance from the firm lower seeds
    above = _upper_face(V, lm, mouth, fu) & ~lower & ~upper & ~_rings(E, on_line, lower, GAP_EDGES - 1)
    return lower, upper | above, notes


def _rings(E, on_line, start, k):
    """(n,) bool: the vertices within ``k`` edges of ``start`` (n,) bool along the edges ``E``
    (m, 2) that are not on the lip line (``on_line`` (m,) bool)."""
    near = start.copy()
    Eo = E[~on_line]
    for _ in range(int(k)):
        near[Eo[near[Eo].any(axis=1)].ravel()] = True
    return near


def seed_band(fu, h_med):
    """How far (mesh units) from the mouth surface the lips are seeded: 0.05 face units, at least
    1.5 median edge lengths ``h_med`` (on a coarse head the lips' vertices lie farther off it)."""
    return max(0.05 * fu, 1.5 * h_med)


def _upper_face(V, lm, mouth, fu):
    """(n,) bool: vertices more than :data:`ABOVE_MARGIN` face units above the jaw's top plane
    (``stomion`` and both ``gonion``; without gonions the mouth plane): the upper face, the eyes,
    the skull; all False without a ``stomion``."""
    out = np.zeros(len(V), dtype=bool)
    if "stomion" not in lm:
        return out
    top = None
    if "gonion_l" in lm and "gonion_r" in lm:
        top = _plane(lm["stomion"], lm["gonion_l"], lm["gonion_r"], _up_hint(lm))
    if top is None and mouth is not None:
        top = mouth["normal"]
    if top is not None:
        out = (V - lm["stomion"]) @ top > ABOVE_MARGIN * fu
    return out
