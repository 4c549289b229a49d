"""Carry per-vertex attribute fields from a source surface onto a target mesh.

Orvalho, Zacur & Susin 2008, §3.5: once the generic surface is stuck onto the target (a dense
correspondence), each target vertex takes the field at its closest point on
the stuck generic surface, by barycentric interpolation; label fields take the
label of the dominant vertex of that triangle.

Beyond Orvalho et al.: where that match is unreliable (the target vertex is far from the
stuck surface, its normal disagrees with it, or the generic vertex there was
marked as folded) copying would spread garbage, so the field is filled in
smoothly from the reliable neighbours instead: harmonic inpainting, the
Laplace equation on the target mesh with the reliable values as boundary
conditions (as in weight inpainting for skin transfer, Abdrashitov et al. 2023).

Vector fields (displacements, normals, directions) are not plain numbers: a
displacement copied as such points the wrong way on a head that lies on its side
or is rotated locally. They are turned into the target's frame by the local
rotation of the correspondence at each match (:func:`local_frames`), and
displacements are also scaled by its local scale, before any inpainting.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import AutobonesError, counted
from ..geometry.closest import closest_points
from ..geometry.laplacian import clipped_cotangent_laplacian, factor_spd
from ..geometry.rotations import polar_rotations
from ..geometry.topology import weld


def sample_fields(V_src, F_src, P):
    """Closest point of ``P`` on the source surface, as face and barycentric coordinates.

    Parameters
    ----------
    V_src : (n, 3) float
        Source vertices (e.g. the generic surface stuck onto the target).
    F_src : (m, 3) int
        Source triangles.
    P : (k, 3) float
        Query points (e.g. target vertices), same frame as ``V_src``.

    Returns
    -------
    face : (k,) int
    bary : (k, 3) float
    distance : (k,) float
    """
    C, face, bary = closest_points(P, V_src, F_src)[:3]
    return face, bary, np.linalg.norm(C - P, axis=1)


def local_frames(V_rest, V_stuck, F, face):
    """Rotation and scale of the correspondence at matched source triangles.

    For each source triangle ``face[i]``, the linear map ``J`` taking its rest edges and unit
    normal ``[e1 e2 n]`` to its stuck edges and unit normal ``[e1' e2' n']`` (the triangle's
    deformation gradient, extended along the normal) is split by polar decomposition:
    ``R`` is the rotation nearest to ``J`` (so a shear or an anisotropic stretch of the
    triangle does not tilt vectors, and no choice of tangent edge biases it) and the scale
    is ``sqrt(area' / area)``. A rigid motion with uniform scale ``s`` of the whole source
    gives exactly that rotation and ``s`` at every triangle. Degenerate (zero-area) triangles
    give the identity and scale 1.

    Parameters
    ----------
    V_rest : (n, 3) float
        Source vertices in the source's own frame and units.
    V_stuck : (n, 3) float
        The same vertices placed on the target (target frame and units).
    F : (m, 3) int
        Source triangles.
    face : (k,) int
        Triangles to evaluate.

    Returns
    -------
    R : (k, 3, 3) float
        Rotations (det +1), source frame -> target frame: ``v_target = R @ v_source``.
    scale : (k,) float
        Target length per source length.
    """
    def frame(V):
        T = V[F[face]]
        e1, e2 = T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]
        n = np.cross(e1, e2)
        area = np.linalg.norm(n, axis=1)
        return np.stack([e1, e2, n / np.maximum(area, 1e-300)[:, None]], axis=2), area

    A, area_rest = frame(np.asarray(V_rest, dtype=np.float64))
    B, area_stuck = frame(np.asarray(V_stuck, dtype=np.float64))
    ok = (area_rest > 1e-12 * max(area_rest.max(initial=0.0), 1e-300)) & (area_stuck > 0)
    eye = np.broadcast_to(np.eye(3), A.shape)
    J = np.where(ok[:, None, None], B, eye) @ np.linalg.inv(np.where(ok[:, None, None], A, eye))
    R = polar_rotations(J)
    scale = np.where(ok, np.sqrt(area_stuck / np.where(ok, area_rest, 1.0)), 1.0)
    return R, scale


def inpaint(V, F, values, known):
    """Harmonic fill of ``values`` where ``known`` is False.

    Parameters
    ----------
    V : (n, 3) float
        Mesh vertices.
    F : (m, 3) int
        Triangles (several parts and unwelded faces are fine: vertices are welded
        by position first).
    values : (n,) or (n, k) float
        Field values; only the known rows are used.
    known : (n,) bool
        Rows to keep.

    Returns
    -------
    (n,) or (n, k) float
        ``values`` on known rows; elsewhere the solution of the Laplace equation
        with the known rows fixed. A part with no known vertex takes the value of
        the nearest known vertex.
    """
    values = np.asarray(values, dtype=np.float64)
    flat = values.ndim == 1
    X = values[:, None] if flat else values.copy()
    known = np.asarray(known, dtype=bool)
    if known.all():
        return values.copy()
    if not known.any():
        raise AutobonesError("no reliable correspondence at all: are the landmarks on the right heads?")
    extent = np.ptp(V, axis=0).max()
    Vw, Fw, index = weld(V, F, 1e-9 * extent)
    # a welded vertex is known if any of its copies is
    kw = np.zeros(len(Vw), dtype=bool)
    kw[index[known]] = True
    Xw = np.zeros((len(Vw), X.shape[1]))
    Xw[index[known]] = X[known]
    # the Laplacian of the triangles at unknown vertices only: their rows are complete, and on a
    # scan whose reliable part is most of it that is a fraction of the cost
    Fu = Fw[(~kw[Fw]).any(axis=1)]
    used = np.zeros(len(Vw), dtype=bool)
    used[Fu.ravel()] = True
    # the clipped cotangent Laplacian: a fill needs an M-matrix, not the intrinsic rebuild's accuracy
    L = clipped_cotangent_laplacian(Vw[used], np.cumsum(used)[Fu] - 1) if len(Fu) else None
    sub = np.flatnonzero(used)
    unknown = sub[~kw[sub]]
    if len(unknown) and L is not None:
        pos = np.full(len(Vw), -1)
        pos[sub] = np.arange(len(sub))
        u, k = pos[unknown], pos[sub[kw[sub]]]
        L = L.tocsr()
        Luu, Luk = L[u][:, u], L[u][:, k]
        # parts with no known vertex make Luu singular: pin them with a tiny diagonal,
        # then give them the nearest known value below
        reach = _reaches_known(L, u, k)
        Luu = (Luu + sp.diags(np.where(reach, 0.0, 1.0))).tocsc()
        Xk = Xw[sub[kw[sub]]]
        # a column constant on the known vertices around the gap fills with that constant: only the
        # others need the solve (label columns absent there, and weights of bones far from it)
        flat_col = (Xk == Xk[:1]).all(axis=0) if len(Xk) else np.ones(Xk.shape[1], dtype=bool)
        fill = np.zeros((len(u), Xk.shape[1]))
        if len(Xk):
            fill[:] = Xk[0]
        if (~flat_col).any():
            rhs = -(Luk @ Xk[:, ~flat_col])
            rhs[~reach] = 0.0
            fill[:, ~flat_col] = factor_spd(Luu)(np.ascontiguousarray(rhs))
        fill[~reach] = 0.0
        Xw[unknown] = fill
        kw[unknown[reach]] = True
    if not kw.all():
        from scipy.spatial import cKDTree

        _, j = cKDTree(Vw[kw]).query(Vw[~kw], workers=-1)
        Xw[~kw] = Xw[kw][j]
    out = Xw[index]
    out[known] = X[known]
    return out[:, 0] if flat else out


def _reaches_known(L, u, k):
    """(len(u),) bool: unknown vertices connected to some known vertex."""
    from scipy.sparse.csgraph import connected_components

    _, comp = connected_components(L, directed=False)
    good = np.zeros(comp.max() + 1, dtype=bool)
    good[comp[k]] = True
    return good[comp[u]]


def transfer_fields(V_stuck, F_src, fields, V_tgt, F_tgt, source_reliable=None, max_distance=0.02,
                    max_angle=60.0, vectors=(), directions=(), V_rest=None):
    """Fields on the stuck source surface -> fields on the target vertices.

    Parameters
    ----------
    V_stuck : (n, 3) float
        Source vertices placed on the target surface (dense correspondence), target frame.
    F_src : (m, 3) int
        Source triangles.
    fields : dict of str -> (n,) or (n, k) array
        Source fields. Integer fields are labels (the dominant vertex's label);
        float fields are interpolated barycentrically.
    V_tgt : (n_t, 3) float
        Target vertices.
    F_tgt : (m_t, 3) int
        Target triangles.
    source_reliable : (n,) bool, optional
        Source vertices whose correspondence is trusted (e.g. not folded).
    max_distance : float
        A target vertex farther than this (fraction of the target's size) from
        the stuck surface is unreliable.
    max_angle : float
        Degrees; a target vertex whose normal differs more from the stuck
        surface's is unreliable.
    vectors, directions : sequence of str
        Names of (n, 3) float fields that are vectors in the source frame: each
        interpolated vector is turned by the correspondence's local rotation at the
        match (:func:`local_frames`); ``vectors`` (displacements, in source units) are
        also multiplied by its local scale, ``directions`` (normals, unit directions) are not.
    V_rest : (n, 3) float
        Source vertices in the source's own frame; needed with ``vectors`` or ``directions``.

    Returns
    -------
    out : dict of str -> array
        The same keys, one row per target vertex.
    reliable : (n_t,) bool
        Target vertices that copied their value (the rest were inpainted).
    """
    from ..geometry.normals import triangle_normals, vertex_normals

    from .stick import facing_face

    size = _extent(V_tgt)
    V_stuck = np.asarray(V_stuck, dtype=np.float64)
    face, bary, dist = sample_fields(V_stuck, F_src, V_tgt)
    n_tgt = vertex_normals(V_tgt, F_tgt)
    # a target vertex on a stuck edge or corner (where the generic was stuck onto that very vertex)
    # belongs to every stuck face there, and rounding picked one: on a fold they face opposite ways
    face, bary = facing_face(np.einsum("ki,kij->kj", bary, V_stuck[F_src[face]]), face, bary, V_stuck, F_src, n_tgt)
    n_src = triangle_normals(V_stuck, F_src)[face]
    n_src /= np.maximum(np.linalg.norm(n_src, axis=1, keepdims=True), 1e-300)
    cos = (n_src * n_tgt).sum(axis=1)
    reliable = (dist <= max_distance * size) & (cos >= np.cos(np.radians(max_angle)))
    corners = F_src[face]
    dominant = corners[np.arange(len(face)), np.argmax(bary, axis=1)]
    if source_reliable is not None:  # the source vertex that dominates the match must be trusted
        reliable &= np.asarray(source_reliable, dtype=bool)[dominant]
    turn = _vector_turns(V_rest, V_stuck, F_src, face, fields, vectors, directions)
    # every field becomes columns of one matrix, so one factorisation inpaints them all
    columns, layout = [], []
    for name, field in fields.items():
        field = np.asarray(field)
        if np.issubdtype(field.dtype, np.integer) or field.dtype == bool:
            lab = field[dominant]
            classes = np.unique(field)
            columns.append((lab[:, None] == classes[None, :]).astype(np.float64))
            layout.append((name, "labels", field.dtype, classes, lab))
        else:
            vals = np.einsum("ki,ki...->k...", bary, field[corners].astype(np.float64))
            if name in turn:  # into the target frame before inpainting, which mixes neighbours
                vals = np.einsum("kij,kj->ki", turn[name], vals)
            columns.append(vals.reshape(len(face), -1))
            layout.append((name, "values", field.dtype, field.shape[1:], None))
    filled = inpaint(V_tgt, F_tgt, np.concatenate(columns, axis=1), reliable) if columns else None
    out, at = {}, 0
    for (name, kind, dtype, extra, lab), col in zip(layout, columns):
        block = filled[:, at:at + col.shape[1]]
        at += col.shape[1]
        if kind == "labels":
            out[name] = np.where(reliable, lab, extra[np.argmax(block, axis=1)]).astype(dtype)
        else:
            out[name] = block.reshape((len(face),) + tuple(extra))
    return out, reliable


def _extent(V):
    """The largest extent of ``V`` (n, 3) along its principal axes (its units): the bounding box's
    largest side in a frame that turns with the mesh, so a turned head gets the same tolerance."""
    V = np.asarray(V, dtype=np.float64)
    C = V - V.mean(axis=0)
    return float(np.ptp(C @ np.linalg.eigh(C.T @ C)[1], axis=0).max())


def _vector_turns(V_rest, V_stuck, F_src, face, fields, vectors, directions):
    """{field name: (k, 3, 3) matrix applied to its interpolated vectors} for ``vectors`` and ``directions``."""
    names = list(vectors) + list(directions)
    if not names:
        return {}
    for name in names:
        if name not in fields:
            raise AutobonesError(f"vector field {name!r} is not among the fields ({', '.join(fields) or 'none'})")
        f = np.asarray(fields[name])
        if f.ndim != 2 or f.shape[1] != 3 or not np.issubdtype(f.dtype, np.floating):
            raise AutobonesError(f"vector field {name!r} must be (n, 3) floats, got {f.shape} {f.dtype}")
    if V_rest is None:
        raise AutobonesError("vector fields need the source's rest vertices (V_rest)")
    R, scale = local_frames(V_rest, V_stuck, F_src, face)
    return {name: R * scale[:, None, None] if name in vectors else R for name in names}


def transfer_attributes(source_mesh, target_mesh, fields, source_landmarks, target_landmarks, vectors=(),
                        directions=(), **fit_options):
    """Transfer per-vertex fields from one landmarked mesh to another.

    Parameters
    ----------
    source_mesh, target_mesh : path, (V, F) pair or mesh object
        Each in its own frame and units (see :func:`autobones.io.mesh.resolve_mesh`).
    fields : dict of str -> (n_src,) or (n_src, k) array
        Per source vertex; integer arrays are labels.
    source_landmarks, target_landmarks : dict of str -> (3,) or landmark file paths
        Paired by name (at least 10 shared names recommended).
    vectors : sequence of str
        (n_src, 3) float fields that are displacements in the source's frame and units:
        they arrive in the target's frame and units, turned and scaled by the
        correspondence's local rotation and scale (:func:`local_frames`).
    directions : sequence of str
        (n_src, 3) float fields that are directions (normals): turned, not scaled.

    Returns
    -------
    dict of str -> array, one row per target vertex.

    Examples
    --------
    The default head's height and an upper/lower label, carried onto the scan:

    >>> import autobones
    >>> from autobones import samples
    >>> V, F = autobones.load_mesh(samples.path("default_head.obj"))
    >>> fields = {"height": V[:, 1], "upper": (V[:, 1] > 0).astype(int)}
    >>> out = autobones.transfer_attributes((V, F), samples.path("scan.obj"), fields,
    ...                                     samples.path("default_head.landmarks.json"),
    ...                                     samples.path("scan.landmarks.json"))
    >>> n = len(autobones.load_mesh(samples.path("scan.obj"))[0])
    >>> out["height"].shape == (n,), out["upper"].dtype.kind, sorted(set(out["upper"].tolist()))
    (True, 'i', [0, 1])
    """
    from .correspondence import dense_correspondence
    from ..io.landmarks import resolve_landmarks
    from ..io.mesh import resolve_mesh, wound_outward

    Vs, Fs, what_s = resolve_mesh(source_mesh)
    Vt, Ft, what_t = resolve_mesh(target_mesh)
    # the fit matches normals: either mesh inside out is fitted outward (the fields are per vertex)
    Fs, Ft = wound_outward(Vs, Fs, what_s)[0], wound_outward(Vt, Ft, what_t)[0]
    for name, f in fields.items():
        if len(f) != len(Vs):
            raise AutobonesError(f"field {name!r} has {counted(len(f), 'row')}; the source mesh has {counted(len(Vs), 'vertex', 'vertices')}")
    P, _, _, ok = dense_correspondence(Vs, Fs, Vt, Ft, resolve_landmarks(source_landmarks)[0], resolve_landmarks(target_landmarks)[0], **fit_options)
    out, _ = transfer_fields(P, Fs, fields, Vt, Ft, source_reliable=ok, vectors=vectors, directions=directions,
                             V_rest=Vs)
    return out
