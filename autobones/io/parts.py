"""Parts of a mesh rigged apart from the head and put back: small parts far from it (a stray
triangle, a dropped prop) and lumps set on it (a hat).

``place`` and ``transfer`` rig the head without them, then give the rig back every input vertex
(:meth:`LeftOut.restore`): a far part weighted to the root bone, a part set on the head weighted as
the skin nearest each of its vertices, so it rides the head as the skin under it does.
"""
from __future__ import annotations

import logging

import numpy as np

from ..geometry.topology import used_vertices

log = logging.getLogger("autobones")


# Small parts far from the head (a stray triangle, a dropped prop) would, like an outlier, decide the
# bounding box: a part whose area is under STRAY_AREA of the mesh's and whose bounding box lies more
# than STRAY_REACH times the body's largest side from the body's box is dropped, as long as all such
# parts together stay under STRAY_AREA (more than that is a mess, refused as outliers). The body is
# the largest part by area and every part within that reach of it, grown until nothing more joins.
# All fractions: the rule is scale-free.
STRAY_AREA = 0.01
STRAY_REACH = 1.0
# Several heads in one file (a lineup, a sheet of variants): parts covering SIDE_SHARE of the area or
# more each whose bounding boxes stand apart by SIDE_GAP of the larger box's side or more. Rigged as
# one head, the frame is found across them (two default heads side by side came out up +z, front +y)
# and every joint lies between them. A head modelled apart from the body it sits on, a hat, eyes and
# teeth touch or overlap the head's box (the held-out dwarf's head and body: gap 0; no shared head
# has two such parts apart). A part of fewer than SIDE_FACES triangles is no head: a scan decimated to
# a wreck (the robot at 23 triangles, 9 fragments, two of them 30 % and 21 % of the area) is rigged.
SIDE_SHARE = 0.2
SIDE_GAP = 0.1
SIDE_FACES = 50


class NamedMesh:
    """Arrays ``vertices`` (n, 3) and ``faces`` (m, 3) with the ``source`` file name (str or None) their
    messages name (:func:`autobones.io.mesh.resolve_mesh` takes it as a mesh object)."""

    def __init__(self, vertices, faces, source=None):
        self.vertices, self.faces, self.source = vertices, faces, source


class LeftOut:
    """Parts of a mesh left out of rigging (:func:`stray_parts`, :func:`worn_parts`) and the body
    rigged without them.

    Attributes
    ----------
    worn : bool
        Parts set on the head (:func:`worn_parts`), not far from it.
    index : (k,) int64
        The body's vertices (every vertex not on a left-out part), in input order.
    V, F : (k, 3) float64, (m', 3) int64
        The body as a mesh of its own (``V = V_in[index]``).
    record : dict
        ``parts``, ``vertices``, ``faces`` dropped and their ``area_fraction``, for the sidecar.
    """

    def __init__(self, V, F, body_vertex, stray_face, area_fraction, parts, worn=False):
        self.V_in, self.F_in, self.worn = V, F, worn
        self.index = np.flatnonzero(body_vertex)
        remap = np.full(len(V), -1, dtype=np.int64)
        remap[self.index] = np.arange(len(self.index))
        self.V, self.F = V[self.index], remap[F[~stray_face]]
        self.record = {"parts": int(parts), "vertices": int(len(V) - len(self.index)),
                       "faces": int(stray_face.sum()), "area_fraction": round(float(area_fraction), 6)}

    def as_mesh(self, source=None):
        """The body as a mesh argument that keeps the file's name ``source`` (str or None) for the
        messages of the rigging it goes through (``place`` and ``transfer`` take it as a mesh)."""
        return NamedMesh(self.V, self.F, source)

    def restore(self, rig, source=None):
        """``rig`` (rigged on the body) back on every input vertex, in input order: the left-out
        vertices weighted 1 to the root bone (the neck; far parts) or as their nearest body vertex
        (parts set on the head, which ride it as the skin under them), 0 in float fields, morph targets
        and the facial mask, and the labels of their nearest body vertex; ``options['dropped_parts']``
        or ``options['worn_parts']``. ``rig.segmentation`` (``place``'s depth grouping) stays the
        body's, one row per ``index``."""
        from scipy.spatial import cKDTree

        n, keep = len(self.V_in), self.index
        gone = np.setdiff1d(np.arange(n), keep, assume_unique=True)
        near = keep[cKDTree(self.V).query(self.V_in[gone])[1]] if len(gone) else gone

        def full(A):
            A = np.asarray(A)
            out = np.zeros((n,) + A.shape[1:], dtype=A.dtype)
            out[keep] = A
            if np.issubdtype(A.dtype, np.integer):   # a label: the nearest body vertex's
                out[gone] = out[near]
            return out

        root = int(np.flatnonzero(np.asarray(rig.skeleton.parents) < 0)[0])
        W = full(rig.weights)
        if self.worn:
            W[gone] = W[near]
        else:
            W[gone, root] = 1.0
        rig.weights, rig.vertices, rig.faces = W, self.V_in, self.F_in
        rig.labels, rig.facial_mask = full(rig.labels), full(rig.facial_mask)
        rig.fields = {k: full(v) for k, v in (rig.fields or {}).items()}
        if getattr(rig, "arkit_targets", None):
            rig.arkit_targets = {k: full(v) for k, v in rig.arkit_targets.items()}
        rig.source = source if source is not None else rig.source
        r = self.record
        if self.worn:
            rig.options["worn_parts"] = {**r, "weighted_as": "the nearest skin"}
            log.warning("%s: rigged without %d separate part%s set on it (a hat, a pad: %d vertices, %.2g%% of "
                        "the area), then weighted as the skin nearest each vertex", source or "mesh", r["parts"],
                        "s" if r["parts"] > 1 else "", r["vertices"], 100 * r["area_fraction"])
            return rig
        rig.options["dropped_parts"] = {**r, "weighted_to": rig.skeleton.names[root]}
        log.warning("%s: dropped %d small part%s far from the head (%d vertices, %d faces, %.2g%% of the "
                    "area), weighted to the %s bone", source or "mesh", r["parts"], "s" if r["parts"] > 1 else "",
                    r["vertices"], r["faces"], 100 * r["area_fraction"], rig.skeleton.names[root])
        return rig


def stray_parts(V, F):
    """The parts of ``(V, F)`` to leave out of rigging by the stray rule (:data:`STRAY_AREA`,
    :data:`STRAY_REACH`): a :class:`LeftOut`, or None when there are none (or too many).

    Parts are connected through shared positions (an unwelded head is one body). ``V`` (n, 3)
    float, ``F`` (m, 3) int, any unit.
    """
    from ..geometry.areas import triangle_areas
    from ..geometry.topology import mesh_parts

    V, F = np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64)
    used = used_vertices(F, len(V))
    if not len(used):
        return None
    span = float(np.ptp(V[used], axis=0).max()) or 1.0
    # connectivity through positions: vertices on a grid far finer than any edge are one
    _, index = np.unique(np.round(V / (1e-9 * span)).astype(np.int64), axis=0, return_inverse=True)
    index = index.ravel()
    part = mesh_parts(int(index.max()) + 1, index[F])[index]          # per input vertex
    face_part = part[F[:, 0]]
    area = triangle_areas(V, F)
    part_area = np.bincount(face_part, area, minlength=part.max() + 1)
    total = float(part_area.sum())
    if not total > 0:
        return None
    lo = np.full((len(part_area), 3), np.inf)
    hi = np.full((len(part_area), 3), -np.inf)
    np.minimum.at(lo, part[used], V[used])
    np.maximum.at(hi, part[used], V[used])
    body = np.zeros(len(part_area), dtype=bool)
    body[np.argmax(part_area)] = True
    while True:   # the body's box grows by its own size at least each round: a few rounds
        blo, bhi = lo[body].min(axis=0), hi[body].max(axis=0)
        gap = np.linalg.norm(np.maximum(np.maximum(lo - bhi, blo - hi), 0.0), axis=1)
        grown = body | (np.isfinite(gap) & (gap <= STRAY_REACH * float((bhi - blo).max())))
        if (grown == body).all():
            break
        body = grown
    stray = ~body & np.isfinite(lo[:, 0])
    dropped = float(part_area[stray].sum())
    if not stray.any() or dropped >= STRAY_AREA * total:
        return None
    return LeftOut(V, F, ~stray[part] | ~np.isin(np.arange(len(V)), used), stray[face_part], dropped / total,
                   int(stray.sum()))


def parts_apart(V, F):
    """The large parts of ``(V, F)`` that stand apart (:data:`SIDE_SHARE`, :data:`SIDE_GAP`,
    :data:`SIDE_FACES`): several heads in one file. Returns None, or ``(shares, gap)``: each such
    part's share of the area (k,), largest first, and the largest gap between two of their boxes in
    the larger box's sides.

    Parts are connected through shared positions (:func:`~autobones.geometry.topology.weld_by_size`).
    ``V`` (n, 3) float, ``F`` (m, 3) int, any unit and frame.
    """
    from ..geometry.topology import part_areas, weld_by_size

    Vw, Fw, _ = weld_by_size(np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64))
    part, area = part_areas(Vw, Fw)
    faces = np.bincount(part[Fw[:, 0]], minlength=len(area))
    big = np.flatnonzero((area >= SIDE_SHARE * area.sum()) & (faces >= SIDE_FACES))
    if len(big) < 2:
        return None
    used = used_vertices(Fw, len(Vw))
    lo = np.full((len(area), 3), np.inf)
    hi = np.full((len(area), 3), -np.inf)
    np.minimum.at(lo, part[used], Vw[used])
    np.maximum.at(hi, part[used], Vw[used])
    lo, hi = lo[big], hi[big]
    gap = np.linalg.norm(np.maximum(np.maximum(lo[:, None] - hi[None], lo[None] - hi[:, None]), 0.0), axis=2)
    side = (hi - lo).max(axis=1)
    gap = gap / np.maximum(side[:, None], side[None])
    if gap.max() < SIDE_GAP:
        return None
    apart = big[(gap >= SIDE_GAP).any(axis=1)]
    return np.sort(area[apart] / area.sum())[::-1], float(gap.max())


def worn_parts(V, F):
    """The lumps set on the head (a hat, a bun, a shoulder pad: a part covering a tenth of the area or
    more, mostly outside the widest part's convex hull and at most half its area; see
    :func:`autobones.geometry.topology.large_parts`) as a :class:`LeftOut` whose ``restore`` weights
    them as the skin nearest them, or None when there are none. Rigged with the head, a ball of 0.15
    head sizes on the crown moved ``place``'s head and neck joints 0.07-0.29 head sizes (the goat, the
    SMPL man, ICT). Hair spread over the head (which :func:`autobones.orient.detect_frame` also leaves
    out) is rigged with the head, as before.

    ``V`` (n, 3) float, ``F`` (m, 3) int, any unit.
    """
    from ..geometry.areas import triangle_areas
    from ..geometry.topology import large_parts

    V, F = np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64)
    drop, part = large_parts(V, F, reach=np.inf)   # lumps only, no spread shells
    if not drop.any():
        return None
    body = np.zeros(len(V), dtype=bool)
    body[F[~drop].ravel()] = True
    body |= ~np.isin(np.arange(len(V)), used_vertices(F, len(V)))   # unused vertices stay, as in stray_parts
    area = triangle_areas(V, F)
    return LeftOut(V, F, body, drop, float(area[drop].sum() / area.sum()), len(np.unique(part[drop])), worn=True)
