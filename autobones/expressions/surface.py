"""The skin surface the expression model works on: welded graph, skin vertices, normals, operators.

Every graph operation of the model (smoothing, diffusion, unfolding) runs on the mesh welded by
position, so heads split along UV seams behave as one surface; per-vertex results are read back
through ``index``. The weld happens only when the mesh falls apart without it: welding would
also join eyelashes, eye-occlusion shells and teeth that merely touch the skin.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..geometry.areas import triangle_areas
from ..geometry.laplacian import factor_spd, laplacian
from ..geometry.normals import triangle_normals, vertex_normals
from ..geometry.topology import mesh_parts, weld


@dataclass
class SkinSurface:
    """The skin of one head, canonical frame (+Y up, +Z front), head sizes.

    n vertices of the mesh, nw of the welded mesh (nw = n when nothing was welded).

    Attributes
    ----------
    index : (n,) int64
        Welded vertex of each vertex.
    first : (nw,) int64
        A vertex of each welded vertex (its last in mesh order).
    vertices : (nw, 3) float
        Welded positions.
    faces : (mw, 3) int64
        Welded faces.
    part : (n,) int
        Connected part (of the welded mesh) of each vertex.
    skin : (n,) bool
        The largest part by area, minus what is bound to an eye bone (weight >= 0.5).
    normals : (n, 3) float
        Unit vertex normals.
    skull_normals : (n, 3) float
        Normals smoothed over about a centimetre: the directions of the offset skull.
    adjacency : scipy.sparse.csr_matrix (nw, nw)
        Edge counts between welded vertices.
    skin_welded : (nw,) bool
        ``skin`` on the welded mesh.
    skin_faces : (ms, 3) int64
        Welded faces with all corners on the skin and a non-degenerate area.
    rest_normals : (ms, 3) float
        Unnormalised rest normals of ``skin_faces`` (twice the area).
    rest_areas : (ms,) float
        Rest areas of ``skin_faces`` (head sizes squared).
    laplacian, mass : scipy.sparse (nw, nw)
        Intrinsic (Delaunay) Laplacian and lumped mass of the welded mesh.
    relax_weights : scipy.sparse.csr_matrix (nw, nw)
        The Laplacian's non-negative off-diagonal weights (the unfolding averages over them).
    relax_degree : (nw,) float
        Row sums of ``relax_weights``.
    """

    index: np.ndarray
    first: np.ndarray
    vertices: np.ndarray
    faces: np.ndarray
    part: np.ndarray
    skin: np.ndarray
    normals: np.ndarray
    skull_normals: np.ndarray
    adjacency: sp.csr_matrix
    skin_welded: np.ndarray
    skin_faces: np.ndarray
    rest_normals: np.ndarray
    rest_areas: np.ndarray
    laplacian: sp.spmatrix
    mass: sp.spmatrix
    relax_weights: sp.csr_matrix
    relax_degree: np.ndarray
    _factors: dict = field(default=None, repr=False, compare=False)

    def diffuse(self, u, t):
        """Per-vertex field ``u`` (n,) or (n, k) after one heat step over time ``t`` (head sizes
        squared) on the welded mesh (:func:`~autobones.geometry.laplacian.diffuse`), read back to
        every vertex."""
        solve = None if self._factors is None else self._factors.get(float(t))
        if solve is None:
            solve = factor_spd(self.mass + t * self.laplacian)
            if self._factors is not None:
                self._factors[float(t)] = solve
        return solve(self.mass @ u[self.first])[self.index]

    @contextmanager
    def sharing_factors(self):
        """Within the block, diffusions over the same time share one factorisation (the lid weights
        and the lids' hinge share: 4 s on a 213k-vertex scan); the factors are dropped after it,
        since each holds many times the mesh's memory."""
        self._factors = {}
        try:
            yield self
        finally:
            self._factors = None


def weld_if_split(V, F):
    """The mesh welded by position when no connected part holds a fifth of its area.

    ``V`` (n, 3) float, ``F`` (m, 3) int64. Returns ``(Vw, Fw, index, first)``: welded vertices
    (nw, 3) and faces, the welded vertex (n,) of each vertex and a vertex (nw,) of each welded
    one; ``V``, ``F`` and the identity when the mesh holds together.
    """
    n = len(V)
    face_area = triangle_areas(V, F)
    part0 = mesh_parts(n, F)
    if np.bincount(part0[F[:, 0]], weights=face_area, minlength=n).max() >= 0.2 * face_area.sum():
        Vw, Fw, index = V, F, np.arange(n)
    else:
        Vw, Fw, index = weld(V, F, 1e-9 * max(float(np.ptp(V, axis=0).max()), 1e-300))
    first = np.zeros(len(Vw), dtype=np.int64)
    first[index] = np.arange(n)
    return Vw, Fw, index, first


def skin_surface(V, F, eye_weights, smoothing_passes):
    """The :class:`SkinSurface` of a head.

    Parameters
    ----------
    V : (n, 3) float
        Vertices, canonical frame, head sizes.
    F : (m, 3) int64
        Faces.
    eye_weights : list of (n,) float
        Skin weights of the eye bones (vertices with 0.5 or more on one are not skin).
    smoothing_passes : int
        Neighbour-sum passes smoothing the skull directions (each reaches one ring further).
    """
    Vw, Fw, index, first = weld_if_split(V, F)
    nw = len(Vw)
    part_w = mesh_parts(nw, Fw)
    part = part_w[index]
    skin = part == int(np.argmax(np.bincount(part_w[Fw[:, 0]], weights=triangle_areas(Vw, Fw), minlength=nw)))
    for w in eye_weights:
        skin &= w < 0.5
    Nw = vertex_normals(Vw, Fw)
    E0 = np.concatenate([Fw[:, [0, 1]], Fw[:, [1, 2]], Fw[:, [2, 0]]])
    A0 = sp.csr_matrix((np.ones(2 * len(E0)), (np.r_[E0[:, 0], E0[:, 1]], np.r_[E0[:, 1], E0[:, 0]])), shape=(nw, nw))
    skin_w = np.zeros(nw, dtype=bool)
    skin_w[index[skin]] = True
    Fs = Fw[skin_w[Fw].all(axis=1)]
    a_s = triangle_areas(Vw, Fs)
    Fs = Fs[a_s > 1e-9 * max(float(np.median(a_s)) if len(a_s) else 0.0, 1e-300)]
    n0 = triangle_normals(Vw, Fs)
    # the offset skull is smooth: its directions are the skin normals smoothed over ~1 cm
    Ns = Nw.copy()
    for _ in range(int(smoothing_passes)):
        Ns = A0 @ Ns + Ns
    Ns /= np.maximum(np.linalg.norm(Ns, axis=1, keepdims=True), 1e-300)
    Lp, M = laplacian(Vw, Fw)
    # the unfolding averages over the intrinsic (Delaunay) Laplacian's non-negative weights: a
    # plain neighbour mean drags the tiny triangles of mouth corners along with big ones
    Wu = (sp.diags(Lp.diagonal()) - Lp).tocsr()
    Wu.data = np.maximum(Wu.data, 0.0)
    Wu.eliminate_zeros()
    return SkinSurface(index=index, first=first, vertices=Vw, faces=Fw, part=part, skin=skin, normals=Nw[index],
                       skull_normals=Ns[index], adjacency=A0.tocsr(), skin_welded=skin_w, skin_faces=Fs,
                       rest_normals=n0, rest_areas=0.5 * np.linalg.norm(n0, axis=1), laplacian=Lp, mass=M,
                       relax_weights=Wu, relax_degree=np.asarray(Wu.sum(axis=1)).ravel())
