"""Which way a head's triangles face: wound consistently within each part and outward as a whole.

Exporters write heads inside out (a negative scale baked into the file, a scan's inward normals:
``fran_cut`` in the shared data), and the pipeline reads the winding where it reads normals: the
winding number that keeps joints inside the head, the dense correspondence's normal matching, the
expression model's skull under the skin, the rendered views the landmark detector reads. An inside-out
copy of a head was rigged differently from the head (``benchmarks/zoo.py``'s ``flip`` copies:
``transfer``'s correspondence p95 5-131 % of ex-ex off on 19 of 22 heads, ``place``'s frame 32-154
degrees off on three). The pipeline works on :func:`outward_faces`; the rigs keep the user's triangles.
"""
import numpy as np

from .normals import triangle_normals

OUTWARD = 0.0   # the outward score's sign decides; the shared heads score +0.38 to +0.91, fran_cut -0.51


def outward_score(V, F):
    """How outward ``F`` (m, 3) int faces on ``V`` (n, 3): in (-1, 1), positive when outward.

    The flux of the position from the surface's area centroid through the triangles (three times the
    enclosed volume of a closed surface), over the area times the RMS distance from that centroid: an
    open head (a neck cut, a face mask, curved about a point behind it) scores like a closed one.
    Unitless; 0 for no area."""
    N = 0.5 * triangle_normals(V, F)
    A = np.linalg.norm(N, axis=1)
    total = A.sum()
    if not total > 0:
        return 0.0
    C = (V[F[:, 0]] + V[F[:, 1]] + V[F[:, 2]]) / 3.0
    C = C - (A @ C) / total
    rms = np.sqrt(A @ np.einsum("ij,ij->i", C, C) / total)
    return float(np.einsum("ij,ij->", C, N) / (total * rms)) if rms > 0 else 0.0


def _consistent(F):
    """True when no directed edge of ``F`` (m, 3) is used twice: neighbours wound alike (the usual case,
    told by one sort, a third of ``igl.bfs_orient``'s time on a scan)."""
    a, b = F.ravel(), np.roll(F, -1, axis=1).ravel()
    key = np.sort(a * (int(F.max()) + 1) + b)
    return not (key[1:] == key[:-1]).any()


def _turned_by(F, G):
    """(m,) bool: which triangles of ``G`` are those of ``F`` (m, 3) with the opposite winding."""
    k = np.argmax(G == F[:, :1], axis=1)            # where F's first corner sits in G
    return G[np.arange(len(F)), (k + 1) % 3] != F[:, 1]


def outward_faces(V, F):
    """``F`` wound consistently within each connected part and outward as a whole.

    Parameters
    ----------
    V : (n, 3) float
        Vertices, any frame and unit.
    F : (m, 3) int
        Triangles.

    Returns
    -------
    F_out : (m, 3) int64
        ``F`` itself when it is consistent and outward already (the usual case: nothing copied);
        else a copy with some triangles reversed (a file written inside out comes back as it
        was): in each part (triangles joined by edges, ``igl.bfs_orient``) the winding of most of
        its area is kept; then all are turned when the whole reads inside out (:func:`outward_score`
        below 0).
    turned : int
        How many triangles were turned.
    """
    import igl

    F = np.asarray(F, dtype=np.int64)
    if len(F) == 0:
        return F, 0
    flip = np.zeros(len(F), dtype=bool)
    if not _consistent(F):
        G, part = igl.bfs_orient(np.ascontiguousarray(F))
        flip = _turned_by(F, np.asarray(G))
    if flip.any():
        # the search starts each part from its first triangle: keep the winding of most of its area
        area = np.linalg.norm(triangle_normals(V, F), axis=1)
        part = np.asarray(part).ravel()
        against = np.bincount(part, area * flip) > 0.5 * np.bincount(part, area)
        flip ^= against[part]
    G = F
    if flip.any():
        G = F.copy()
        G[flip] = F[flip][:, ::-1]
    if outward_score(V, G) < OUTWARD:
        G, flip = G[:, ::-1], ~flip   # a turned triangle turned back is the file's own, corner for corner
    return (F, 0) if not flip.any() else (np.ascontiguousarray(G), int(flip.sum()))
