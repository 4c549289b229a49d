"""Facial bones by k-means on the facial mask, at a chosen density.

The bone-placement method of ``place`` (its §3.2): k-means on the facial-mask vertices, initial centres from dense,
well separated regions, the best of several runs by squared error, a bone at
each centroid, parented to the head bone.

Beyond that method: the centres are constrained to be mirror-symmetric about the
head's symmetry plane (x = 0 in the canonical frame): each centre is either on
the plane or one of a mirrored pair. Lloyd's update is followed by projecting
the centres onto that constraint (a pair's centre is the weighted mean of its
points and its partner's mirrored points), which is the exact minimiser of the
squared error over symmetric centres for the current assignment, so the error
never rises on a symmetric head. Vertices are weighted by their surface area so
that bones follow the shape, not the density of the tessellation.
"""
from __future__ import annotations

import numpy as np
from scipy.cluster.vq import vq

from ..errors import AutobonesError, counted
from ..geometry.areas import vertex_areas
from ..geometry.closest import closest_points
from ..geometry.normals import vertex_normals
from ..geometry.spatial_order import spatial_order

DENSITIES = {"sparse": 8, "medium": 16, "dense": 32}
MIRROR = np.array([-1.0, 1.0, 1.0])


def bone_count(density):
    """``'sparse'`` (8), ``'medium'`` (16), ``'dense'`` (32) or an integer 1..256 -> int."""
    if isinstance(density, str) and density.strip().lower() in DENSITIES:
        return DENSITIES[density.strip().lower()]
    try:
        k = int(str(density))
    except ValueError:
        raise AutobonesError(
            f"density {density!r}: use sparse ({DENSITIES['sparse']}), medium ({DENSITIES['medium']}), "
            f"dense ({DENSITIES['dense']}) or a number of facial bones") from None
    if not 1 <= k <= 256:
        raise AutobonesError(f"density {k}: the number of facial bones must be between 1 and 256")
    return k


def bones_for_mask(n_bones, density, mask_vertices):
    """The facial bones a facial mask of ``mask_vertices`` vertices takes for ``density`` (asking
    ``n_bones``, :func:`bone_count`).

    A named density (sparse, medium, dense) asks for a level of detail: on a mask with fewer
    vertices than its bones (a low-poly head: a dwarf statuette cut under its beard has 10, and
    the default medium was refused) it gets one bone per two mask vertices (at least one). A number
    is taken as asked (:class:`FacialBones` refuses more bones than mask vertices). Masks that
    hold enough vertices are untouched.
    """
    named = isinstance(density, str) and density.strip().lower() in DENSITIES
    if named and mask_vertices < n_bones:
        return max(1, int(mask_vertices) // 2)
    return n_bones


def check_seed(value, what="random_state"):
    """``value`` as a Python int when it is a whole number >= 0 (numpy's generators take no
    other seed); AutobonesError naming ``what`` otherwise."""
    import numbers

    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 0:
        raise AutobonesError(f"{what} {value!r}: the seed must be a whole number >= 0 (e.g. 0, 1, 42)")
    return int(value)


class FacialBones:
    """Symmetric k-means of facial points (scikit-learn style estimator).

    Parameters
    ----------
    n_bones : int
        Number of centres (facial bones).
    n_init : int
        Seeded restarts; the one with the lowest weighted squared error wins.
    max_iter : int
        Lloyd iterations per restart.
    midline_width : float
        A seed closer than this to the symmetry plane becomes a single midline
        centre (canonical units: head sizes).
    symmetric : bool
        Constrain centres to mirror pairs and midline points.
    random_state : int
        Seed of every random choice; the same input gives the same bones.

    Attributes
    ----------
    cluster_centers_ : (n_bones, 3) float
        Canonical centres, ordered top to bottom, then right to left.
    labels_ : (k,) int
        Centre of each input point.
    partner_ : (n_bones,) int
        Index of each centre's mirror image (itself on the midline).
    inertia_ : float
        Weighted sum of squared distances to the assigned centres.
    """

    def __init__(self, n_bones=16, n_init=8, max_iter=100, midline_width=0.02,
                 symmetric=True, random_state=0):
        self.n_bones = n_bones
        self.n_init = n_init
        self.max_iter = max_iter
        self.midline_width = midline_width
        self.symmetric = symmetric
        self.random_state = random_state

    def fit(self, X, sample_weight=None):
        """Cluster ``X`` (k, 3) canonical points (symmetry plane x = 0)."""
        X = np.asarray(X, dtype=np.float64)
        w = np.ones(len(X)) if sample_weight is None else np.asarray(sample_weight, dtype=np.float64)
        if len(X) < self.n_bones:
            raise AutobonesError(
                f"the facial mask has {counted(len(X), 'vertex', 'vertices')}, fewer than the {self.n_bones} facial bones asked for; "
                f"use a lower --density (at most {len(X)}), or sparse, medium or dense, which fit the mask")
        rng = np.random.default_rng(self.random_state)
        # the seeds are drawn over the points in space order, so the same points in another order (a
        # re-export) give the same layout, and a point moved or added a little nearby seeds
        where = spatial_order(X, tie=w)
        Xs, ws = X[where], w[where]
        best = None
        for _ in range(self.n_init):
            C, partner = self._seed(Xs, ws, rng)
            C, labels, inertia = self._lloyd(Xs, ws, C, partner)
            if best is None or inertia < best[2] * (1 - 1e-12):
                best = (C, labels, inertia, partner)
        C, labels_s, inertia, partner = best
        labels = np.empty_like(labels_s)
        labels[where] = labels_s   # back to the given order
        order = np.lexsort((C[:, 0], -np.round(C[:, 1], 9)))
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        self.cluster_centers_ = C[order]
        self.partner_ = rank[partner[order]]
        self.labels_ = rank[labels]
        self.inertia_ = float(inertia)
        return self

    def _seed(self, X, w, rng):
        """k-means++ on the data and its mirror image: seeds far from chosen ones, drawn by
        weight, so from dense and well separated regions; a seed near the plane is a midline
        centre, any other brings its mirror partner."""
        k = self.n_bones
        centers, partner = [], []
        d2 = np.full(len(X), np.inf)
        Xt = np.ascontiguousarray(X.T)
        while len(centers) < k:
            p = w * np.where(np.isinf(d2), 1.0, d2)
            # greedy k-means++: the best of a few candidates by the error they leave; the
            # candidates' distances in one array
            trials = rng.choice(len(X), size=min(len(X), 2 + int(np.log(k + 1))), p=p / p.sum())
            news = []
            for t in trials:
                c = X[t].copy()
                if self.symmetric and (abs(c[0]) < self.midline_width or len(centers) == k - 1):
                    c[0] = 0.0
                    news.append([c])
                elif self.symmetric:
                    news.append([c, c * MIRROR])
                else:
                    news.append([c])
            Q = np.array([q for new in news for q in new])
            D = (Xt[0] - Q[:, 0:1]) ** 2  # coordinate by coordinate: a sum over a length-3 axis is slow
            D += (Xt[1] - Q[:, 1:2]) ** 2
            D += (Xt[2] - Q[:, 2:3]) ** 2
            first = np.cumsum([0] + [len(new) for new in news])
            ND = np.minimum(d2, D[first[:-1]])
            two = np.array([len(new) == 2 for new in news])
            ND[two] = np.minimum(ND[two], D[first[:-1][two] + 1])
            cost = (w * ND).sum(axis=1)
            b = int(np.argmin(cost))  # the first of equal costs, as a strict running minimum
            new, d2 = news[b], ND[b]
            i = len(centers)
            centers.extend(new)
            partner.extend([i] if len(new) == 1 else [i + 1, i])
        return np.array(centers), np.array(partner)

    def _lloyd(self, X, w, C, partner):
        # Hamerly's (2010) bounds skip the points whose centre cannot have changed; the labels,
        # hence every centre, are exactly those of plain Lloyd iterations
        Xt = np.ascontiguousarray(X.T)
        margin = 1e-7 * np.sqrt((X ** 2).sum(axis=1).max())
        labels, shift = None, None
        for _ in range(self.max_iter):
            if labels is None:
                new_labels, upper, lower = _assign(Xt, C, np.arange(len(X)))
            else:
                new_labels = labels.copy()
                upper = upper + shift[labels]
                lower = lower - shift.max()
                gap = np.sqrt(_pair_sq_dists(C))
                np.fill_diagonal(gap, np.inf)
                bound = np.maximum(0.5 * gap.min(axis=1)[labels], lower)
                check = np.flatnonzero(upper + margin >= bound)
                if len(check):
                    new_labels[check], upper[check], lower[check] = _assign(Xt, C, check)
            if labels is not None and np.array_equal(new_labels, labels):
                break
            labels = new_labels
            W = np.bincount(labels, weights=w, minlength=len(C))
            S = np.stack([np.bincount(labels, weights=w * X[:, j], minlength=len(C)) for j in range(3)], axis=1)
            if self.symmetric:
                # project onto symmetric centres: pool each centre with its partner's mirror
                Wp = W + W[partner] * (partner != np.arange(len(C)))
                Sp = S + (S[partner] * MIRROR) * (partner != np.arange(len(C)))[:, None]
                W, S = Wp, Sp
            empty = W <= 0
            C_new = np.where(empty[:, None], C, S / np.maximum(W, 1e-300)[:, None])
            if self.symmetric:
                C_new[partner == np.arange(len(C)), 0] = 0.0
            shift = np.sqrt(((C_new - C) ** 2).sum(axis=1))
            C = C_new
        labels = _nearest(X, C)
        inertia = float((w * ((X - C[labels]) ** 2).sum(axis=1)).sum())
        return C, labels, inertia


def _pair_sq_dists(C):
    """(c, c) squared distances between centres."""
    return ((C[:, None, :] - C[None, :, :]) ** 2).sum(axis=2)


def _assign(Xt, C, rows):
    """Nearest centre of the points ``Xt[:, rows]`` (``Xt`` (3, k) transposed points, ``C`` (c, 3))
    with the distance to it and to the second nearest: the first minimum of squared distances summed
    x, y, z in that order, as scipy's vector quantiser picks it."""
    P = Xt[:, rows]
    D = (P[0] - C[:, 0:1]) ** 2
    D += (P[1] - C[:, 1:2]) ** 2
    D += (P[2] - C[:, 2:3]) ** 2
    lab = np.argmin(D, axis=0)
    cols = np.arange(len(rows))
    best = D[lab, cols]
    if len(C) > 1:
        D[lab, cols] = np.inf
        second = D.min(axis=0)
    else:
        second = np.full(len(rows), np.inf)
    return lab.astype(np.int64), np.sqrt(best), np.sqrt(second)


def _nearest(X, C):
    """Index (k,) int64 of the nearest centre ``C`` (c, 3) of each point ``X`` (k, 3): scipy's vector
    quantiser, in C (a numpy expression per Lloyd step took most of the k-means time)."""
    return vq(X, C, check_finite=False)[0].astype(np.int64)


def _area_sample(V, area, idx, size, random_state):
    """At most ``size`` of the vertices ``idx`` (k,) int of ``V`` (n, 3), drawn by their ``area`` (n,):
    systematic sampling (one random offset, even steps through the cumulative area) over them in space
    order, so the same surface gives the same sample whatever its numbering and a little noise moves it
    a little (a vertex holding more than one step of area is taken once)."""
    where = spatial_order(V[idx], tie=area[idx])
    cdf = np.cumsum(area[idx][where])
    u = np.random.default_rng(random_state).random()
    picks = np.searchsorted(cdf, (np.arange(size) + u) * (cdf[-1] / size), side="right")
    return idx[where[np.unique(np.minimum(picks, len(idx) - 1))]]


def _under_skin(V, F, P, partner, max_depth):
    """Centroids deeper than ``max_depth`` under the skin (a sparse bone on a curved or boxy
    face) are pulled toward their closest surface point, then re-mirrored."""
    P = P.copy()
    for _ in range(3):  # mirroring can move a point off the surface again; a few rounds settle it
        # a few dozen points on a scan: the near-triangle path, not a tree over every triangle
        closest, _, _, d2 = closest_points(P, V, F)
        d = np.sqrt(d2)
        deep = d > max_depth
        if not deep.any():
            break
        P[deep] = closest[deep] + (P[deep] - closest[deep]) * (max_depth / d[deep])[:, None]
        P = 0.5 * (P + P[partner] * MIRROR)
    return P


def facial_bones(V, F, mask, n_bones, random_state=0, bone_length=0.03, max_depth=0.02, max_points=8000,
                 surface=None, **kwargs):
    """Place facial bones on the facial mask of a canonical head.

    Parameters
    ----------
    V : (n, 3) float
        Canonical vertices (head sizes, +Y up, +Z front, symmetry plane x = 0).
    F : (m, 3) int
        Triangles.
    mask : (n,) bool
        Facial-mask vertices to cluster.
    n_bones : int
        Number of facial bones.
    bone_length : float
        Length of each bone (head sizes), pointing along the cluster's mean normal.
    max_depth : float
        A centroid deeper than this under the skin (head sizes) is moved up to it.
    max_points : int
        Masks with more vertices are clustered on an area-weighted sample of at most this size
        (a vertex holding more than one sampling step of area is taken once).
    surface : (Vc, Fc), optional
        A coarser copy of the same surface for the closest-point test of ``max_depth``.

    Returns
    -------
    heads, tails : (n_bones, 3) float
        Canonical bone heads (the centroids) and tails.
    model : FacialBones
        The fitted estimator (labels of the mask vertices, partners, inertia).
    """
    idx = np.flatnonzero(mask)
    area = vertex_areas(V, F)
    model = FacialBones(n_bones=n_bones, random_state=random_state, **kwargs)
    if len(idx) > max_points:
        # a dense scan: cluster a sample drawn by area (the same objective, estimated), then
        # label every mask vertex by its nearest centre
        sub = np.sort(_area_sample(V, area, idx, max_points, random_state))
        model.fit(V[sub])
        model.labels_ = _nearest(V[idx], model.cluster_centers_)
    else:
        model.fit(V[idx], sample_weight=area[idx])
    heads = _under_skin(*((V, F) if surface is None else surface), model.cluster_centers_, model.partner_, max_depth)
    N = vertex_normals(V, F)[idx] * area[idx, None]
    dirs = np.stack([np.bincount(model.labels_, weights=N[:, j], minlength=n_bones) for j in range(3)], axis=1)
    if model.symmetric:
        dirs = dirs + dirs[model.partner_] * MIRROR
    norm = np.linalg.norm(dirs, axis=1, keepdims=True)
    dirs = np.where(norm > 1e-12, dirs / np.maximum(norm, 1e-300), [0.0, 0.0, 1.0])
    return heads, heads + bone_length * dirs, model
