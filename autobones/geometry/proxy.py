"""A welded, and for large meshes coarser, copy of a mesh for solves and queries whose answer is
smooth at the coarse scale (bone heat, inside tests, closest surface points)."""
import threading
from dataclasses import dataclass

import numpy as np

from .areas import triangle_areas
from .topology import mesh_parts, weld


def decimate_parts(V, F, max_vertices, min_part_vertices=500, quadric=True):
    """Quadric-decimate each connected part of a mesh to a common fraction of its vertices.

    Each part is decimated on its own (Garland & Heckbert 1997 quadrics, by
    ``fast_simplification``), so small separate parts (eyes, teeth) keep their shape and no
    part merges into or vanishes beside a larger one. Parts that would drop below
    ``min_part_vertices`` are kept whole.

    Parameters
    ----------
    V : (n, 3) float
        Vertices, any frame and unit; every vertex in some face.
    F : (m, 3) int
        Triangles.
    max_vertices : int
        About how many vertices the proxy should have (more when many small parts are kept).
    min_part_vertices : int
        Parts are decimated no further than this.
    quadric : bool
        False: vertex clustering only (:func:`cluster_vertices`), several times faster and coarser
        in shape; enough for pictures.

    Returns
    -------
    Vp : (k, 3) float64
        Proxy vertices: the kept parts' vertices first (``V`` itself when every part is kept),
        then each decimated part's.
    Fp : (mp, 3) int64
        Proxy triangles.
    part : (n,) int64
        Connected part of each input vertex.
    face_part : (mp,) int64
        Part of each proxy triangle (same labels as ``part``).
    kept : (n,) int64
        Proxy vertex of each input vertex whose part was kept whole, else -1.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    n = len(V)
    part = mesh_parts(n, F).astype(np.int64)
    kept = np.full(n, -1, dtype=np.int64)
    ratio = max_vertices / max(n, 1)
    sizes = np.bincount(part)
    face_of = part[F[:, 0]]
    whole = (sizes * ratio < min_part_vertices) | (ratio >= 1.0)
    Vs, Fs, labels = [], [], []
    offset = 0

    # the parts kept whole, in one piece (there may be many of them)
    keep_v = whole[part]
    if keep_v.any():
        idx = np.flatnonzero(keep_v)
        kept[idx] = np.arange(len(idx))
        keep_f = whole[face_of]
        Vs.append(V[idx])
        Fs.append(kept[F[keep_f]])
        labels.append(face_of[keep_f])
        offset = len(idx)
    # vertices and faces grouped by part once (each vertex's index within its part), not one
    # full-length mask per decimated part
    by_part = np.argsort(part, kind="stable")
    start = np.r_[0, np.cumsum(sizes)]
    local = np.empty(n, dtype=np.int64)
    local[by_part] = np.arange(n) - np.repeat(start[:-1], sizes)
    faces_by_part = np.argsort(face_of, kind="stable")
    face_start = np.r_[0, np.cumsum(np.bincount(face_of, minlength=len(sizes)))]
    for p in np.flatnonzero(~whole):
        idx = by_part[start[p]:start[p + 1]]
        Fl = local[F[faces_by_part[face_start[p]:face_start[p + 1]]]]
        Vd, Fd = _simplify(V[idx], Fl, 1.0 - ratio) if quadric else cluster_vertices(V[idx], Fl, ratio * len(idx))
        Vs.append(Vd)
        Fs.append(Fd + offset)
        labels.append(np.full(len(Fd), p, dtype=np.int64))
        offset += len(Vd)
    return np.concatenate(Vs), np.concatenate(Fs), part, np.concatenate(labels), kept


# A part with more than PRECLUSTER times its target vertex count is first vertex-clustered to
# that many: the quadric decimator's first passes over every face are most of its cost (3 s for a
# million faces), clustering is a few sorts, and at 8x the proxy's density the clusters are still
# much finer than the proxy's edges, so the quadrics decide its shape (benchmarks/place.py: on a
# 535k-vertex scan the weights move by 1.7e-4 on average, the joints not at all).
PRECLUSTER = 8


# fast_simplification keeps its mesh in process-global arrays: one decimation at a time in a process
# (transfer --arkit fits two correspondences, each with a decimated coarse copy, in two threads)
_SIMPLIFY = threading.Lock()


def quadric_simplify(V, F, reduction, agg=7):
    """``fast_simplification.simplify`` (Garland & Heckbert 1997 quadrics) of ``V`` (n, 3), ``F`` (m, 3)
    with ``target_reduction=reduction``, one call at a time: (Vd (k, 3), Fd (mk, 3)) as it returns them."""
    import fast_simplification

    with _SIMPLIFY:
        return fast_simplification.simplify(V, F, target_reduction=reduction, agg=agg)


def _simplify(V, F, reduction):
    """``fast_simplification`` of one part (V (n, 3), F (m, 3)) by ``reduction`` of its vertices ->
    (Vd, Fd int64). Not threaded: the library keeps its mesh in process-global arrays."""
    target = (1.0 - reduction) * len(V)
    if len(V) > PRECLUSTER * target:
        V, F = cluster_vertices(V, F, PRECLUSTER * target)
        reduction = max(0.0, 1.0 - target / max(len(V), 1))
    # aggressiveness 9 (the library's default is 7): a third faster on scans, and the heat weights on
    # the 134k scan's proxy are unchanged to the digits benchmarks/place.py reports against the exact solve
    Vd, Fd = quadric_simplify(V, F.astype(np.int32), reduction, agg=9)
    return np.asarray(Vd, dtype=np.float64), np.asarray(Fd, dtype=np.int64)


def cluster_vertices(V, F, vertices):
    """Vertex clustering (Rossignac & Borrel 1993): the vertices of each cell of a cubic grid merge
    into their mean, faces that collapse or repeat are dropped.

    Parameters
    ----------
    V : (n, 3) float
        Vertices, any frame and unit.
    F : (m, 3) int
        Triangles.
    vertices : float
        About how many vertices to keep; the cell size comes from the surface area and is grown
        until at most 1.3 times as many cells are occupied.

    Returns
    -------
    Vc : (k, 3) float64
        Cell means, in cell order (every one used by some face).
    Fc : (mc, 3) int64
        Triangles on ``Vc``, first occurrences in input order, none degenerate.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    lo = V.min(axis=0)
    h = np.sqrt(max(triangle_areas(V, F).sum(), 1e-300) / max(vertices, 1.0))
    for _ in range(8):
        key = np.floor((V - lo) / h).astype(np.int64)
        span = key.max(axis=0) + 1
        cell = (key[:, 0] * span[1] + key[:, 1]) * span[2] + key[:, 2]
        order = np.argsort(cell, kind="stable")
        c = cell[order]
        new = np.r_[True, c[1:] != c[:-1]]
        k = int(new.sum())
        if k <= 1.3 * vertices:
            break
        h *= np.sqrt(k / vertices)
    inv = np.empty(len(V), dtype=np.int64)
    inv[order] = np.cumsum(new) - 1
    count = np.bincount(inv, minlength=k)
    Vc = np.stack([np.bincount(inv, weights=V[:, j], minlength=k) for j in range(3)], axis=1) / count[:, None]
    Fc = inv[F]
    Fc = Fc[(Fc[:, 0] != Fc[:, 1]) & (Fc[:, 1] != Fc[:, 2]) & (Fc[:, 0] != Fc[:, 2])]
    s = np.sort(Fc, axis=1)
    tri = (s[:, 0] * k + s[:, 1]) * k + s[:, 2] if k < 2 ** 20 else None
    if tri is not None:
        by = np.argsort(tri, kind="stable")
        t = tri[by]
        Fc = Fc[np.sort(by[np.r_[True, t[1:] != t[:-1]]])]
    else:
        Fc = Fc[np.sort(np.unique(s, axis=0, return_index=True)[1])]
    used = np.zeros(k, dtype=bool)
    used[Fc.ravel()] = True
    remap = np.cumsum(used) - 1
    return Vc[used], remap[Fc]


@dataclass
class MeshProxy:
    """A mesh welded by position, unreferenced vertices dropped, and its decimated copy when large.

    Attributes
    ----------
    index : (n,) int64
        Welded vertex of each input vertex (``-1``: in no triangle).
    vertices, faces : (k, 3) float64, (m', 3) int64
        The welded mesh (every vertex used).
    coarse : tuple or None
        ``(Vp, Fp, part, face_part, kept)`` of :func:`decimate_parts` on the welded mesh, or None
        when it has at most ``above`` vertices.
    """

    index: np.ndarray
    vertices: np.ndarray
    faces: np.ndarray
    coarse: tuple = None

    @property
    def coarse_surface(self):
        """(Vp, Fp) of the coarse mesh, or None when the mesh was small enough to keep."""
        return None if self.coarse is None else self.coarse[:2]


def mesh_proxy(V, F, weld_tol, above=None, vertices=None):
    """Weld ``V`` (n, 3) / ``F`` (m, 3) at ``weld_tol`` (mesh units), drop unreferenced vertices, and
    when more than ``above`` (None: never) remain, decimate to about ``vertices`` (default
    ``above``) with :func:`decimate_parts`. Returns a :class:`MeshProxy`."""
    V = np.asarray(V, dtype=np.float64)
    Vw, Fw, index = weld(V, F, weld_tol)
    used = np.zeros(len(Vw), dtype=bool)
    used[Fw.ravel()] = True
    remap = np.where(used, np.cumsum(used) - 1, -1)
    Vu, Fu = Vw[used], remap[Fw]
    coarse = None
    if above is not None and len(Vu) > above:
        coarse = decimate_parts(Vu, Fu, vertices or above)
    return MeshProxy(index=remap[index], vertices=Vu, faces=Fu, coarse=coarse)
