"""Smooth skin weights by heat diffusion from the bones over the surface.

The bone-placement method of ``place`` (end of its §3.2) asks for smooth skinning: every vertex influenced by
several bones, weights summing to one. We use the bone-heat equilibrium of
Baran and Popovic (Pinocchio, 2007): for each bone j solve

    (L + M H) w_j = M H p_j

with L the surface Laplacian, M the lumped mass matrix, H = diag(1 / d^2) the
heat each vertex receives from its nearest bone at distance d, and p_j = 1
where bone j is the nearest. The weights sum to one exactly (the p_j do) and
are non-negative because the Laplacian is an M-matrix.

Where Blender's bone heat gives up (non-manifold edges, holes, separate parts,
unwelded faces), three choices keep this one working:
- vertices are welded by position before diffusion, so faces that only touch
  at copies of the same point still pass heat (unwelded low-poly heads);
- the Laplacian is the intrinsic Delaunay one of ``robust_laplacian`` (Sharp
  and Crane 2020), which stays an M-matrix on non-manifold and badly shaped
  meshes, where the cotangent Laplacian gives negative weights;
- every vertex receives some heat (no visibility test), so each separate part
  (eyes, teeth) is solved from its own nearest bones and the system is never
  singular.
One sparse LU factorisation serves all bones; nothing is n x n dense. Large meshes are
solved on a quadric-decimated proxy and the weights interpolated back (see ``PROXY_VERTICES``).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..geometry.closest import closest_points
from ..geometry.proxy import mesh_proxy
from ..geometry.laplacian import factor_spd, laplacian
from ..geometry.weights import prune_weights

CHUNK = 65536


def segment_distances(P, segments):
    """Distance from points to bone segments.

    Parameters
    ----------
    P : (n, 3) float
        Points.
    segments : (b, 2, 3) float
        Bone heads and tails, same frame and units as ``P``.

    Returns
    -------
    D : (n, b) float
    """
    A, B = segments[:, 0], segments[:, 1]
    AB = B - A
    L2 = np.maximum((AB ** 2).sum(axis=1), 1e-300)
    out = np.empty((len(P), len(segments)))
    # coordinate by coordinate on (n, b) arrays, summed x, y, z in that order: the same numbers as
    # sums over a length-3 axis, which numpy reduces slowly
    for s in range(0, len(P), CHUNK):
        X = [P[s:s + CHUNK, k:k + 1] for k in range(3)]
        D = [X[k] - A[:, k] for k in range(3)]
        t = np.clip((D[0] * AB[:, 0] + D[1] * AB[:, 1] + D[2] * AB[:, 2]) / L2, 0.0, 1.0)
        E = [X[k] - (A[:, k] + t * AB[:, k]) for k in range(3)]
        out[s:s + CHUNK] = np.sqrt(E[0] * E[0] + E[1] * E[1] + E[2] * E[2])
    return out


# Above PROXY_ABOVE (welded) vertices the heat system is solved on a decimated proxy of about
# PROXY_VERTICES and carried up: the weights are smooth at a scale of many edges, and the exact
# solve grows faster than linearly (factorisation fill). Meshes up to PROXY_ABOVE (ICT's 26.7k,
# the 53k template) are solved exactly, as before. Sizes and their error: benchmarks/place.py.
PROXY_ABOVE = 60000
PROXY_VERTICES = 25000
WELD_TOL = 1e-6  # canonical units (head sizes)


def bone_heat_weights(V, F, segments, weld_tol=WELD_TOL, prune=0.01, heat=1.0, max_vertices=PROXY_ABOVE,
                      proxy=None):
    """Skin weights of every vertex for every bone.

    Parameters
    ----------
    V : (n, 3) float
        Vertices; best in canonical units (head sizes) so ``weld_tol`` is relative.
    F : (m, 3) int
        Triangles; may be non-manifold, holed, unwelded or in several parts.
    segments : (b, 2, 3) float
        Bone heads and tails, same frame as ``V``.
    weld_tol : float
        Vertices closer than this share heat (same units as ``V``).
    prune : float
        Weights below this fraction of the vertex's largest weight are set to
        zero and the rest renormalised.
    heat : float
        Scale of the heat each vertex receives from its nearest bone.
    max_vertices : int or None
        Meshes with more welded vertices are solved on a quadric-decimated proxy of about
        ``PROXY_VERTICES`` (each connected part decimated on its own) and the weights carried
        up barycentrically from each vertex's closest proxy point on its own part; None always
        solves on the whole mesh.
    proxy : MeshProxy, optional
        :func:`autobones.geometry.proxy.mesh_proxy` of ``(V, F)`` when the caller has it
        (``weld_tol`` and ``max_vertices`` are then its own).

    Returns
    -------
    W : (n, b) float64
        Weights >= 0, each row summing to 1; unreferenced vertices copy the
        weights of the nearest referenced vertex.
    """
    segments = np.asarray(segments, dtype=np.float64)
    if proxy is None:
        proxy = mesh_proxy(V, F, weld_tol, above=max_vertices, vertices=PROXY_VERTICES)
    Vu, Fu = proxy.vertices, proxy.faces
    Wu = _heat(Vu, Fu, segments, heat) if proxy.coarse is None else _carry_up(Vu, proxy.coarse, segments, heat)
    if prune > 0:  # heat has long thin tails: a facial bone should not tug at the scalp
        for s in range(0, len(Wu), CHUNK):  # in place, a block at a time: no second (n, b) array
            Wu[s:s + CHUNK] = prune_weights(Wu[s:s + CHUNK], prune)
    loose = proxy.index < 0
    if loose.any():  # loose vertices: the weights of the nearest surface vertex
        from scipy.spatial import cKDTree

        _, j = cKDTree(Vu).query(np.asarray(V, dtype=np.float64)[loose])
        out = np.empty((len(V), len(segments)))
        out[~loose] = Wu[proxy.index[~loose]]
        out[loose] = Wu[j]
        return out
    if len(Wu) == len(V) and np.array_equal(proxy.index, np.arange(len(V))):
        return Wu  # nothing was welded (most scans): no copy
    return Wu[proxy.index]


def _heat(V, F, segments, heat, ordering="colamd"):
    """Bone heat (n, b), rows summing to one, solved on the whole of a welded mesh (every vertex used)
    with :func:`~autobones.geometry.laplacian.factor_spd` and that ``ordering``."""
    L, M = laplacian(V, F)
    D = segment_distances(V, segments)
    dmin = D.min(axis=1)
    scale = np.median(dmin[dmin > 0]) if (dmin > 0).any() else 1.0
    dmin = np.maximum(dmin, 1e-3 * scale)
    nearest = D <= (D.min(axis=1, keepdims=True) * (1 + 1e-9) + 1e-15)
    Pn = nearest / nearest.sum(axis=1, keepdims=True)
    mh = heat * M.diagonal() / dmin ** 2
    A = (L + sp.diags(mh)).tocsc()
    # a component where every vertex has zero mass (degenerate faces only) would be singular
    A = A + sp.diags(np.where(mh > 0, 0.0, 1.0))
    rhs = mh[:, None] * Pn
    rhs[mh <= 0] = Pn[mh <= 0]
    W = factor_spd(A, ordering=ordering)(rhs)
    W = np.clip(W, 0.0, None)
    W /= np.maximum(W.sum(axis=1, keepdims=True), 1e-300)
    return W


def _carry_up(V, coarse, segments, heat):
    """Bone heat (n, b) solved on the decimated proxy ``coarse`` of ``V`` and interpolated at each
    vertex's closest proxy point on the vertex's own part (so eyes and teeth keep their own weights)."""
    Vp, Fp, part, face_part, kept = coarse
    # minimum degree in symmetric mode: on decimated meshes half COLAMD's fill and a 2-5x faster
    # solve for all bones; its ordering step only blows up far above the proxy's size
    Wp = _heat(Vp, Fp, segments, heat, ordering="mmd_symmetric" if len(Vp) <= PROXY_ABOVE else "colamd")
    whole = kept >= 0
    rest = np.flatnonzero(~whole)
    carried = None
    if len(rest):
        _, face, bary, _ = closest_points(V[rest], Vp, Fp, labels=part[rest], face_labels=face_part)
        # one sparse (rest, proxy) interpolation matrix, three entries a row in corner order: its
        # product sums b0 W0 + b1 W1 + b2 W2, with no (n, 3, b) temporaries
        interp = sp.csr_matrix((bary.ravel(), Fp[face].ravel(), np.arange(0, 3 * len(rest) + 1, 3)),
                               shape=(len(rest), len(Vp)))
        carried = interp @ Wp
        if len(rest) == len(V):
            return carried  # every part decimated (most scans): no second (n, b) array
    W = np.empty((len(V), len(segments)))
    W[whole] = Wp[kept[whole]]
    if carried is not None:
        W[rest] = carried
    return W
