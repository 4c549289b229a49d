"""Triangle-mesh clean-up and topology helpers for the half head.

Meshes are ``V`` (n, 3) float vertex positions (metres) and ``F`` (m, 3)
int vertex indices, counter-clockwise seen from outside.  The "half" mesh is
the x >= 0 side of the default head, open along the plane x = 0.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components


def _directed_edges(F):
    """(3m, 2) directed edges of F, face-edge (0,1) block first, then (1,2), (2,0)."""
    return np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])


def clean(V, F):
    """Drop degenerate faces and unreferenced vertices, keeping order: (V', F')."""
    F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])]
    used = np.zeros(len(V), bool)
    used[F.ravel()] = True
    remap = -np.ones(len(V), np.int64)
    remap[used] = np.arange(used.sum())
    return V[used], remap[F]


def _vertex_fans_ok(F):
    """True if every vertex's one-ring is a single fan or cycle (vertex-manifold)."""
    opp = {}                          # vertex -> its opposite edges, in face order
    for a, b, c_ in F.tolist():
        opp.setdefault(a, []).append((b, c_))
        opp.setdefault(b, []).append((c_, a))
        opp.setdefault(c_, []).append((a, b))
    for edges in opp.values():
        nxt = dict(edges)
        if len(nxt) != len(edges):
            return False
        starts = set(nxt) - set(nxt.values())
        if len(starts) > 1:
            return False
        s = next(iter(starts)) if starts else edges[0][0]
        seen, cur = 0, s
        while cur in nxt and seen <= len(edges):
            cur = nxt[cur]
            seen += 1
            if cur == s:
                break
        if seen != len(edges):
            return False
    return True


def is_manifold(F):
    """Edge- and vertex-manifold and consistently oriented (borders allowed)."""
    d = _directed_edges(F)
    if len(np.unique(d, axis=0)) != len(d):
        return False
    _, c = np.unique(np.sort(d, axis=1), axis=0, return_counts=True)
    if c.max() > 2:
        return False
    return _vertex_fans_ok(F)


def keep_largest_component(V, F):
    """The edge-connected component with the most faces, cleaned: (V', F')."""
    n = len(V)
    e = _directed_edges(F)
    A = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    _, lab = connected_components(A, directed=False)
    big = np.argmax(np.bincount(lab[F[:, 0]]))
    F = F[lab[F[:, 0]] == big]
    return clean(V, F)


def boundary_edges(F):
    """(k, 2) directed edges used by exactly one face, in face orientation."""
    e = _directed_edges(F)
    key = np.sort(e, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return e[cnt[inv.ravel()] == 1]


def boundary_mask(n, F):
    """(n,) bool, True for the vertices on a border of F."""
    on_b = np.zeros(n, bool)
    on_b[boundary_edges(F).ravel()] = True
    return on_b


def tri_angles(V, F):
    """(m, 3) interior angles in degrees, at F[:, 0], F[:, 1], F[:, 2]."""
    a = V[F[:, 1]] - V[F[:, 0]]
    b = V[F[:, 2]] - V[F[:, 1]]
    c = V[F[:, 0]] - V[F[:, 2]]

    def ang(u, v):
        cu = np.einsum("ij,ij->i", u, v) / np.maximum(
            np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1), 1e-30)
        return np.degrees(np.arccos(np.clip(cu, -1, 1)))
    return np.stack([ang(a, -c), ang(b, -a), ang(c, -b)], -1)


def mirror_weld(V, F):
    """Close a half mesh whose border lies on x = 0 with its mirror image.

    The mirrored copy uses -x bit-for-bit and reuses the border vertices, so
    the result (V', F') is closed and exactly symmetric; mirrored faces are
    reversed to stay outward.  Original vertices keep their indices.
    """
    n = len(V)
    on0 = boundary_mask(n, F)
    assert np.all(V[on0, 0] == 0.0) and np.all(V[~on0, 0] > 0.0)
    idx = np.arange(n)
    mir_idx = np.where(on0, idx, n + np.cumsum(~on0) - 1)
    Vm = V[~on0].copy()
    Vm[:, 0] = -Vm[:, 0]
    Vall = np.concatenate([V, Vm])
    Fm = mir_idx[F][:, ::-1]
    Fall = np.concatenate([F, Fm])
    return Vall, Fall
