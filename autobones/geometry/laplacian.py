"""The mesh Laplacian, heat diffusion, and one solver for the symmetric positive definite systems they give.

The Laplacian is the intrinsic Delaunay one of ``robust_laplacian`` (Sharp & Crane, "A Laplacian
for nonmanifold triangle meshes", 2020): it stays an M-matrix on non-manifold, badly shaped and
unwelded meshes, where the cotangent Laplacian goes negative.
"""
import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from ..errors import AutobonesError
from .normals import cross_rows

try:  # optional extra `autobones[cholmod]`: a supernodal Cholesky, faster again on large meshes
    from sksparse.cholmod import cholesky as _cholmod
except ImportError:  # pragma: no cover - exercised when scikit-sparse is absent (the default install)
    _cholmod = None


def laplacian(V, F):
    """Intrinsic Delaunay Laplacian ``L`` (n, n) (positive semi-definite) and lumped mass ``M``
    (n, n) diagonal, in mesh units (``M`` in squared units), as scipy sparse matrices."""
    import robust_laplacian

    try:
        return robust_laplacian.mesh_laplacian(np.ascontiguousarray(V), np.ascontiguousarray(F))
    except RuntimeError as exc:  # geometry-central's assertions (e.g. an unreferenced vertex)
        raise AutobonesError(f"mesh: the surface Laplacian failed on this mesh ({exc})") from None


def clipped_cotangent_laplacian(V, F, floor=1e-6):
    """Cotangent Laplacian ``L`` (n, n), positive semi-definite, with every edge weight kept positive.

    The cotangent weight of an edge goes negative opposite obtuse angles (irregular scans have
    many); here it is clipped to ``floor`` times the mean positive weight, so ``L`` is an M-matrix
    (a harmonic fill stays within its boundary values) and no edge is cut loose. About ten times
    faster than :func:`laplacian`'s intrinsic Delaunay rebuild, and within a few 1e-6 of it on
    harmonic fills of scans (measured on a 134k-vertex bust); kept for fills, where that suffices.

    Parameters
    ----------
    V : (n, 3) float
        Vertices, any unit.
    F : (m, 3) int
        Triangles; degenerate (zero-area) triangles give their edges the floor weight.

    Returns
    -------
    scipy.sparse.csr_matrix (n, n)
        Unitless (a cotangent is a ratio): row sums 0, off-diagonals < 0.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    n = len(V)
    rows, cols, vals = [], [], []
    for k in range(3):
        i, j, o = F[:, (k + 1) % 3], F[:, (k + 2) % 3], F[:, k]
        a, b = V[i] - V[o], V[j] - V[o]
        dot = a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]
        c = cross_rows(a, b)
        area2 = np.sqrt(c[:, 0] * c[:, 0] + c[:, 1] * c[:, 1] + c[:, 2] * c[:, 2])
        rows += [i, j]
        cols += [j, i]
        w = np.where(area2 > 0, 0.5 * dot / np.where(area2 > 0, area2, 1.0), 0.0)
        vals += [w, w]
    W = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
    W.sum_duplicates()
    positive = W.data[W.data > 0]
    W.data = np.maximum(W.data, floor * (positive.mean() if len(positive) else 1.0))
    return (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W).tocsr()


ORDERINGS = {
    # SuperLU's default column ordering: the fastest measured on bone-heat systems of 26k-420k vertex
    # scans (benchmarks/solver.py), and the one every solve but the correspondence fit used before
    "colamd": dict(permc_spec="COLAMD"),
    # minimum degree on A + A^T in symmetric mode, no pivoting: a third less fill, but its ordering
    # step blows up on large meshes (a 420k-vertex bone-heat system: 362 s against 10 s for COLAMD)
    "mmd_symmetric": dict(permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True)),
}


def factor_spd(A, ordering="colamd", use_cholmod=None):
    """Factor a sparse symmetric positive definite ``A`` (n, n) once; return ``solve(b)``.

    ``b`` is (n,) or (n, k); the solution has its shape, so one factorisation serves every
    right-hand side (all bones, all fields). ``ordering`` picks SuperLU's fill-reducing ordering
    (a key of :data:`ORDERINGS`). With scikit-sparse installed (the ``[cholmod]`` extra) and
    ``use_cholmod`` None or True, CHOLMOD's supernodal Cholesky is used instead, whatever the
    ordering; its round-off differs from SuperLU's at about 1e-13 relative, so results are
    bit-identical only between runs of the same install.
    """
    A = sp.csc_matrix(A)
    if _cholmod is not None and use_cholmod is not False:
        return _cholmod(A)
    return splu(A, **ORDERINGS[ordering]).solve


def diffuse(u, L, M, t):
    """One implicit heat step ``(M + t L) u' = M u`` of a field ``u`` (n,) or (n, k) over time
    ``t`` (squared mesh units: the field spreads over about ``sqrt(t)``)."""
    return factor_spd(M + t * L)(M @ u)
