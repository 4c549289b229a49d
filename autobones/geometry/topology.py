"""Connectivity of triangle meshes: edges, boundary, connected parts, welding coincident vertices."""
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .areas import triangle_areas


def sorted_unique(a):
    """``np.unique`` of an int array ``(k,)`` -> sorted ``(u,)``, by one sort: numpy 2.4's default hash
    path is 30-60x slower on the hundreds of thousands of edge keys of a scan."""
    a = np.sort(np.asarray(a).ravel())
    return a[np.r_[True, a[1:] != a[:-1]]] if len(a) else a


def used_vertices(F, n=None):
    """Sorted indices ``(u,)`` int64 of the vertices some triangle of ``F`` ``(m, 3)`` uses (``n``: vertex count)."""
    F = np.asarray(F, dtype=np.int64).ravel()
    return np.flatnonzero(np.bincount(F, minlength=n or 0)) if len(F) else np.zeros(0, dtype=np.int64)


def distinct_faces(F):
    """``F`` ``(m, 3)`` int without its repeated triangles (the same three vertices in any order: a
    double-sided export's back faces, a triangle written twice), the first of each kept, in order;
    ``F`` itself when none repeats. Repeats count twice in every area-weighted sample and make each
    of their edges look non-manifold."""
    F = np.asarray(F, dtype=np.int64)
    if len(F) < 2:
        return F
    S = np.sort(F, axis=1)
    order = np.lexsort((S[:, 2], S[:, 1], S[:, 0]))
    S = S[order]
    repeat = np.r_[False, (S[1:] == S[:-1]).all(axis=1)]
    if not repeat.any():
        return F
    keep = np.ones(len(F), dtype=bool)
    keep[order[repeat]] = False   # the stable sort puts the first occurrence first
    return F[keep]


def mesh_edges(F):
    """Unique undirected edges ``(e, 2)`` int64 of triangles ``F`` ``(m, 3)``, with ``i < j``."""
    F = np.asarray(F, dtype=np.int64)
    a = np.concatenate([F[:, 0], F[:, 1], F[:, 2]])
    b = np.concatenate([F[:, 1], F[:, 2], F[:, 0]])
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    n = int(hi.max()) + 1 if len(hi) else 1
    key = sorted_unique(lo * n + hi)
    return np.stack([key // n, key % n], axis=1)


def mesh_parts(n, F):
    """Connected component label ``(n,)`` of each of ``n`` vertices (vertices in no face get their own)."""
    F = np.asarray(F, dtype=np.int64)
    # repeated edges only add up in the matrix: no need to make them unique
    a, b = F.ravel(), F[:, [1, 2, 0]].ravel()
    A = sp.csr_matrix((np.ones(len(a), dtype=np.int8), (a, b)), shape=(n, n))
    return connected_components(A, directed=False)[1]


def part_areas(V, F):
    """Connected parts of a mesh and their areas.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int

    Returns
    -------
    part : (n,) int
        Each vertex's part (:func:`mesh_parts`; a face's part is its first vertex's).
    area : (k,) float
        Each part's area, mesh units squared.
    """
    V, F = np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64)
    part = mesh_parts(len(V), F)
    return part, np.bincount(part[F[:, 0]], weights=triangle_areas(V, F), minlength=int(part.max()) + 1 if len(part) else 1)


# a part beside the skin (the widest part, when it covers SKIN_LEAD times the next) covering SHELL of
# the area and reaching SPREAD of the mesh's radius from its own centre (hair, a beard) is left out of
# the frame. The shared heads' other parts: ICT's mouth 0.085 of the area (0.11-0.13 in ICT cut into a
# mask, but reaching 0.29-0.30: a lump inside), eyeballs 0.018; the robot's 0.075 and less; hair copies
# (benchmarks/accessories.py) 0.17-0.48, reaching 0.45-0.98. A lump set on the head (a hat: a ball of
# 0.15 head sizes on the crown, 0.11-0.15 of the area) reaches less, but lies outside the skin's convex
# hull, which a lump inside (the mouth) does not: left out too, when at most half the skin's area (it
# turned 20 of the 35 shared heads more than 30 degrees; benchmarks/accessories.py --kinds hat). A
# face mask under a wig as large has no clear skin: nothing is left out.
SHELL = 0.1
SKIN_LEAD = 1.3
SPREAD = 0.4


def without_large_parts(V, F, share=SHELL, lead=SKIN_LEAD, reach=SPREAD):
    """``F`` without the large parts beside the widest one (:func:`large_parts`): the rows kept, in their
    order, ``F`` itself when none is dropped."""
    F = np.asarray(F)
    drop, _ = large_parts(V, F, share, lead, reach)
    return F[~drop] if drop.any() else F


def large_parts(V, F, share=SHELL, lead=SKIN_LEAD, reach=SPREAD, lump_lead=2.0):
    """The large parts beside the widest one: connected parts (after :func:`weld_by_size`) other than
    the one with the largest area that cover ``share`` of the area or more and either reach ``reach`` of
    the mesh's radius or more from their own centre (the largest distance of a vertex from the
    centroid; a part spread over the mesh, hair) or lie mostly outside the widest part's convex hull
    while the widest covers ``lump_lead`` times their area or more (a lump set on it, a hat; not a lump
    inside it, a mouth, nor a head modelled apart from the body it sits on, whose piece below the cut
    is not much wider: the held-out dwarf's 0.40 of the area against its head's 0.28), when the widest
    covers at least ``lead`` times the next (else, with no clear main part, none).

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    share, lead, reach, lump_lead : float

    Returns
    -------
    drop : (m,) bool
        The triangles on such parts.
    part : (m,) int64
        Each triangle's connected part.
    """
    F = np.asarray(F)
    none = np.zeros(len(F), dtype=bool)
    if not len(F):
        return none, np.zeros(0, dtype=np.int64)
    Vw, Fw, index = weld_by_size(np.asarray(V, dtype=np.float64), F)
    part, area = part_areas(Vw, Fw)
    face_part = part[index[F[:, 0]]].astype(np.int64)
    if len(area) < 2:
        return none, face_part
    first, second = np.argsort(area)[::-1][:2]
    if area[first] < lead * area[second]:
        return none, face_part
    drop = area >= share * area.sum()
    drop[first] = False
    used = np.zeros(len(Vw), dtype=bool)
    used[used_vertices(Fw, len(Vw))] = True
    radius = lambda P: float(np.sqrt(((P - P.mean(axis=0)) ** 2).sum(axis=1).max()))
    whole = radius(Vw[used])
    hull = []   # the widest part's, built once, when a candidate first needs it
    for k in np.flatnonzero(drop):
        P = Vw[used & (part == k)]
        if radius(P) >= reach * whole:
            continue
        if area[first] >= lump_lead * area[k]:
            hull = hull or [_hull(Vw[used & (part == first)])]
            drop[k] = _outside_hull(hull[0], P) > 0.5
        else:
            drop[k] = False
    return drop[face_part], face_part


def _hull(H):
    """(facet planes (f, 4), tolerance) of the convex hull of the points ``H`` (h, 3), or None when
    ``H`` is flat."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        return ConvexHull(H).equations, 1e-9 * float(np.ptp(H, axis=0).max())
    except QhullError:
        return None


def _outside_hull(hull, P):
    """Share of the points ``P`` (k, 3) outside ``hull`` (:func:`_hull`); 0 when it is None (flat)."""
    if hull is None:
        return 0.0
    planes, tol = hull
    return float(((P @ planes[:, :3].T + planes[:, 3]) > tol).any(axis=1).mean())


def weld_by_size(V, F, share=2e-6):
    """:func:`weld` with a tolerance of ``share`` of the used vertices' largest distance from their
    centroid: free of the file's unit and axes (a turned or scaled copy welds alike)."""
    h = V[used_vertices(F, len(V))]
    return weld(V, F, share * np.sqrt(((h - h.mean(axis=0)) ** 2).sum(axis=1).max()))


def largest_part(V, F):
    """The largest connected part (most vertices) of a mesh as a mesh of its own.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int

    Returns
    -------
    Vs : (k, 3) float
        Its vertices, in their order in ``V``.
    Fs : (m', 3) int64
        Its triangles, indexing ``Vs``.
    index : (k,) int64
        Where each of ``Vs`` is in ``V``.
    """
    F = np.asarray(F, dtype=np.int64)
    part = mesh_parts(len(V), F)
    index = np.flatnonzero(part == np.argmax(np.bincount(part)))
    return (*submesh(V, F, index), index)


def submesh(V, F, index):
    """The vertices ``index`` (k,) int of a mesh ``V`` (n, 3), ``F`` (m, 3) as a mesh of their own: ``V[index]``
    (k, 3) and the triangles of ``F`` whose three corners are among them, renumbered (m', 3) int64."""
    F = np.asarray(F, dtype=np.int64)
    remap = np.full(len(V), -1, dtype=np.int64)
    remap[index] = np.arange(len(index))
    Fs = remap[F]
    return np.asarray(V)[index], Fs[(Fs >= 0).all(axis=1)]


def boundary_vertices(n, F):
    """Boolean ``(n,)``: the vertex lies on an edge used by exactly one triangle."""
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    E.sort(axis=1)
    key = E[:, 0] * n + E[:, 1]
    u, count = np.unique(key, return_counts=True)
    b = u[count == 1]
    out = np.zeros(n, dtype=bool)
    out[b // n] = True
    out[b % n] = True
    return out


def weld(V, F, tol):
    """Merge vertices closer than ``tol`` (mesh units) by rounding to a grid of that size.

    Returns
    -------
    Vw : (k, 3) float
        Welded vertices (the first input vertex of each grid cell).
    Fw : (m', 3) int
        Faces on ``Vw``; faces that collapsed are removed.
    index : (n,) int
        Welded vertex of each input vertex.
    """
    key = np.round(V / tol).astype(np.int64)
    # cells in lexicographic order, each welded vertex the first input vertex of its cell (what
    # np.unique(key, axis=0) gives, without its slow sort of structured rows)
    lo = key.min(axis=0) if len(key) else np.zeros(3, dtype=np.int64)
    span = (key.max(axis=0) - lo + 1) if len(key) else np.ones(3, dtype=np.int64)
    if int(span[0]) * int(span[1]) * int(span[2]) < 2 ** 62:
        # one int64 per cell in the same lexicographic order: a stable argsort of it is the
        # lexsort's order at a third of its cost on a scan
        cell = ((key[:, 0] - lo[0]) * span[1] + (key[:, 1] - lo[1])) * span[2] + (key[:, 2] - lo[2])
        order = np.argsort(cell, kind="stable")
        c = cell[order]
        new_cell = np.r_[True, c[1:] != c[:-1]] if len(c) else np.zeros(0, dtype=bool)
    else:
        order = np.lexsort(key.T[::-1])
        k = key[order]
        new_cell = np.r_[True, (k[1:] != k[:-1]).any(axis=1)] if len(k) else np.zeros(0, dtype=bool)
    first = order[new_cell]
    index = np.empty(len(V), dtype=np.int64)
    index[order] = np.cumsum(new_cell) - 1
    Vw = V[first]
    Fw = index[F]
    ok = (Fw[:, 0] != Fw[:, 1]) & (Fw[:, 1] != Fw[:, 2]) & (Fw[:, 0] != Fw[:, 2])
    return Vw, Fw[ok], index
