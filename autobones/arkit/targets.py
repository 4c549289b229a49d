"""The 52 ARKit shapes of one transferred rig: displacement fields on its own vertices.

Goes beyond the seeds (issue #15). The packaged source shapes (:mod:`.shapes`, ICT-FaceKit's
neutral skin) are tied to the head by one more dense correspondence (ICT's 27 contract
landmarks onto the rig's; :func:`autobones.rig_transfer.correspondence.dense_correspondence`)
and carried by deformation transfer (:mod:`.deformation_transfer`), one factorisation for all.

Eyes: a head with separate eyeballs (vertices bound wholly to the ``eye_l`` / ``eye_r`` bones
by :func:`autobones.rig_transfer.eyes.bind_eyeballs`) keeps them out of the skin solve, and the
eyeLook* shapes turn them rigidly about their eye bone by :data:`EYE_TURN_DEG` (ICT's own
eyeLook shapes move the lids and eye shells, not its eyeballs, which ICT turns by joints; the
angles are chosen, not measured). On a one-surface scan the eye surface between the lids is
one with them: its triangles (:func:`.fissures.eye_fissures`) are set free in the solve so the lids can
close over it (held rigid, it kept them apart), and where the gradients still leave the lids
apart (james's left eye: its blink closed 33 % of the gap vertically, ICT's own 82 %) the
shapes that move the lids are solved again with the opening's vertices placed where the
source's lids go (:mod:`.lids`: 79 %); the eyeLook* shapes move the lids and that surface as
the skin transfer gives, with no turn.
``tongueOut`` (ICT has none) is an all-zero target, recorded as absent.
"""
from __future__ import annotations

import logging
import time

import numpy as np

from ..errors import AutobonesError, counted
from ..geometry.rotations import similarity
from ..geometry.topology import mesh_parts
from .copy_baseline import copy_displacements
from .deformation_transfer import DeformationTransfer
from .fissures import eye_fissures, mouth_fissure
from .folds import ON_TOP, folded_triangles, unfold_shapes
from ..rig_transfer.eyes import fit_sphere
from .lid_meet import BLINK_CLOSED, lids_note, meet_lids
from .lids import LidClosure
from .names import ARKIT_NAMES, EYE_LOOK
from .shapes import MIN_LANDMARKS, flipped_triangles, load_shapes

log = logging.getLogger(__name__)

# eyeball turn at weight 1, degrees, in the head's canonical frame (+X subject's left, +Y up, +Z front)
EYE_TURN_DEG = {"Up": 25.0, "Down": 30.0, "In": 30.0, "Out": 30.0}
# the shape set's correspondence onto the head: a lighter schedule than transfer's (two updates per
# stage, a 5k coarse copy, one full-resolution update): on 4 remeshed ICT identities the explained
# fraction is the same (skin mean 94.9 %, worst shape 84.9 %, against 94.8 / 84.9 with transfer's)
# in 1.0-1.1 s instead of 1.3-1.6 (benchmarks/arkit.py)
CORRESPONDENCE = dict(iterations=2, coarse_vertices=5000, fine_iterations=1)


def eye_turn(name, frame_rotation):
    """Rotation (3, 3) of the eyeball for eyeLook ``name`` at weight 1, in the input frame.

    ``frame_rotation``: rows are the head's left, up and front in the input frame
    (:attr:`autobones.orient.Frame.turn_axes`: a transferred rig's anatomical axes).
    """
    side = "Left" if name.endswith("Left") else "Right"
    way = name[len("eyeLook"):-len(side)]
    a = np.radians(EYE_TURN_DEG[way])
    c, s = np.cos(a), np.sin(a)
    if way in ("Up", "Down"):
        a = -a if way == "Up" else a          # about +X: +Z (gaze) toward +Y is a negative turn
        c, s = np.cos(a), np.sin(a)
        Rc = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    else:
        # toward +X (subject's left) is a positive turn about +Y; the left eye looks out to +X
        toward_left = (way == "Out") == (side == "Left")
        s = s if toward_left else -s
        Rc = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    Rf = np.asarray(frame_rotation, dtype=np.float64)
    return Rf.T @ Rc @ Rf


def eyeball_vertices(rig):
    """``{"eye_l": mask, "eye_r": mask}`` of vertices bound wholly to an eye bone in separate parts (n,) bool."""
    names = rig.skeleton.names
    part = mesh_parts(len(rig.vertices), rig.faces)
    main = np.argmax(np.bincount(part))
    out = {}
    for eye in ("eye_l", "eye_r"):
        if eye in names:
            m = (np.asarray(rig.weights)[:, names.index(eye)] >= 0.999) & (part != main)
            if m.any():
                out[eye] = m
    return out


def deformation_targets(shapes, deltas, P, V, F, landmarks, one_surface=None, keep=None, timings=None,
                        close_lids=True, frame=None, free_lips=True):
    """Deformation transfer of a shape set onto a head, lids closed as the source's on a one-surface head.

    Parameters
    ----------
    shapes : ShapeSet
        The source (:func:`load_shapes`); ``deltas`` (k, n_s, 3) its displacements to carry.
    P : (n_s, 3) float
        Each source vertex's point on the head (the dense correspondence), head frame and units.
    V : (n, 3) float, F : (m, 3) int
        The head, input frame and units.
    landmarks : dict str -> (3,)
        The head's landmarks (the eye's four name its lid margins).
    one_surface : Frame or None
        The head's frame when its lids and visible eye are one surface (no separate eyeballs):
        then the eye surface between the lids is set free (:func:`.fissures.eye_fissures`) and the shapes
        that open or close the eyes are solved again with the opening's vertices placed where the
        source's lids go (:class:`autobones.arkit.lids.LidClosure`). None: a head with eyeballs.
    keep : (n,) bool, optional
        Vertices held at 0 (separate eyeballs).
    timings : dict, optional
        Filled with seconds: ``map``, ``factor``, ``solve``, ``lids``.
    close_lids : bool
        False: on a one-surface head only set the eye surface free (for comparison).
    frame : Frame, optional
        The head's frame (:class:`autobones.orient.Frame`; ``one_surface`` when that is given):
        with it the triangles across a closed mouth's lip line are set free (:func:`.fissures.mouth_fissure`)
        so the lips can part, on any head (a head whose mouth is open has none).
    free_lips : bool
        False: the lip line's triangles held as the rest (for comparison).

    Returns
    -------
    (k, n, 3) float64
        Displacements, input frame and units.
    """
    S, D = shapes, np.asarray(deltas, dtype=np.float64)
    moving = np.linalg.norm(D, axis=2).max(axis=0) > 0
    free = lids = None
    if one_surface is not None:
        # the scan's eye surface between the lids takes no gradient
        free = eye_fissures(V, F, landmarks, one_surface)
        if close_lids:
            lids = LidClosure().fit(S.vertices, S.faces, S.landmarks, V, F, landmarks)
    frame = one_surface if frame is None else frame
    if free_lips and frame is not None:  # nor the triangles joining a closed mouth's lips
        lips = mouth_fissure(V, F, landmarks, frame)
        free = lips if free is None else free | lips
    pinned = None if lids is None else lids.vertices_
    dt = DeformationTransfer().fit(S.vertices, S.faces, P, V, F, moving=moving, free=free, pinned=pinned)
    X = dt.transform(D, keep=keep)
    tim = dict(dt.timings_)
    if lids is not None and len(lids.vertices_):
        # the gradients alone keep a one-surface scan's lids apart: where they do (not on a head
        # whose lids are modelled), the shapes that open or close the eyes are solved again, the
        # opening's vertices placed where the source's lids go (the upper margin down to the lower
        # one in a blink) and the lower lid where the gradients put it
        t = time.perf_counter()
        need = lids.needed(D, X)
        sel = np.flatnonzero(lids.moving_shapes(D)) if need.any() else []
        if len(sel):
            X[sel] = dt.transform(D[sel], keep=keep, pins=lids.targets(D[sel], X[sel], need))
        tim["lids"] = time.perf_counter() - t
    if timings is not None:
        timings.update(tim)
    return X


def rig_shape_set(rig_option):
    """The shape set of a rig folder (``rig.options['rig']``, a transfer's ``--rig``) when ``build-rig
    --shapes`` gave it one, else the packaged ICT-FaceKit set (:func:`load_shapes`)."""
    from .studio import rig_shapes_folder

    return load_shapes(rig_shapes_folder(rig_option))


def shared_landmarks(shapes, landmarks):
    """Names of the shape set's landmarks the head also has (the set's order); an error below
    :data:`MIN_LANDMARKS`."""
    shared = [n for n in shapes.landmarks if n in landmarks]
    if len(shared) < MIN_LANDMARKS:
        raise AutobonesError(f"ARKit shapes: the rig has {counted(len(shared), 'landmark')} shared with the shape set "
                             f"({', '.join(shared) or 'none'}); at least {MIN_LANDMARKS} are needed "
                             "(make the rig with autobones transfer)")
    return shared


def shape_correspondence(shapes, V, F, landmarks, **fit_options):
    """Each vertex of the shape set's skin on the head: ``P`` (n_s, 3) float64 (head frame and units) and
    the landmark names it was fitted on.

    :func:`autobones.rig_transfer.correspondence.dense_correspondence` of ``shapes`` (a ShapeSet) onto
    ``V`` (n, 3), ``F`` (m, 3) from the landmarks both have (``landmarks``: name -> (3,), head frame),
    with :data:`CORRESPONDENCE` and then ``fit_options``. Depends only on the head and its
    landmarks: ``transfer --arkit`` runs it beside its own fit of the generic rig. The set's skin is
    fitted neutral, also on an expressive head: deformation transfer carries each shape from the
    set's neutral skin to the head's rest, so the two must correspond as they are (fitted wearing the
    head's open jaw, ICT's jawOpen then opened it again: folds before the repair 14 -> 92, the shapes
    2.6 -> 12 s).
    """
    from ..rig_transfer.correspondence import dense_correspondence

    shared = shared_landmarks(shapes, landmarks)
    src = {n: shapes.landmarks[n] for n in shared}
    dst = {n: np.asarray(landmarks[n], dtype=np.float64) for n in shared}
    P = dense_correspondence(shapes.vertices, shapes.faces, V, F, src, dst, **{**CORRESPONDENCE, **fit_options})[0]
    return P, shared


def arkit_targets(rig, shapes=None, method="deformation", timings=None, repair_folds=True, free_lips=True,
                  correspondence=None, meet_blinks=True, **fit_options):
    """Displacements of the 52 ARKit shapes on a transferred rig's vertices, and their record.

    Parameters
    ----------
    rig : Rig
        A rig with ``landmarks`` (``autobones.transfer``), input frame and units.
    shapes : ShapeSet or None
        The source set (None: the set of the generic rig folder the rig was transferred from,
        ``options['rig']``, when ``build-rig --shapes`` gave it one, else the packaged ICT-FaceKit set).
    method : "deformation" or "copy"
        Deformation transfer, or the copy baseline (:mod:`.copy_baseline`; for comparison).
    timings : dict, optional
        Filled with seconds: ``correspond``, ``map``, ``factor``, ``solve``, ``lids`` (one-surface heads), ``folds``
        (the repair and the counts of the record), ``eyes``.
    repair_folds : bool
        Turn back the triangles a shape turns over at weight 1, moving only their vertices
        (:func:`autobones.arkit.folds.unfold_shapes`; ``mouthClose`` judged on top of ``jawOpen``).
        False: the shapes as carried (for comparison).
    free_lips : bool
        Let the lips of a closed mouth part (:func:`.fissures.mouth_fissure`); False for comparison.
    correspondence : (n_s, 3) float, optional
        :func:`shape_correspondence`'s ``P`` for this rig and set, when already computed.
    meet_blinks : bool
        Bring the blinks' lid margins together on the head's own lids (:func:`autobones.arkit.lid_meet.meet_lids`,
        deformation only); False: the blinks as carried (for comparison).
    **fit_options
        Passed to :func:`dense_correspondence`, over :data:`CORRESPONDENCE`.

    Returns
    -------
    targets : dict str -> (n, 3) float64
        All 52 :data:`ARKIT_NAMES` (``tongueOut`` zero), input frame and units, rounded to
        float32 (what the glb stores, so a reloaded rig poses identically).
    record : dict
        For the sidecar: ``names``, ``source``, ``method``, ``absent``, ``eyes``,
        ``flipped_triangles`` (per name, at weight 1, each shape alone), ``folds`` (the fold repair,
        :mod:`.folds`: triangles turned over before and after it, ``mouthClose`` judged on top of
        ``jawOpen``), ``max_displacement`` (mesh units).
    """
    S = rig_shape_set((getattr(rig, "options", None) or {}).get("rig")) if shapes is None else shapes
    lm = rig.landmarks or {}
    V, F = np.asarray(rig.vertices, dtype=np.float64), np.asarray(rig.faces, dtype=np.int64)
    t = time.perf_counter()
    P, shared = _correspondence(S, V, F, lm, correspondence, fit_options)
    tim = {"correspond": time.perf_counter() - t}
    names = S.names
    D = np.stack([S.deltas[n] for n in names])
    eyes = eyeball_vertices(rig)
    keep = np.zeros(len(V), dtype=bool)
    for m in eyes.values():
        keep |= m
    X = _carry(S, D, P, V, F, lm, shared, rig.frame, method, eyes, keep, tim, free_lips)
    names = list(names)
    met, apart = {}, {}
    if method == "deformation" and meet_blinks:
        t = time.perf_counter()
        X, met, apart = _meet_blinks(V, F, lm, X, names, eyes)
        tim["lids"] = tim.get("lids", 0.0) + time.perf_counter() - t
    t = time.perf_counter()
    X, fold_report = _repair_folds(V, F, X, names, keep, repair_folds)
    tim["folds"] = time.perf_counter() - t
    t = time.perf_counter()
    by_name = dict(zip(names, X))
    turned = _turn_eyeballs(rig, V, by_name, eyes)
    # all 52 names, a name the set lacks all zero; rounded to the float32 the glb stores
    targets = {n: (np.zeros_like(V) if by_name.get(n) is None else by_name[n]).astype(np.float32).astype(np.float64)
               for n in ARKIT_NAMES}
    tim["eyes"] = time.perf_counter() - t
    t = time.perf_counter()
    on_top, alone, judged = _fold_counts(V, F, targets, by_name, fold_report, turned)
    tim["folds"] += time.perf_counter() - t
    if timings is not None:
        timings.update(tim)
    record = _arkit_record(S, method, shared, met, apart, eyes, targets, alone, judged, on_top, repair_folds,
                           fold_report)
    _warn_still_folded(judged, record["source_flipped_triangles"])
    return targets, record


def _correspondence(S, V, F, lm, correspondence, fit_options):
    """The shape set ``S``'s skin on the head (``P`` (n_s, 3), head frame and units) and the
    landmark names shared: :func:`shape_correspondence`, or the ``correspondence`` given
    (checked against the set's vertex count)."""
    if correspondence is None:
        return shape_correspondence(S, V, F, lm, **fit_options)
    P, shared = np.asarray(correspondence, dtype=np.float64), shared_landmarks(S, lm)
    if P.shape != S.vertices.shape:
        raise AutobonesError(f"ARKit shapes: {counted(len(P), 'corresponding point')} for the shape set's {counted(len(S.vertices), 'vertex', 'vertices')}")
    return P, shared


def _carry(S, D, P, V, F, lm, shared, frame, method, eyes, keep, tim, free_lips):
    """The set's displacements ``D`` (k, n_s, 3) carried onto the head ``V`` (n, 3), ``F`` (m, 3)
    (input frame and units) through ``P`` (n_s, 3): deformation transfer
    (:func:`deformation_targets`; a head without separate ``eyes`` is one surface), or copied
    through a similarity fit on the ``shared`` landmarks. ``keep`` (n,) bool held at 0; ``tim``
    takes the transfer's seconds. Returns (k, n, 3) float64."""
    if method == "deformation":
        return deformation_targets(S, D, P, V, F, lm, None if eyes else frame, keep=keep, timings=tim,
                                   frame=frame, free_lips=free_lips)
    if method == "copy":
        s, R = similarity(np.array([S.landmarks[n] for n in shared]), np.array([lm[n] for n in shared], dtype=np.float64))
        X = copy_displacements(S.faces, D, P, V, s, R)
        X[:, keep] = 0.0
        return X
    raise AutobonesError(f"ARKit shapes: unknown method {method!r} (deformation or copy)")


def _repair_folds(V, F, X, names, keep, repair_folds):
    """``X`` (k, n, 3; ``names`` its k ARKit names) rounded to float32 and, with ``repair_folds``,
    :func:`unfold_shapes`'d (``keep`` (n,) bool never moved). Returns (k, n, 3) float64 and the
    repair's report per name (empty without the repair)."""
    # triangles a carried shape turns over are turned back, moving only their vertices (mouthClose
    # on top of jawOpen); rounded first to the float32 the glb stores, so the counts are of what is written
    X = X.astype(np.float32).astype(np.float64)
    fold_report = {}
    if repair_folds:
        X, fold_report = unfold_shapes(V, F, X, names, fixed=keep, dtype=np.float32)
    return X, fold_report


def _warn_still_folded(judged, src):
    """Log the shapes that turn more triangles over (``judged``: name -> count) than the source's
    own (``src``: name -> count)."""
    bad = {n: c for n, c in judged.items() if c > src.get(n, 0)}
    if bad:  # ICT's own shapes fold some (mouthClose): only more than the source's is news
        log.warning("ARKit shapes: triangles still turned over at weight 1 after the fold repair: %s",
                    ", ".join(f"{n} {c} (source {src.get(n, 0)})" for n, c in bad.items()))


def _meet_blinks(V, F, lm, X, names, eyes):
    """The blinks of ``X`` (k, n, 3; ``names`` their k names) with their lid margins brought
    together on the head's own lids (:func:`meet_lids`; the gradients leave them apart), the
    separate eyeballs ``eyes`` (name -> (n,) bool) as spheres. Returns the new (k, n, 3), the
    per-blink record and the blinks left apart."""
    balls = [fit_sphere(V[m]) for m in eyes.values()]
    blinks, met = meet_lids(V, F, lm, dict(zip(names, X)), eyeballs=balls)
    X = np.stack([blinks[n] for n in names])
    apart = {n: r for n, r in met.items() if r["open"] > 1.0 - BLINK_CLOSED}
    if apart:
        log.warning("ARKit shapes: %s", lids_note(apart))
    return X, met, apart


def _turn_eyeballs(rig, V, by_name, eyes):
    """Set each eyeLook* shape of ``by_name`` (name -> (n, 3), changed in place) on the separate
    eyeballs ``eyes`` (``eye_l``/``eye_r`` -> (n,) bool) to their rigid turn about their eye bone
    (:func:`eye_turn`). Returns the names turned."""
    turned = set()
    if eyes:
        names_b = rig.skeleton.names
        for name in EYE_LOOK:
            eye = "eye_l" if name.endswith("Left") else "eye_r"
            if eye in eyes and name in by_name:  # a set without the shape leaves it absent (all zero)
                m = eyes[eye]
                c = rig.skeleton.heads[names_b.index(eye)]
                R = eye_turn(name, rig.frame.turn_axes)
                by_name[name] = by_name[name].copy()
                by_name[name][m] = (V[m] - c) @ R.T + c - V[m]
                turned.add(name)
    return turned


def _fold_counts(V, F, targets, by_name, fold_report, turned):
    """Triangles each of the 52 ``targets`` (name -> (n, 3)) turns over at weight 1: the shapes
    driven on top of another (:data:`ON_TOP`, both in ``by_name``), each shape alone, and as judged
    (alone, but on top of its base for those). Counts the fold repair made (``fold_report``) are
    reused unless an eyeball turn (``turned``) changed the shape since."""
    # each shape alone, as ever; a shape meant on top of another (mouthClose) also judged that way.
    # The fold repair counted every other shape as written (unless an eyeball turn changed it since)
    on_top = {n: b for n, b in ON_TOP.items() if n in by_name and b in by_name}
    known = {n: r["after"] for n, r in fold_report.items() if n not in on_top and n not in turned}
    alone = flipped_triangles(V, F, {n: targets[n] for n in ARKIT_NAMES if n not in known})
    alone = {n: known[n] if n in known else alone[n] for n in ARKIT_NAMES}
    judged = dict(alone)
    for n, b in on_top.items():
        judged[n] = (fold_report[n]["after"] if n in fold_report else
                     int(folded_triangles(V, F, targets[n], targets[b]).sum()))
    return on_top, alone, judged


def _arkit_record(S, method, shared, met, apart, eyes, targets, alone, judged, on_top, repair_folds, fold_report):
    """The sidecar's record of the ARKit shapes (see :func:`arkit_targets`)."""
    return {
        "format": "autobones-arkit/1",
        "names": list(ARKIT_NAMES),
        "source": S.meta.get("source"),
        "license": S.meta.get("license"),
        "method": {"deformation": "deformation transfer (Sumner & Popovic 2004)",
                   "copy": "displacements copied through the correspondence"}[method],
        "left_right": "Left is the subject's own left (ARKit's convention)",
        "landmarks_used": shared,
        "absent": [n for n in ARKIT_NAMES if n not in S.deltas],
        # per blink the lids were closed on: the fraction of the rest gap its margins leave open
        "lids_meet": met,
        **({"lids_note": lids_note(apart)} if apart else {}),
        "eyes": ("eyeLook* turn the separate eyeballs about " + ", ".join(sorted(eyes)) + " by "
                 + ", ".join(f"{k.lower()} {v:g} deg" for k, v in EYE_TURN_DEG.items())) if eyes else
                "no separate eyeballs: eyeLook* move the lids and eye surface as the skin transfer gives",
        "flipped_triangles": alone,
        # the same count for the source's own shapes on its own skin: ICT folds some (mouthClose)
        "source_flipped_triangles": S.meta.get("source_flipped_triangles", {}),
        "folds": {
            "rule": "triangles whose normal turns over at weight 1 (each shape alone, but mouthClose on top of "
                    "jawOpen at weight 1, as ARKit drives it), before and after the local fold repair",
            "on_top_of": on_top,
            "repaired": bool(repair_folds),
            "before_repair": ({n: fold_report[n]["before"] if n in fold_report else 0 for n in ARKIT_NAMES}
                              if repair_folds else judged),
            "after_repair": judged,
        },
        "max_displacement": {n: float(np.linalg.norm(targets[n], axis=1).max(initial=0.0)) for n in ARKIT_NAMES},
    }
