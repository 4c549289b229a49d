"""Dense correspondence by fitting the warped source surface to the target.

Bibliowicz 2005, ch. 5.6 (Jeong's global alignment) on top of Orvalho, Zacur &
Susin 2008, §3.1-3.3 (TPS, then stick). Their pipeline ``STK(TPS(source))`` is only as good as
the TPS warp away from the landmarks, and the 27 face landmarks leave the sides
and back of the head, the ears and the neck to extrapolation. Here the TPS warp
is only the starting point; the source vertices ``x`` are then moved by
repeated linear least squares (Bibliowicz 2005, eq. 5.4)::

    E(x) = sum_i w_i ||x_i - c_i||^2                         (distance, 5.2)
         + sum_i r_i ||x_i - m_i||^2                          (reverse distance)
         + lam * sum_(i,j) ||(x_i - x_j) - s R_ij (v_i - v_j)||^2   (shape)
         + mu  * sum_(b in boundary) ||x_b - c_b||^2         (binding, 5.6)
         + nu  * sum_l ||B_l x - q_l||^2                      (constraints, 5.7)

- ``c_i``: closest point of the target to ``x_i`` (point-to-plane at the
  nearest target vertex during the iterations), dropped (``c_i = x_i``) when
  the normals differ by more than ``max_angle`` or the distance is an outlier;
- the reverse term is Bibliowicz's own direction of eq. 5.2 (scan point to
  its closest point of the mesh, Amberg's symmetric data term): every target
  vertex is matched to its nearest source vertex of the same part (same
  rejections), ``m_i`` is the area-weighted centroid of the target vertices
  matched to ``x_i`` -- the centroid of the piece of target surface closest to
  it -- and ``r_i = symmetric_weight * min(area received / own area, 4)``.
  The forward term only pulls along the normal; this one also pulls
  tangentially, so the sides and back of the head, the ears and the neck
  spread over the target instead of keeping the TPS's tangential error.
  It is area- not sample-weighted, so a scan's sampling density does not
  pull the mesh; to keep the matrix constant it is folded into the target
  of the forward term, ``c_i <- (c_i + r_i m_i) / (1 + r_i)``;
- the shape term keeps every source edge ``v_i - v_j`` at its source length
  times the landmark scale ``s``, turned first by the rotation between the
  two files (:func:`rigid_turn`, the polar factor of the TPS's affine part:
  a head modelled facing another axis, like the goat's muzzle along -X, or
  turned by any angle) and then by the rotation ``R_ij`` of the local
  normal. ``R_ij`` only tilts the normal: without the first turn, edges around
  every normal near the turn's axis keep the source's heading about it and the
  fit twists the surface sideways to comply (the generic's right side landed
  across the goat's midline). The turn is exact, not the nearest of the 24
  axis turns: a head at 37 degrees fitted with the axis turn came out 40-60%
  of ex-ex (p95) off its upright copy's correspondence; now the same to
  rounding. It is Bibliowicz's smoothness term (a vertex near
  its neighbours' centroid) made relative to the source's own differential
  coordinates: it is the uniform graph Laplacian, and with ``R = I, s = 1``
  its minimum is the source itself. We tried the bi-Laplacian form
  ``||L x - L x_tps||^2`` too: less accurate and its factor much larger
  (see benchmarks/correspondence.py). Near the landmarks the reference edge
  is the TPS-warped edge instead (``edge_reference="blend"``, the default):
  weight 1 within ``REFERENCE_CORE`` of the nearest landmark, fading as a
  Gaussian over ``REFERENCE_FALLOFF`` beyond (units: the landmarks' RMS
  radius). The source's own edges there would pull an open jaw or a smile back
  toward the neutral face: the chin slid up the target by 10-18% of ex-ex
  with its landmarks held; far from the landmarks the warp's extrapolation
  (the skull stretched by a dropped menton) is the worse guide. Full ARAP
  rotations (Sorkine & Alexa 2007) instead of the normal tilt were tried and
  let smooth regions turn about their normals: the scalp slid;
- the binding term pulls mesh boundary vertices (neck cut, eye and mouth
  openings) to the target's boundary of the same part (beyond both papers):
  it is the only cue for where the neck ends;
- the constraint term holds the source landmarks (barycentric rows ``B``) on
  the target landmarks ``q``.

Coarse to fine: a source of more than ``1.5 * coarse_vertices`` vertices is
first decimated (quadric error, ``fast_simplification``; libigl's
``decimate`` when that is missing) to ``coarse_vertices``; the whole staged
fit runs on the decimated mesh, its displacements from the TPS warp are
carried to every source vertex (inverse squared distance of the 4 nearest
coarse vertices of the same part), and from there ``fine_stages`` (one loose
stage, 2 iterations) finish at full resolution. Faster and more accurate:
on the decimated mesh the same ``lam`` is stiffer and the reverse term sees
a mesh that does not share the target's triangulation (figures in
benchmarks/README.md, from benchmarks/correspondence.py).

``lam`` decreases over stages (stiff, coarse fit first); in each stage the
normal matrix ``W + lam D^T D + mu W_b + nu B^T B`` is constant (rejected
matches are held in place rather than given zero weight) and factorised once
with ``scipy.sparse.linalg.splu`` (symmetric mode, minimum-degree ordering of
``A + A^T``: less fill than COLAMD). A final exact stick
(:func:`autobones.rig_transfer.stick.stick`) puts every vertex on the target surface.

A target much denser than the source (a scan) is matched back through grid cells of half the
source's median edge (:data:`autobones.rig_transfer.matching.SAMPLE_RATIO`): each cell's area-weighted centroid stands for its
vertices, so the reverse term costs what the source's resolution needs (ICT identity000 midpoint-
subdivided twice, 420k vertices: 13.5 -> 11.3 s, error 0.45/1.12 -> 0.44/1.16 % ex-ex).

An open jaw (``jaw=``, :mod:`autobones.rig_transfer.jaw_prior`): a jaw turned about its joint is
far from a smooth warp, so with the source rig's jaw given, the source skin's jaw is first opened as
far as the landmarks say and the posed skin is what the TPS warps and the shape term keeps (the
result is still one point per source vertex). Closed-mouth targets (estimate within 3 degrees of
rest) are fitted exactly as without it.

A symmetric head (``symmetry=``, :mod:`autobones.rig_transfer.symmetry`): after every solve each source
vertex is averaged with the reflection of its mirror partner's fitted point, so a smooth symmetric head's
points cannot drift across its midline.

Multi-part meshes (ICT: skin, eyeballs, teeth, gums, mouth socket, ... 56
parts): the parts are the connected components of each mesh. After the TPS
warp every source part votes, by the target part of its vertices' nearest
compatible (normal within ``max_angle``) target vertices, and if one target
part has at least half of the votes the source part is matched only to it,
in the iterations and in the final stick. So an eyelid vertex cannot land on
the eyeball behind it; a target scan with one part receives everything.
"""
from __future__ import annotations

import logging
import time

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..errors import AutobonesError
from ..geometry.areas import vertex_areas
from ..geometry.closest import closest_points
from ..geometry.landmark_warp import LocalLandmarkWarp, nearest_landmark
from ..geometry.laplacian import factor_spd
from ..geometry.normals import vertex_normals
from ..geometry.proxy import quadric_simplify
from ..geometry.rotations import polar_rotations, rotate_between
from ..geometry.topology import boundary_vertices, mesh_edges, mesh_parts
from ..geometry.validate import mesh_arrays
from ..geometry.tps import ThinPlateSpline, as_points, landmark_arrays
from .matching import SAMPLE_RATIO, Matcher, PartTrees, boundary_neighbours, target_samples
from .source_pose import open_source_jaw, pose_source_expression
from .stick import stick
from .symmetry import mirror_operator, symmetrize

log = logging.getLogger(__name__)


def _decimate(V, F, count):
    """Quadric-error decimation of ``(V, F)`` to about ``count`` vertices (fast_simplification, else libigl)."""
    import importlib.util

    if importlib.util.find_spec("fast_simplification") is None:  # pragma: no cover - libigl's edge collapse,
        import igl                                                  # slower and a little less accurate
        Vc, Fc = igl.decimate(V, F, max(4, int(len(F) * count / len(V))))[:2]
        return np.asarray(Vc, dtype=np.float64), np.asarray(Fc, dtype=np.int64)
    Vc, Fc = quadric_simplify(V.astype(np.float32), F.astype(np.int32), 1.0 - count / len(V))
    return np.asarray(Vc, dtype=np.float64), np.asarray(Fc, dtype=np.int64)


def _interpolate(Vc, Fc, Dc, V, F, k=4):
    """Displacements ``Dc`` of coarse vertices ``Vc`` -> fine vertices ``V``: inverse squared distance of the ``k`` nearest of the same part."""
    part = mesh_parts(len(V), F)
    part_c = part[cKDTree(V).query(Vc, workers=-1)[1]]
    big = 10.0 * (np.ptp(V, axis=0).max() + 1.0)
    d, i = cKDTree(np.c_[Vc, big * part_c]).query(np.c_[V, big * part], k=min(k, len(Vc)), workers=-1)
    d, i = d.reshape(len(V), -1), i.reshape(len(V), -1)
    w = 1.0 / np.maximum(d, 1e-12 * big) ** 2
    w /= w.sum(axis=1, keepdims=True)
    return np.einsum("ij,ijk->ik", w, Dc[i])


def _part_map(src_part, tgt_part, nearest, agree):
    """Source part -> target part holding >= half of its compatible nearest vertices, else -1."""
    labels = np.full(src_part.max() + 1, -1, dtype=np.int64)
    ok = agree
    pairs = np.stack([src_part[ok], tgt_part[nearest[ok]]], axis=1)
    if len(pairs) == 0:
        return labels
    u, count = np.unique(pairs, axis=0, return_counts=True)
    size = np.bincount(src_part, minlength=len(labels))
    order = np.argsort(-count, kind="stable")
    for (s, t), c in zip(u[order], count[order]):
        if labels[s] < 0 and c >= 0.5 * size[s]:
            labels[s] = t
    return labels


def rigid_turn(A):
    """The rotation (3, 3), applied as ``x @ R``, nearest the linear part ``A`` (3, 3) of a row-vector
    map ``x -> x @ A + t`` (the TPS's affine part): its polar factor, made proper.

    Exactly equivariant: a head turned by any ``Q`` (rows ``x @ Q``) gives ``A @ Q`` and so ``R @ Q``,
    and the shape term's reference edges turn with the head. The 24 axis turns used before
    (``axis_turn``) were only right for a file whose axes were swapped: a head at 37 degrees kept a
    reference 37 degrees off and the fit twisted the generic about its normals (p95 40-60% of ex-ex
    from the as-is correspondence, mapped back).
    """
    return polar_rotations(np.asarray(A, dtype=np.float64)[None])[0]   # mirrored landmarks: the nearest proper one


def _source_terms(V_src, F_src, X, tps, P, edge_reference):
    """Source-side matrices of the fit: edge difference ``D`` (e, n) and ``D^T D``, the reference
    edges ``edge_src`` (e, 3) with their unit edge normals, vertices in a face, landmark rows ``B``."""
    n = len(V_src)
    E = mesh_edges(F_src)
    m = len(E)
    D = sp.csr_matrix((np.r_[np.ones(m), -np.ones(m)], (np.r_[np.arange(m), np.arange(m)], np.r_[E[:, 0], E[:, 1]])),
                      shape=(m, n))
    DtD = (D.T @ D).tocsc()
    def edge_normals(N):
        ne = N[E[:, 0]] + N[E[:, 1]]
        return ne / np.maximum(np.linalg.norm(ne, axis=1, keepdims=True), 1e-12)

    if edge_reference == "tps":
        edge_src, n_edge_src = X[E[:, 0]] - X[E[:, 1]], edge_normals(vertex_normals(X, F_src))
    else:
        # in the target file's axes: R_ij below only tilts the normal and cannot turn edges about it
        scale = abs(np.linalg.det(tps.affine_[1:])) ** (1.0 / 3.0)
        turn = rigid_turn(tps.affine_[1:])
        n_edge_src = edge_normals(vertex_normals(V_src, F_src) @ turn)
        edge_src = scale * (V_src[E[:, 0]] - V_src[E[:, 1]]) @ turn
    if edge_reference == "blend":
        # near the landmarks the warp's edges (turned into the source edge's normal frame, so one
        # R_ij turns both): they carry the stretch an expression or a different face puts there
        d, r = nearest_landmark(P, 0.5 * (V_src[E[:, 0]] + V_src[E[:, 1]]))
        alpha = np.exp(-(np.maximum(d - REFERENCE_CORE * r, 0.0) / (REFERENCE_FALLOFF * r)) ** 2)[:, None]
        warped = rotate_between(edge_normals(vertex_normals(X, F_src)), n_edge_src, X[E[:, 0]] - X[E[:, 1]])
        edge_src = (1.0 - alpha) * edge_src + alpha * warped
    in_face = np.zeros(n, dtype=bool)
    in_face[F_src.ravel()] = True
    _, lface, lbary, _ = closest_points(P, V_src, F_src)
    B = sp.csr_matrix((lbary.ravel(), (np.repeat(np.arange(len(P)), 3), F_src[lface].ravel())), shape=(len(P), n))
    return E, D, DtD, edge_src, n_edge_src, in_face, B


def _target_terms(tgt, V_tgt, F_tgt):
    """Fill ``tgt`` (once; shared by the coarse and the fine solve) with the target's vertex
    normals, vertices in a face, parts, nearest-vertex trees, boundary and vertex areas."""
    if tgt:
        return tgt
    nt = len(V_tgt)
    tgt["N"] = vertex_normals(V_tgt, F_tgt)
    tgt["in_face"] = np.zeros(nt, dtype=bool)
    tgt["in_face"][F_tgt.ravel()] = True
    tgt["part"] = mesh_parts(nt, F_tgt)
    tgt["trees"] = PartTrees(V_tgt, tgt["in_face"], tgt["part"])
    tgt["bnd"] = boundary_vertices(nt, F_tgt)
    tgt["btrees"] = PartTrees(V_tgt, tgt["bnd"], tgt["part"]) if tgt["bnd"].any() else None
    tgt["bnb"] = boundary_neighbours(nt, F_tgt) if tgt["bnd"].any() else None
    tgt["area"] = vertex_areas(V_tgt, F_tgt)
    return tgt


def _fit(V_src, F_src, V_tgt, F_tgt, P, Q, tps, X0, stages, iterations, landmark_weight, boundary_weight, max_angle,
         restrict_parts, exact, edge_reference, symmetric_weight, symmetry, tgt):
    """Staged least squares of :func:`fit_surface` from ``X0`` (default: the TPS warp); returns X, labels, seconds."""
    t1 = time.perf_counter()
    n = len(V_src)
    X = tps.transform(V_src)
    E, D, DtD, edge_src, n_edge_src, in_face, B = _source_terms(V_src, F_src, X, tps, P, edge_reference)
    nt = len(V_tgt)
    tgt = _target_terms(tgt, V_tgt, F_tgt)
    N_tgt, tgt_in_face, tgt_part, trees = tgt["N"], tgt["in_face"], tgt["part"], tgt["trees"]
    cos_max = np.cos(np.radians(max_angle))

    if restrict_parts:
        src_part = mesh_parts(n, F_src)
        N = vertex_normals(X, F_src)
        near = trees.query(X, np.full(n, -1))
        agree = (np.einsum("ij,ij->i", N, N_tgt[near]) >= cos_max) & in_face
        labels = _part_map(src_part, tgt_part, near, agree)[src_part]
    else:
        labels = np.full(n, -1, dtype=np.int64)

    bnd_src = boundary_vertices(n, F_src) & (boundary_weight > 0)
    btrees = tgt["btrees"] if bnd_src.any() else None
    bidx = np.flatnonzero(bnd_src) if btrees is not None else np.zeros(0, dtype=np.int64)

    w = in_face.astype(np.float64)
    w[bidx] = boundary_weight
    w[~in_face] = 1e-6        # loose vertices: held where the TPS put them
    W = sp.diags(w)
    BtB = landmark_weight * (B.T @ B)
    BtQ = landmark_weight * (B.T @ Q)
    t2 = time.perf_counter()

    reverse = None
    if symmetric_weight > 0:
        tlab = tgt_part if restrict_parts else np.full(nt, -1, dtype=np.int64)
        sidx = np.flatnonzero(in_face & ((labels >= 0) | (not restrict_parts)))
        tq = np.flatnonzero(tgt_in_face & np.isin(tlab, labels[sidx]))
        if len(sidx) and len(tq):
            cell = 0.0
            if len(tq) > SAMPLE_RATIO * len(sidx):
                cell = 0.5 * float(np.median(np.linalg.norm(X[E[:, 0]] - X[E[:, 1]], axis=1)))
            samples = target_samples(V_tgt, N_tgt, tlab, tgt["area"], tq, cell, rigid_turn(tps.affine_[1:]))
            reverse = (np.maximum(vertex_areas(X, F_src), 1e-300), sidx, samples)
    if X0 is not None:
        X = X0.copy()
    match = Matcher(V_tgt, F_tgt, tgt, labels, in_face, bidx, btrees, cos_max, exact, symmetric_weight, reverse)
    if symmetry is not None:
        mirror, partnered = mirror_operator(V_src, F_src, symmetry["source_plane"], symmetry["partner_tol"])
    # --- staged least squares
    for lam in stages:
        # the fit runs on a coarse copy (about 8k vertices), where both orderings take the same time;
        # this one is what the fit has always used, so correspondences stay bit-identical
        solve = factor_spd(W + lam * DtD + BtB, ordering="mmd_symmetric")
        for _ in range(iterations):
            N = vertex_normals(X, F_src)
            C = match(X, N)
            n_edge = N[E[:, 0]] + N[E[:, 1]]
            n_edge /= np.maximum(np.linalg.norm(n_edge, axis=1, keepdims=True), 1e-12)
            rhs = w[:, None] * C + lam * (D.T @ rotate_between(n_edge_src, n_edge, edge_src)) + BtQ
            X = solve(rhs)
            if symmetry is not None:
                X = symmetrize(X, mirror, partnered, symmetry["target_plane"])
    t3 = time.perf_counter()
    return X, labels, (t2 - t1, t3 - t2)


# the blended reference (edge_reference="blend"): the landmark warp's shape within CORE, fading
# over FALLOFF beyond it; both in units of the landmarks' RMS distance from their centroid
REFERENCE_CORE = 0.5
REFERENCE_FALLOFF = 0.5


def fit_surface(V_src, F_src, V_tgt, F_tgt, lm_src, lm_tgt, stages=(100.0, 30.0, 10.0, 3.0), iterations=3,
                landmark_weight=30.0, boundary_weight=10.0, max_angle=60.0, restrict_parts=True, exact=False, edge_reference="blend", symmetric_weight=10.0, coarse_vertices=8000,
                fine_stages=(3.0,), fine_iterations=2, timings=None, jaw=None, details=None, symmetry=None,
                expressions=None, far_field="spline"):
    """Deform the source surface onto the target (TPS, then staged least squares).

    Parameters
    ----------
    V_src, F_src : (n, 3) float, (m, 3) int
        Source vertices (source frame and units) and triangles.
    V_tgt, F_tgt : (n_t, 3) float, (m_t, 3) int
        Target vertices (target frame and units) and triangles.
    lm_src, lm_tgt : dict of str -> (3,) float, or (k, 3) float
        Landmarks on the source and on the target, each in its mesh's frame
        (dicts are paired by name; arrays row by row). At least 4, not
        coplanar; 10 or more well spread recommended.
    stages : sequence of float
        Shape-term weights ``lam``, stiff to loose; one factorisation each.
    iterations : int
        Closest-point updates per stage.
    landmark_weight, boundary_weight : float
        ``nu`` and ``mu`` relative to a data weight of 1 per vertex. A strong
        landmark term (30) holds the landmarks far better than 1 and helps
        the whole fit (see benchmarks/README.md, correspondence).
    max_angle : float
        Degrees; matches whose normals differ more are rejected.
    restrict_parts : bool
        Match each source part only to its voted target part (see module doc).
    exact : bool
        Exact closest points (libigl AABB) in every iteration instead of
        point-to-plane at the nearest target vertex (slower, no more accurate
        in benchmarks/correspondence.py).
    edge_reference : {"blend", "source", "tps"}
        Reference edge vectors of the shape term: the TPS-warped edges near
        the landmarks and the source's own edges times the landmark scale far
        from them (default; module doc), the source's everywhere, or the
        TPS-warped edges everywhere (keeps an anisotropic or sheared landmark
        warp, but also its extrapolation over the skull and neck).
    symmetric_weight : float
        Weight of the reverse (target -> source) distance term relative to the
        forward one, for a source vertex receiving its own area; 0: off.
    coarse_vertices : int or None
        Vertex count of the decimated source for the coarse solve (module doc);
        None, 0 or a source of at most 1.5 times as many: full resolution only.
    fine_stages, fine_iterations
        ``stages`` and ``iterations`` of the full-resolution solve after the
        coarse one.
    timings : dict, optional
        Filled with seconds per step: ``tps`` (with ``jaw``: the jaw's estimate and pose
        included), ``setup``, ``fit`` (setup and fit summed over the coarse and fine solves).
    jaw : dict, optional
        The source's jaw (:func:`autobones.rig_transfer.jaw_prior.jaw_prior`: ``weight`` (n,),
        ``pivot`` (3,), ``axis`` (3,), ``glide`` (3,) per degree, optional; source frame): the source skin's
        jaw is first opened (turned and glided) as far
        as the landmarks say (:func:`~autobones.rig_transfer.jaw_prior.estimate_jaw_angle`), and
        that posed skin is what the TPS warps and the shape term keeps. None: no prior.
    details : dict, optional
        Filled with ``jaw_deg`` (float, the jaw opening used; 0 without ``jaw``) and ``jaw``
        (the estimate's details) when ``jaw`` is given.
    symmetry : dict, optional
        Keep the fit symmetric (:mod:`autobones.rig_transfer.symmetry`): ``source_plane`` and
        ``target_plane`` (unit normal, offset; each mesh's frame) and ``partner_tol`` (source
        units: a source vertex whose reflection is further from the source surface has no
        partner), from :meth:`autobones.rig_transfer.symmetry.Symmetry.fit_option`. None: off.
    expressions : dict, optional
        The source skin's expression space (:mod:`autobones.rig_transfer.expression_prior`): ``names``
        (k,), ``basis`` (k, n, 3) displacements at weight 1 (source units), optionally ``identity``
        ((j, n, 3) identity modes solved with it) or ``weights`` ({name: weight}, found on another skin
        of the same space): the source wears them (given
        weights, on top of the jaw prior's opening), or the weights the target seems to wear
        (solved, :func:`~autobones.rig_transfer.expression_prior.fit_expression`), before the warp;
        ``details['expression']`` says which. None: the neutral source.
    far_field : {"spline", "local"}
        The warp the fit starts from: Bookstein's spline of the landmarks everywhere (default), or that
        spline near the landmarks and their affine map far from them
        (:class:`~autobones.geometry.landmark_warp.LocalLandmarkWarp`: what moves a few landmarks, a
        smile the expression space does not hold, then does not bend the ears, scalp and neck).
        ``details['far_field']`` says which.

    Returns
    -------
    X : (n, 3) float64
        Fitted source vertices in the target frame (near, not exactly on, the
        target surface; :func:`dense_correspondence` sticks them).
    labels : (n,) int64
        Target part each source vertex is restricted to (``-1``: any), for
        ``face_labels`` of the target faces given by ``mesh_parts(len(V_tgt), F_tgt)[F_tgt[:, 0]]``.

    Raises
    ------
    AutobonesError
        Bad meshes or landmarks (see :class:`autobones.geometry.tps.ThinPlateSpline`).
    """
    t0 = time.perf_counter()
    V_src, F_src = mesh_arrays(V_src, F_src, "source mesh")
    V_tgt, F_tgt = mesh_arrays(V_tgt, F_tgt, "target mesh")
    P, Q = _landmark_pairs(lm_src, lm_tgt)
    if not len(stages) or min(stages) <= 0 or iterations < 1 or not len(fine_stages) or min(fine_stages) <= 0 \
            or fine_iterations < 1:
        raise AutobonesError("stages must be positive shape weights and iterations >= 1")
    if edge_reference not in ("source", "tps", "blend"):
        raise AutobonesError(f"edge_reference must be 'blend', 'source' or 'tps', got {edge_reference!r}")
    if far_field not in ("spline", "local"):
        raise AutobonesError(f"far_field must be 'spline' or 'local', got {far_field!r}")
    if jaw is not None:
        V_src, P = open_source_jaw(V_src, F_src, P, Q, jaw, details)
    elif details is not None:
        details["jaw_deg"] = 0.0
    if expressions is not None:
        V_src, P = pose_source_expression(V_src, F_src, P, Q, V_tgt, F_tgt, expressions, details)
    tps = (LocalLandmarkWarp() if far_field == "local" else ThinPlateSpline()).fit(P, Q)
    if details is not None:
        details["far_field"] = far_field
    t1 = time.perf_counter()
    args = (landmark_weight, boundary_weight, max_angle, restrict_parts, exact, edge_reference, symmetric_weight,
            symmetry, {})
    X, labels, t_setup, t_fit = _coarse_to_fine(V_src, F_src, V_tgt, F_tgt, P, Q, tps, coarse_vertices,
                                                (stages, iterations), (fine_stages, fine_iterations), args)
    if timings is not None:
        timings.update(tps=t1 - t0, setup=t_setup, fit=t_fit)
    log.debug("fit_surface: tps %.3fs setup %.3fs fit %.3fs", t1 - t0, t_setup, t_fit)
    return X, labels


def _coarse_to_fine(V_src, F_src, V_tgt, F_tgt, P, Q, tps, coarse_vertices, schedule, fine_schedule, args):
    """:func:`_fit` on the source decimated to ``coarse_vertices`` with ``schedule`` (stages,
    iterations), its displacements from the TPS carried to every source vertex, then at full
    resolution with ``fine_schedule``; a small source is fitted at full resolution with
    ``schedule`` only. Returns X (n, 3), labels (n,), setup and fit seconds."""
    X0, t_setup, t_fit = None, 0.0, 0.0
    stages, iterations = schedule
    if coarse_vertices and len(V_src) > 1.5 * coarse_vertices:
        Vc, Fc = _decimate(V_src, F_src, coarse_vertices)
        Xc, _, (ts, tf) = _fit(Vc, Fc, V_tgt, F_tgt, P, Q, tps, None, stages, iterations, *args)
        X0 = tps.transform(V_src) + _interpolate(Vc, Fc, Xc - tps.transform(Vc), V_src, F_src)
        t_setup, t_fit = ts, tf
        stages, iterations = fine_schedule
    X, labels, (ts, tf) = _fit(V_src, F_src, V_tgt, F_tgt, P, Q, tps, X0, stages, iterations, *args)
    return X, labels, t_setup + ts, t_fit + tf


def _landmark_pairs(lm_src, lm_tgt):
    """Source and target landmarks as row-paired (k, 3) arrays (dicts paired by name)."""
    if isinstance(lm_src, dict) or isinstance(lm_tgt, dict):
        if not (isinstance(lm_src, dict) and isinstance(lm_tgt, dict)):
            raise AutobonesError("give both landmark sets as dicts {name: [x, y, z]} or both as (k, 3) arrays")
        _, P, Q = landmark_arrays(lm_src, lm_tgt)
        return P, Q
    return as_points(lm_src, "source landmarks"), as_points(lm_tgt, "target landmarks")


def dense_correspondence(V_src, F_src, V_tgt, F_tgt, lm_src, lm_tgt, timings=None, **kwargs):
    """Source vertex -> point on the target surface: :func:`fit_surface` then a final stick.

    Parameters
    ----------
    V_src, F_src, V_tgt, F_tgt, lm_src, lm_tgt
        As in :func:`fit_surface` (each mesh in its own frame and units).
    timings : dict, optional
        Filled with seconds per step: ``tps``, ``setup``, ``fit``, ``stick``.
    **kwargs
        Passed to :func:`fit_surface`.

    Returns
    -------
    P : (n, 3) float64
        Corresponding points on the target surface (target units).
    face : (n,) int64
        Target face of each point.
    bary : (n, 3) float64
        Barycentric coordinates in that face.
    reliable : (n,) bool
        False where :func:`autobones.rig_transfer.stick.stick` detected a fold.
    """
    X, labels = fit_surface(V_src, F_src, V_tgt, F_tgt, lm_src, lm_tgt, timings=timings, **kwargs)
    t0 = time.perf_counter()
    F_tgt = np.asarray(F_tgt, dtype=np.int64)
    face_labels = mesh_parts(len(V_tgt), F_tgt)[F_tgt[:, 0]] if (labels >= 0).any() else None
    out = stick(X, F_src, V_tgt, F_tgt, labels=labels if face_labels is not None else None, face_labels=face_labels)
    if timings is not None:
        timings["stick"] = time.perf_counter() - t0
    return out
