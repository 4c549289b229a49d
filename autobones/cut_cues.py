"""What a cut looks like on a head mesh: its open rim, its main cut loop, how open the surface is,
and how much a direction's far end looks cut. Cues for :mod:`autobones.orient`'s up and front.

Goes beyond the papers we implement (they take upright heads): a neck cut or a bust base marks
the bottom, a face-only capture's opening its back. Input-frame arrays in, arrays and floats out;
nothing here depends on the frame, so a head turned or scaled gives the same cues turned or scaled.
"""
from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from .geometry.normals import triangle_normals
from .geometry.topology import used_vertices, weld_by_size

# an open-rim loop shorter than this times the square root of the surface's area is a hole, never a
# cut (the shared heads' neck cuts and bust bases: 0.70-3.2; the robot's bolt holes 0.05, the menpo
# template's mouth 0.46)
HOLE = 0.5
# a loop at the far end of the surface from the main one is a second cut when it is at least this share
# of the main loop's length (a missing crown against the neck's cut: 0.7-1.4)
FAR_SHARE = 0.5
# rim edges tested for cracks at a time: (CHUNK, 65) candidates, ~100 MB at most
CHUNK = 1 << 16


def cut_cues(V, F):
    """What a cut looks like, computed once: face centroids, unit normals and areas, and the
    open rim (edges with one face, after welding by position so unwelded meshes have none
    spurious) as midpoints, lengths and the loop each belongs to (``rim_loop``), and the main
    loop (:func:`_main_loop`)."""
    cross = triangle_normals(V, F)
    area2 = np.linalg.norm(cross, axis=1)
    normal = np.divide(cross, area2[:, None], out=np.zeros_like(cross), where=area2[:, None] > 0)
    heights = V[used_vertices(F, len(V))]
    Vw, Fw, _ = weld_by_size(V, F)
    # edge keys (low * n + high); an open-rim edge is one whose key occurs once
    a, b = Fw.T.ravel(), Fw[:, [1, 2, 0]].T.ravel()
    key = np.sort(np.minimum(a, b) * len(Vw) + np.maximum(a, b))
    once = np.r_[True, key[1:] != key[:-1]] & np.r_[key[1:] != key[:-1], True]
    rim = np.column_stack([key[once] // len(Vw), key[once] % len(Vw)])
    rim = rim[~crack_edges(Vw, rim)]
    if len(rim):
        graph = coo_matrix((np.ones(len(rim)), (rim[:, 0], rim[:, 1])), shape=(len(Vw), len(Vw)))
        loop = connected_components(graph, directed=False)[1][rim[:, 0]]
    else:
        loop = np.zeros(0, dtype=np.int64)
    cues = {"centroid": (V[F[:, 0]] + V[F[:, 1]] + V[F[:, 2]]) / 3.0, "normal": normal, "area2": area2, "heights": heights,
            "rim_mid": 0.5 * (Vw[rim[:, 0]] + Vw[rim[:, 1]]),
            "rim_length": np.linalg.norm(Vw[rim[:, 0]] - Vw[rim[:, 1]], axis=1), "rim_loop": loop}
    cues.update(_main_loop(cues))
    return cues


def crack_edges(V, rim, neighbours=(8, 64), tol=1e-3):
    """(r,) bool: the open-rim edges ``rim`` (r, 2) of ``V`` (n, 3) that lie along another rim edge: both
    sides of a crack, where a triangle split without its neighbour (a T-junction) leaves the long edge
    and the two halves facing it unjoined though the surface is closed there. Such a crack is no
    hole; read as one, half the triangles of a head split so turned 12 of 19 shared heads 13-149
    degrees. An edge is on a crack when its midpoint lies within ``tol`` of its own length of one of
    the rim edges whose midpoints are nearest: the first ``neighbours`` for every edge, then more for
    those not yet found beside a crack (where many cracks meet, the partner is farther down the list)."""
    on = np.zeros(len(rim), dtype=bool)
    if len(rim) < 2:
        return on
    a, b = V[rim[:, 0]], V[rim[:, 1]]
    mid, length = 0.5 * (a + b), np.linalg.norm(b - a, axis=1)
    tree, todo = cKDTree(mid), np.arange(len(rim))
    for k in neighbours:
        k = min(k + 1, len(rim))
        found = [_on_near_edge(a, b, mid, length, tree, rows, k, tol)
                 for rows in np.array_split(todo, -(-len(todo) // CHUNK))]
        hit = np.concatenate([h for h, _ in found])
        on[todo[hit]] = True
        # looked at farther only beside a crack found: a mesh with no cracks costs one pass
        beside = np.concatenate([on[near].any(axis=1) for _, near in found])
        todo = todo[~hit & beside]
        if not len(todo):
            break
    return on


def _on_near_edge(a, b, mid, length, tree, rows, k, tol):
    """(len(rows),) bool: the midpoints of edges ``rows`` within ``tol`` of their length of one of the
    other edges among their ``k`` nearest (``tree`` over the midpoints; edges from ``a`` to ``b``), and
    those (len(rows), k) nearest edges."""
    _, near = tree.query(mid[rows], k=k)                 # (t, k), the edge itself among them
    d = b[near] - a[near]                                 # (t, k, 3) candidate edges
    dd = np.maximum(np.einsum("tkc,tkc->tk", d, d), 1e-300)
    t = np.einsum("tkc,tkc->tk", mid[rows, None, :] - a[near], d) / dd
    gap = np.linalg.norm(a[near] + np.clip(t, 0.0, 1.0)[..., None] * d - mid[rows, None, :], axis=2)
    return ((gap <= tol * length[rows, None]) & (near != rows[:, None]) & (length[near] > 0)).any(axis=1), near


def midline_cuts(cues, normal, offset):
    """``cues`` with only the open-rim loops that may be cuts, the main loop found again among them:
    those that reach across the symmetry plane ``normal . x = offset`` (unit ``normal`` (3,)) and
    are at least ``HOLE`` times the square root of the surface's area long.

    A cut (a neck cut, a bust base, a face capture's opening) crosses the midline; a hole that
    does not is one of a mirrored pair (eye sockets, open eyeballs, ears, nostrils), however long
    its rim, and a short one on the midline is a mouth or a bolt hole. Blender's Suzanne has only
    mirrored holes: its eye sockets, in the lowest tenth along its back, read as a cut there and
    laid it face down (up 160 degrees off)."""
    side = cues["rim_mid"] @ normal - offset
    loop = cues["rim_loop"]
    if not len(loop):
        return cues
    lo = np.full(loop.max() + 1, np.inf)
    hi = np.full(loop.max() + 1, -np.inf)
    np.minimum.at(lo, loop, side)
    np.maximum.at(hi, loop, side)
    length = np.bincount(loop, weights=cues["rim_length"])
    keep = (lo[loop] < 0.0) & (hi[loop] > 0.0) & (length[loop] >= HOLE * np.sqrt(cues["area2"].sum() / 2.0))
    if keep.all():
        return cues
    out = dict(cues, rim_mid=cues["rim_mid"][keep], rim_length=cues["rim_length"][keep], rim_loop=loop[keep])
    out.update(_main_loop(out))
    return out


def _main_loop(cues):
    """The longest open-rim loop (``cues["rim_loop"]`` labels the rim edges) as a cut: its length,
    its best-fit plane's unit normal pointing away from the surface (toward the missing cap) and
    how far its points stray from that plane, over the loop's RMS radius; and the far loop
    (:func:`_far_loop`), when the surface is open at its other end too.

    A neck cut or a bust base is a planar loop (every zoo head cut at the neck: 0.00-0.02 of
    the extent); a face-only capture's rim follows the face's outline round to the ears
    (0.13-0.27), and eye or mouth holes are short loops of their own."""
    none = {"loop_length": 0.0, "loop_normal": None, "loop_flatness": np.inf, "loop_centre": None, "far_loop": None}
    edge_comp = cues["rim_loop"]
    if not len(edge_comp):
        return none
    lengths = np.bincount(edge_comp, weights=cues["rim_length"])
    best = int(np.argmax(lengths))  # ties: the lowest label, a function of the vertex order only
    surface_mid = cues["area2"] @ cues["centroid"] / max(cues["area2"].sum(), 1e-300)
    main = _loop_plane(cues, best, surface_mid)
    return {"loop_length": float(lengths[best]), "loop_normal": main[0], "loop_flatness": main[1],
            "loop_centre": main[2], "far_loop": _far_loop(cues, lengths, best, main, surface_mid)}


def _loop_plane(cues, label, surface_mid):
    """One rim loop's best-fit plane: (unit normal (3,) pointing away from the surface's area
    centroid ``surface_mid``, flatness (RMS off the plane over the in-plane RMS radius), centre (3,))."""
    pts = cues["rim_mid"][cues["rim_loop"] == label]
    w = cues["rim_length"][cues["rim_loop"] == label]
    mid = w @ pts / w.sum()
    d = pts - mid
    d = d / max(float(np.abs(d).max()), 1e-300)  # unit-free: moments of a head in 1e150 units overflowed
    evals, evecs = np.linalg.eigh((d * w[:, None]).T @ d / w.sum())
    normal = evecs[:, 0]
    normal = normal if (mid - surface_mid) @ normal >= 0 else -normal
    flatness = float(np.sqrt(max(evals[0], 0.0)) / max(np.sqrt(evals[1] + evals[2]), 1e-300))
    return normal, flatness, mid


def _far_loop(cues, lengths, best, main, surface_mid):
    """The longest other loop at the surface's far end from the main one, as ``{"length", "normal",
    "flatness", "centre"}``, or None: at least ``FAR_SHARE`` of the main loop's length, beyond the
    surface's centroid on the other side, facing the other way (normals more than 135 degrees apart).

    A head open at both ends is a band: a neck cut and a missing crown (scans that did not capture
    the hair), the longer of the two either (benchmarks/accessories.py: the crown's loop 0.7-1.4 of
    the neck's). Read as the only cut, the main loop stood such heads on their crowns. A mouth or a
    cyclops' eye hole on the midline lies near the centroid and faces forward (ICT's mouth and the
    ogre's eye: 0.05 and 0.08 of the surface's square-root area off it), no far loop."""
    normal, _, centre = main
    reach = (centre - surface_mid) @ normal
    far = None
    for label in np.argsort(-lengths, kind="stable"):
        if label == best or lengths[label] < FAR_SHARE * lengths[best]:
            continue
        n2, flat2, c2 = _loop_plane(cues, label, surface_mid)
        if n2 @ normal < -np.cos(np.radians(45.0)) and (c2 - surface_mid) @ normal < -0.5 * reach:
            far = {"length": float(lengths[label]), "normal": n2, "flatness": flat2, "centre": c2}
            break
    return far


def bottom_cut(cues, up):
    """``cues`` with its main loop the cut at the bottom along ``up`` (unit (3,)): the far loop's
    (:func:`_far_loop`) when the main one lies at the top (a missing crown longer than the neck's
    cut), else ``cues`` as they are."""
    far = cues.get("far_loop")
    if far is None or cues["loop_normal"] @ up <= far["normal"] @ up:
        return cues
    return dict(cues, loop_length=far["length"], loop_normal=far["normal"], loop_flatness=far["flatness"],
                loop_centre=far["centre"], far_loop=None)


def open_shell_facing(cues):
    """The direction an open surface faces (unit (3,)) and how open it is (its vector area over
    its area, 0 for a closed surface, up to 1 for a flat sheet).

    A closed surface's area-weighted normals sum to zero; an open one's sum to the vector area of
    its missing cap, pointing away from the opening (or toward it, when the triangles wind inward:
    the sign is taken from which way the surface bulges from its open rim). A neck cut leaves a small cap (ICT's full head:
    13% of the surface's area, the bust and full heads of the shared set less), a face-only capture
    a cap as large as its face (a head cut in half behind the ears: 28-50%, a face scan 43-64%).
    """
    vec = (cues["normal"] * cues["area2"][:, None]).sum(axis=0)
    size = np.linalg.norm(vec)
    if len(cues["rim_length"]) and cues["rim_length"].sum() > 0:
        # the sign from the shape, not the winding (scans come with inward normals too: fran_cut):
        # the surface bulges away from its opening
        bulge = (cues["area2"] @ cues["centroid"] / max(cues["area2"].sum(), 1e-300)
                 - cues["rim_length"] @ cues["rim_mid"] / cues["rim_length"].sum())
        vec = -vec if bulge @ vec < 0 else vec
    return vec / max(size, 1e-300), float(size / max(cues["area2"].sum(), 1e-300))


def base_score(cues, up):
    """How strongly the mesh's lowest tenth along ``up`` looks like a cut: flat area facing
    down plus open boundary rim, relative to the whole surface."""
    h_v = cues["heights"] @ up
    lo, hi = h_v.min(), h_v.max()
    bottom = (cues["centroid"] @ up - lo) / (hi - lo) < 0.1
    flat = (cues["normal"] @ -up) > np.cos(np.radians(20))
    area2 = cues["area2"]
    flat_part = area2[bottom & flat].sum() / area2.sum()
    low_rim = (cues["rim_mid"] @ up - lo) / (hi - lo) < 0.1
    rim_part = cues["rim_length"][low_rim].sum() / np.sqrt(area2.sum() / 2)
    return float(flat_part + 0.05 * rim_part)


def cap_score(cues, up, depth=0.02, tilt=15.0):
    """How much of the surface is a flat cap at the far end of ``-up``: the area of the faces facing
    ``-up`` within ``tilt`` degrees and lying within ``depth`` of the height from the lowest vertex,
    over the whole area. A closed bust's base (a plane capping the cut) has no open rim for
    :func:`base_score` to see, and its flat-facing area alone can be matched by a long flat slope
    elsewhere (the goat's nose bridge: 0.055 against its base's 0.044); a cap lies all at one level,
    at the extreme (the goat's base 0.042, any other direction of it or of the zoo's heads 0.00-0.03)."""
    h_v = cues["heights"] @ up
    lo, hi = h_v.min(), h_v.max()
    bottom = (cues["centroid"] @ up - lo) / max(hi - lo, 1e-300) < depth
    flat = (cues["normal"] @ -up) > np.cos(np.radians(tilt))
    return float(cues["area2"][bottom & flat].sum() / max(cues["area2"].sum(), 1e-300))


def is_planar_cut(cues, min_length=0.5, max_flatness=0.12):
    """Whether the main rim loop is a planar cut long enough to be a neck cut or a bust base: at
    least ``min_length`` times the square root of the surface's area (the zoo's neck cuts: 0.9-3.2,
    an eye hole far less) and no further from its plane than ``max_flatness`` of its radius (neck
    cuts 0.00-0.05, ICT's 0.08-0.09; face-only captures' outlines 0.17-0.32)."""
    if cues["loop_normal"] is None:
        return False
    area = cues["area2"].sum() / 2.0
    return cues["loop_length"] >= min_length * np.sqrt(area) and cues["loop_flatness"] < max_flatness


def cut_up_front(P, normal, offset, cues, slab=0.02):
    """Up and front (unit (3,), input frame) from a planar neck cut, for a head that looks like no
    human face: up is the cut's far side turned into the symmetry plane ``normal . x = offset``;
    front is the way the midline profile (sample points ``P`` within ``slab`` of the plane, in
    head sizes) reaches farther past the cut's centre. Every vertebrate's spine enters the skull
    at its base, behind the jaw, so the face or snout overhangs the neck farther than the back of
    the skull does (zoo animals with the landmarks' frame: 0.52-0.74 of the two reaches). Then
    front turns onto the line from the profile's most posterior point to its most anterior one,
    clear of the neck (as opisthocranion -> pronasale), and up with it. Also returns that share
    (0.5-1), how clear the front was."""
    d = cues["loop_normal"]
    up = -d + (d @ normal) * normal
    up /= np.linalg.norm(up)
    front = np.cross(normal, up)
    # the head size along the plane's own axes, not the file's (a turned copy measures the same)
    size = np.ptp(P @ np.array([normal, up, front]).T, axis=0).max()
    profile = P[np.abs(P @ normal - offset) < slab * size]
    reach = (profile - cues["loop_centre"]) @ front
    ahead, behind = max(reach.max(), 0.0), max(-reach.min(), 0.0)
    share = ahead / max(ahead + behind, 1e-300)
    front, share = (front, share) if share >= 0.5 else (-front, 1.0 - share)
    # the landmarks' own front, opisthocranion -> pronasale: the profile's most anterior and most
    # posterior points clear of the neck (a cut slants with the neck: the cow's by 39 degrees)
    head = profile[(profile - cues["loop_centre"]) @ -d > 0.1 * size]
    if len(head) >= 2:
        chord = head[np.argmax(head @ front)] - head[np.argmin(head @ front)]
        chord -= (chord @ normal) * normal
        if np.linalg.norm(chord) > 0:
            front = chord / np.linalg.norm(chord)
            up = np.cross(front, normal)
            up *= np.sign(up @ -d) or 1.0
    return up, front, share
