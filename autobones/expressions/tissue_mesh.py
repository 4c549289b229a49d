"""The layered mesh of the soft tissue (:mod:`.tissue`; Lee, Terzopoulos & Waters 1995, §4): which skin
triangles carry it, the three node layers of each column, the springs between the nodes, and the
prisms' volumes and layer areas the volume terms measure.

Below every skin triangle of the tissue stands a prism of three node layers: the epidermis (the
skin itself), the fascia (the bottom of the dermal-fatty layer) and the skull estimate (the bottom
of the muscle layer), along the skull normals at the region's soft-tissue thickness. Springs join
the nodes within the epidermis and the fascia and between layers (vertical and crossed).

Nodes are numbered layer by layer: column ``k``'s epidermis, fascia and skull nodes are ``k``,
``c + k`` and ``2c + k`` (``c`` columns). Everything canonical (+Y up, +Z front), head sizes.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import AutobonesError
from ..geometry.normals import cross_rows, triangle_normals
from ..geometry.topology import mesh_edges


@dataclass
class _Springs:
    """Springs between nodes ``a`` and ``b`` (s,) with rest lengths ``rest`` (s,) and weights
    ``weight`` (s,); ``limit`` (s,) the deformation ratio past which the second phase's extra
    weight ``weight2`` (s,) acts (inf: one phase)."""

    a: np.ndarray
    b: np.ndarray
    rest: np.ndarray
    weight: np.ndarray
    limit: np.ndarray
    weight2: np.ndarray


def _prism_tets(top, bottom):
    """The three tetrahedra (3, 4) of node-index arrays that split prisms ``top`` (e, 3) over
    ``bottom`` (e, 3) (bottom[:, k] under top[:, k]); each tet as (e, 4)."""
    a, b, c = top.T
    a_, b_, c_ = bottom.T
    return [np.stack(t, axis=1) for t in ((a, b, c, a_), (b, c, a_, b_), (c, a_, b_, c_))]


def prism_volumes(X, top, bottom):
    """Volumes (e,) of prisms with corners ``X[top]`` over ``X[bottom]`` (``X`` (N, 3)).

    Positive when the top triangle's normal (right hand, corners in order) points away from
    the bottom; each prism is the sum of its three tetrahedra, so the sum over prisms sharing
    faces is the volume they fill.
    """
    vol = np.zeros(len(top))
    for t in _prism_tets(top, bottom):
        p0 = X[t[:, 0]]
        vol += (cross_rows(X[t[:, 1]] - p0, X[t[:, 2]] - p0) * (X[t[:, 3]] - p0)).sum(axis=1)
    # (a, b, c, a') with a' below an outward (a, b, c) is negative: flip to a positive volume
    return -vol / 6.0


def layer_areas(X, Fc, layer, across=None):
    """Area (c,) around each column in node layer ``layer`` of ``X`` (3c, 3): a third of each
    element's area at that layer; with ``across`` (e, 3), the unit mean column direction at
    its corners, that area projected on the plane normal to it (area times height along the
    columns is then the volume however the layers tilt: the pressure's measure)."""
    nc = len(X) // 3
    n = triangle_normals(X[layer * nc:(layer + 1) * nc], Fc)
    a = 0.5 * np.linalg.norm(n, axis=1) if across is None else 0.5 * np.abs(np.einsum("ij,ij->i", n, across))
    return np.bincount(Fc.ravel(), weights=np.repeat(a / 3.0, 3), minlength=nc)


def tissue_triangles(model, regions):
    """The skin triangles (e, 3) int of ``model.surface_`` (welded vertex indices) that carry
    tissue: all three corners on skin facing out of the head in one of ``regions`` (region labels;
    None: every region), none across the mouth line. An error when there is none."""
    surf = model.surface_
    # skin facing out of the head (not skin that faces into it: the mouth's lining)
    where = model.skin_ & ~model.mouth_["inward"]
    if model.region_ is not None and regions is not None:
        keep = [i for i, name in enumerate(model.region_labels_) if name in set(regions)]
        where &= np.isin(model.region_, keep)
    in_tissue = np.zeros(len(surf.vertices), dtype=bool)
    in_tissue[surf.index[where]] = True
    Fs = surf.skin_faces
    # no element across the mouth line (with the lips among the regions: they part there)
    upper = np.zeros(len(surf.vertices), dtype=np.int8)
    zone = np.zeros(len(surf.vertices))
    upper[surf.index] = model.mouth_["upper"] > 0.5
    zone[surf.index] = model.mouth_["zone"]
    across = (np.ptp(upper[Fs], axis=1) != 0) & (zone[Fs] >= 0.05).any(axis=1)
    Fe = Fs[in_tissue[Fs].all(axis=1) & ~across]
    if len(Fe) == 0:
        raise AutobonesError("tissue: no skin of the tissue's regions on this head (no triangle whose corners "
                             f"all lie in {', '.join(regions or ())} and face out of the head)")
    return Fe


def layer_nodes(model, Fe, dermal_fraction):
    """The columns and rest nodes under the tissue's triangles ``Fe`` (e, 3) (welded indices).

    Returns ``cols`` (c,) the welded skin vertices that carry a column, ``Fc`` (e, 3) the
    triangles as column indices wound so their normal points out of the head, ``E0`` (c, 3) the
    epidermis at rest, ``Ns`` (c, 3) the skull normals, ``T`` (c,) the soft-tissue thickness (head
    sizes) and ``X0`` (3c, 3) the rest nodes layer by layer: the fascia ``dermal_fraction`` of the
    thickness below the skin, the skull estimate the whole thickness.
    """
    surf = model.surface_
    first = surf.first
    cols, Fc = np.unique(Fe, return_inverse=True)
    Fc = Fc.reshape(-1, 3)
    E0 = surf.vertices[cols]
    Ns = model.skull_normals_[first[cols]]
    T = np.maximum(model.thickness_[first[cols]], 1e-9)
    # wind every element so that its normal points out of the head (away from the skull)
    n_e = triangle_normals(E0, Fc)
    flip = (n_e * Ns[Fc].sum(axis=1)).sum(axis=1) < 0
    Fc[flip] = Fc[flip][:, [0, 2, 1]]
    df = float(dermal_fraction)
    X0 = np.concatenate([E0, E0 - Ns * (df * T)[:, None], E0 - Ns * T[:, None]])
    return cols, Fc, E0, Ns, T, X0


def area_shares(E0, Fc):
    """Per-area shares of the epidermis ``E0`` (c, 3) with triangles ``Fc`` (e, 3): each triangle's
    area split among its corners and its edges. Returns the area per column (c,) (head sizes
    squared), the unique edges (q, 2) (sorted pairs of column indices, :func:`mesh_edges`) and the
    area per edge (q,)."""
    nc = len(E0)
    area = 0.5 * np.linalg.norm(triangle_normals(E0, Fc), axis=1)
    col_area = np.bincount(Fc.ravel(), weights=np.repeat(area / 3.0, 3), minlength=nc)
    edges = mesh_edges(Fc)
    ekey = edges[:, 0] * nc + edges[:, 1]
    fe = np.sort(np.concatenate([Fc[:, [0, 1]], Fc[:, [1, 2]], Fc[:, [2, 0]]]), axis=1)
    e_of = np.searchsorted(ekey, fe[:, 0] * nc + fe[:, 1])
    edge_area = np.bincount(e_of, weights=np.tile(area / 3.0, 3), minlength=len(edges))
    return col_area, edges, edge_area


def layer_springs(X0, edges, col_area, edge_area, epidermis, fascia, muscle_layer, dermal, biphasic, compression):
    """The tissue's springs (a ``_Springs``) on the rest nodes ``X0`` (3c, 3): along every edge
    (q, 2) in the epidermis and in the fascia, soft under compression (``compression`` of their
    stiffness); and vertical and crossed between epidermis and fascia (biphasic: ``dermal`` (k1,
    k2), stiffening past ``biphasic`` stretch) and between fascia and skull (``muscle_layer``).

    Weights are the stiffness (per unit area and squared strain) times the area share
    (``col_area`` (c,), ``edge_area`` (q,): :func:`area_shares`) over the rest length squared;
    springs of zero rest length are left out.
    """
    nc = len(col_area)
    springs = []

    def add(a, b, share, k, limit=np.inf, k2=0.0):
        rest = np.linalg.norm(X0[a] - X0[b], axis=1)
        ok = rest > 1e-12
        a, b, rest, share = a[ok], b[ok], rest[ok], share[ok]
        springs.append((a, b, rest, float(k) * share / rest**2, np.full(len(a), float(limit)),
                        float(k2) * share / rest**2))

    i, j = edges[:, 0], edges[:, 1]
    cidx = np.arange(nc)
    k1, k2 = (float(v) for v in dermal)
    lim = 1.0 + float(biphasic)
    # skin and fascia resist stretch but give under compression (they wrinkle instead):
    # a tenth of the stiffness below the rest length
    soft = float(compression)
    add(i, j, edge_area, soft * epidermis, 1.0, (1.0 - soft) * epidermis)          # epidermis
    add(nc + i, nc + j, edge_area, soft * fascia, 1.0, (1.0 - soft) * fascia)      # fascia
    for top, bottom, k, ph2 in ((0, nc, k1, k2 - k1), (nc, 2 * nc, float(muscle_layer), 0.0)):
        limit = lim if ph2 > 0 else np.inf
        add(top + cidx, bottom + cidx, col_area, k, limit, ph2)                    # vertical
        add(top + i, bottom + j, 0.5 * edge_area, k, limit, ph2)                   # crossed
        add(top + j, bottom + i, 0.5 * edge_area, k, limit, ph2)
    return _Springs(*(np.concatenate([s[m] for s in springs]) for m in range(6)))
