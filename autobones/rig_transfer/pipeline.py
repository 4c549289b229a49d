"""``transfer``: a labelled generic rig carried onto a landmarked head (seed 004 §3.7).

The pipeline, one module a stage:
1. landmarks (io.landmarks): read, checked against the head (names, units,
   left/right, distance to the surface);
2. warp + stick (tps, fit, stick): the generic skin is warped onto the head by
   thin-plate splines from the shared landmarks, fitted to the surface and
   stuck to it: every generic vertex gets its point on the head (a dense
   correspondence);
3. under-skin points (tps): a second TPS, fitted on a well-spread subsample of
   that correspondence, carries the skeleton and the muscle origins (004 §3.4);
   muscle insertions ride the correspondence itself;
4. attributes (attributes): skin weights, region labels and every other
   field land on the head's own vertices, with unreliable matches inpainted;
5. the result is a :class:`autobones.rig.Rig`, saved as the same skinned
   glTF as ``place`` with muscles and fields in the sidecars.
"""
from __future__ import annotations

import logging
import os

import numpy as np

from .fields import transfer_fields
from ..errors import AutobonesError
from .correspondence import dense_correspondence
from ..io.landmarks import NAMES, resolve_landmarks, validate_landmarks
from ..orient import detect_frame, frame_from_landmarks
from .labelled_rig import _jsonable
from ..placement.pipeline import resolve_mesh
from ..rig import Rig
from ..timing import Stopwatch
from ..geometry.tps import ThinPlateSpline
from ..placement.skin_weights import prune_weights

log = logging.getLogger("autobones")

MIN_LANDMARKS = 10


def load_generic(rig=None):
    """A LabelledRig from a folder (None: the built-in generic rig) or as given."""
    from ..generic_rig import default_rig_path

    from .labelled_rig import LabelledRig

    if rig is None or isinstance(rig, (str, os.PathLike)):
        return LabelledRig.load(default_rig_path() if rig is None else rig)
    return rig


def spread_subsample(P, count):
    """Indices of ``count`` well-spread points of ``P`` (greedy farthest-point order from
    the point nearest the centroid; deterministic)."""
    count = min(count, len(P))
    chosen = np.empty(count, dtype=np.int64)
    chosen[0] = int(np.argmin(((P - P.mean(axis=0)) ** 2).sum(axis=1)))
    d = ((P - P[chosen[0]]) ** 2).sum(axis=1)
    for i in range(1, count):
        chosen[i] = int(np.argmax(d))
        d = np.minimum(d, ((P - P[chosen[i]]) ** 2).sum(axis=1))
    return chosen


_DETECTED = {}


def generic_detected_landmarks(generic, rig=None):
    """Automatic landmarks of the generic rig's own skin, or None when its skin shows no face
    the detector knows. Cached: per rig folder (and its mesh's time stamp) across calls, on
    the object itself for a LabelledRig given directly."""
    from ..landmarks.detect import LandmarkDetector, NoFaceError

    def detect():
        try:
            return dict(LandmarkDetector().detect(generic.vertices, generic.faces, what="the generic rig"))
        except NoFaceError:
            return None

    if rig is None or isinstance(rig, (str, os.PathLike)):
        from ..generic_rig import default_rig_path

        folder = os.path.abspath(os.fspath(default_rig_path() if rig is None else rig))
        key = (folder, os.stat(os.path.join(folder, "mesh.obj")).st_mtime_ns)
        if key not in _DETECTED:
            _DETECTED[key] = detect()
        return _DETECTED[key]
    if not hasattr(generic, "_detected_landmarks"):
        generic._detected_landmarks = detect()
    return generic._detected_landmarks


def ride(points, V_src, F_src, P):
    """Points on the source surface moved with the correspondence ``P`` (n_src, 3): each is
    expressed in barycentric coordinates of its closest source triangle."""
    from ..geometry.closest import closest_points

    _, face, bary = closest_points(np.asarray(points, dtype=np.float64), V_src, F_src)[:3]
    return np.einsum("ki,kij->kj", bary, P[F_src[face]])


def transfer(head, landmarks=None, rig=None, up=None, front=None, control_points=400, details=None, **fit_options):
    """Carry the generic rig onto a landmarked head.

    Parameters
    ----------
    head : str, (V, F) or None
        The head mesh, any frame and unit (None: the built-in default head).
    landmarks : str, dict of str -> (3,), or None
        A landmark file (contract JSON, MeshLab .pp, iBUG-68 .json/.pts/.ljson)
        or a dict, in the head's own frame; at least 10 names shared with the rig.
        None: found automatically on a human head (:mod:`autobones.detect`; needs the
        ``landmarks`` extra); the rig's ``options['landmarks_source']`` says which.
    rig : str, LabelledRig or None
        The generic rig (a folder written by ``build_rig``); None: the built-in one.
    up, front : str or None
        Override the detected axes (used to check left/right of the landmarks).
    control_points : int
        Size of the correspondence subsample the under-skin TPS is fitted on.
    details : dict, optional
        Filled with ``correspondence`` ((n_rig, 3): each generic vertex's point on
        the head) and ``reliable`` ((n_rig,) bool), for evaluation.

    Returns
    -------
    Rig
        In the head's frame and units: the rig's skeleton, skin weights, labels,
        fields and muscles on the head's own vertices.
    """
    watch = Stopwatch()
    lap, timings = watch.lap, watch.timings

    V, F, source = resolve_mesh(head)
    generic = load_generic(rig)
    lap("load")
    detected = None
    if landmarks is None:
        from ..landmarks.detect import LandmarkDetector

        frame = detect_frame(V, F, up=up, front=front)
        detected = LandmarkDetector().detect(V, F, frame=frame, what=source or "the head")
        lm, where = dict(detected), "automatic landmarks"
        log.info("landmarks: %d found automatically (mean confidence %.2f)%s", len(lm),
                 np.mean(list(detected.confidence.values())),
                 f"; dropped {', '.join(detected.dropped)}" if detected.dropped else "")
    else:
        lm, where = resolve_landmarks(landmarks)
        # the landmarks give the frame directly (and much faster) unless the user overrides an axis
        frame = None if up or front else frame_from_landmarks(V, F, lm)
        frame = frame or detect_frame(V, F, up=up, front=front)
    lm = validate_landmarks(lm, V, F, frame=frame, min_count=MIN_LANDMARKS, source=where)
    shared = [n for n in NAMES if n in lm and n in generic.landmarks]
    if len(shared) < MIN_LANDMARKS:
        raise AutobonesError(
            f"{where}: only {len(shared)} landmark names are shared with the generic rig "
            f"({', '.join(shared) or 'none'}); at least {MIN_LANDMARKS} well-spread ones are needed")
    lap("landmarks")
    src = {n: generic.landmarks[n] for n in shared}
    if detected is not None:
        # the same detector on the generic skin: its biases (brows, eye corners) then cancel
        # instead of pulling the correspondence (ICT pairs: 0.38% vs 0.56% mean error)
        mirror = generic_detected_landmarks(generic, rig)
        if mirror is not None and all(n in mirror for n in shared):
            src = {n: mirror[n] for n in shared}
        lap("generic_landmarks")
    dst = {n: lm[n] for n in shared}
    fit_timings = {}
    P, _, _, ok = dense_correspondence(generic.vertices, generic.faces, V, F, src, dst, timings=fit_timings,
                                       **fit_options)
    timings.update({f"fit_{k}": v for k, v in fit_timings.items()})
    if details is not None:
        details.update(correspondence=P, reliable=ok)
    lap("correspond")

    good = np.flatnonzero(ok) if ok.sum() >= 20 else np.arange(len(P))
    idx = good[spread_subsample(generic.vertices[good], control_points)]
    under = ThinPlateSpline(regularization=1e-3).fit(generic.vertices[idx], P[idx])
    skeleton = generic.skeleton.transformed(under.transform)
    muscles = []
    for m in generic.muscles:
        m = dict(m)
        m["origin"] = under.transform(np.asarray(m["origin"], dtype=np.float64)[None])[0]
        m["insertion"] = ride(np.asarray(m["insertion"], dtype=np.float64)[None], generic.vertices,
                              generic.faces, P)[0]
        muscles.append(m)
    lap("skeleton")

    fields = {"__weights__": generic.weights, **generic.fields}
    out, reliable = transfer_fields(P, generic.faces, fields, V, F, source_reliable=ok)
    W = np.clip(out.pop("__weights__"), 0.0, None)
    W = prune_weights(W / np.maximum(W.sum(axis=1, keepdims=True), 1e-300))  # inpainting leaves faint tails
    W, eyeballs = bind_eyeballs(V, F, W, skeleton, generic, under)
    skeleton = centre_eye_bones(V, skeleton, eyeballs)
    lap("attributes")

    labels = out["depth_group"].astype(np.int8) if "depth_group" in out else np.zeros(len(V), np.int8)
    facial_mask = labels == 0
    if "region" in out and "region" in generic.labels and "neck" in generic.labels["region"]:
        facial_mask &= out["region"] != generic.labels["region"].index("neck")
    options = {"command": "transfer", "landmarks_used": shared, "up": up, "front": front,
               "landmarks_source": "file" if isinstance(landmarks, (str, os.PathLike)) else
               "detected" if detected is not None else "given",
               "rig": "built-in" if rig is None else str(rig) if isinstance(rig, (str, os.PathLike)) else "object"}
    return Rig(
        vertices=V, faces=F, skeleton=skeleton, weights=W, labels=labels, facial_mask=facial_mask,
        frame=frame, options=options, timings=timings,
        extra={"source": source, "muscles": _jsonable(muscles),
               "landmarks": {n: lm[n].tolist() for n in lm},
               **({} if detected is None else {"landmark_confidence": detected.confidence,
                                               "landmarks_dropped": detected.dropped,
                                               "landmarks_flagged": detected.flagged}),
               "field_labels": {k: list(v) for k, v in generic.labels.items()},
               "reliable_fraction": float(reliable.mean())},
        fields=out)


def bind_eyeballs(V, F, W, skeleton, generic, under):
    """Separate parts sitting on an eye bone (eyeballs, corneas) follow it rigidly.

    A generic skin has no eyeballs to carry weights for, and on the target they
    would take the eyelids' weights from the closest skin. A part counts as an
    eyeball when its centroid is within 0.35 eye-fissure lengths of the eye bone's
    pivot and it is no wider than 1.5 fissures (eyelashes and lids sit farther out).
    Returns the weights and ``{eye bone name: (n,) bool}`` of the vertices bound.
    """
    from ..geometry.topology import mesh_parts

    names = skeleton.names
    bound = {}
    if not all(n in generic.landmarks for n in ("exocanthion_l", "endocanthion_l")):
        return W, bound
    ex, en = under.transform(np.array([generic.landmarks["exocanthion_l"], generic.landmarks["endocanthion_l"]]))
    fissure = np.linalg.norm(ex - en)
    part = mesh_parts(len(V), F)
    if part.max() == 0:
        return W, bound
    count = np.bincount(part)
    centroid = np.stack([np.bincount(part, weights=V[:, j]) for j in range(3)], axis=1) / count[:, None]
    W = W.copy()
    for eye in ("eye_l", "eye_r"):
        if eye not in names:
            continue
        pivot = skeleton.heads[names.index(eye)]
        for p in np.flatnonzero(np.linalg.norm(centroid - pivot, axis=1) < 0.35 * fissure):
            members = part == p
            if np.ptp(V[members], axis=0).max() < 1.5 * fissure and members.sum() < 0.5 * len(V):
                W[members] = 0.0
                W[members, names.index(eye)] = 1.0
                bound[eye] = bound.get(eye, np.zeros(len(V), dtype=bool)) | members
    return W, bound


def centre_eye_bones(V, skeleton, eyeballs, max_residual=0.1):
    """Move each eye bone to the centre of the eyeball it carries, when the head has one.

    The warped pivot can sit several millimetres off a modelled eyeball's centre (ICT:
    0.06-0.08 face units), and gaze and the lid joints turn about it: the eyeball would
    swing through the lids. A least-squares sphere through the bound vertices is trusted
    when their median distance to it is under ``max_residual`` of its radius (a cornea
    bulge or an iris disc stays within that; a non-spherical part is left alone).

    Parameters
    ----------
    V : (n, 3) float
        Head vertices.
    skeleton : Skeleton
        Bones in the head's frame and units; not modified.
    eyeballs : dict str -> (n,) bool
        Vertices bound rigidly to each eye bone (from :func:`bind_eyeballs`).

    Returns
    -------
    Skeleton
        A copy with each such eye bone (head and tail) translated to its sphere's centre.
    """
    from ..skeleton import Skeleton

    heads, tails = skeleton.heads.copy(), skeleton.tails.copy()
    for eye, members in eyeballs.items():
        P = V[members]
        if len(P) < 10:
            continue
        centre, radius = fit_sphere(P)
        if not radius > 0 or np.median(np.abs(np.linalg.norm(P - centre, axis=1) - radius)) > max_residual * radius:
            continue
        j = skeleton.names.index(eye)
        shift = centre - heads[j]
        heads[j] += shift
        tails[j] += shift
    return Skeleton(list(skeleton.names), skeleton.parents.copy(), heads, tails)


def fit_sphere(P):
    """Algebraic least-squares sphere through points P (m, 3): (centre (3,), radius)."""
    c0 = P.mean(axis=0)
    Q = P - c0                                   # centred, for conditioning
    A = np.c_[2.0 * Q, np.ones(len(Q))]
    x = np.linalg.lstsq(A, (Q * Q).sum(axis=1), rcond=None)[0]
    r2 = x[3] + x[:3] @ x[:3]
    return c0 + x[:3], float(np.sqrt(r2)) if r2 > 0 else 0.0
