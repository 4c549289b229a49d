"""A welded, and for large meshes coarser, copy of a mesh for solves and queries whose answer is
smooth at the coarse scale (bone heat, inside tests, closest surface points)."""
from dataclasses import dataclass

import numpy as np

from .topology import mesh_parts, weld


def decimate_parts(V, F, max_vertices, min_part_vertices=500):
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
        Vd, Fd = _simplify(V[idx], Fl, 1.0 - ratio)
        Vs.append(Vd)
        Fs.append(Fd + offset)
        labels.append(np.full(len(Fd), p, dtype=np.int64))
        offset += len(Vd)
    return np.concatenate(Vs), np.concatenate(Fs), part, np.concatenate(labels), kept


def _simplify(V, F, reduction):
    """``fast_simplification`` of one part (V (n, 3), F (m, 3)) by ``reduction`` of its triangles ->
    (Vd, Fd int64). Not threaded: the library keeps its mesh in process-global arrays."""
    import fast_simplification

    Vd, Fd = fast_simplification.simplify(V, F.astype(np.int32), target_reduction=reduction)
    return np.asarray(Vd, dtype=np.float64), np.asarray(Fd, dtype=np.int64)


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
