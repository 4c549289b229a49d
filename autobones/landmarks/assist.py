"""Assisted landmarks: the contract's other names proposed from five given ones (issue #35).

A user (or the landmark editor) places the outer eye corners, the nose tip and the mouth
corners; everything else is read off the generic head fitted to the mesh:

1. the generic rig's skin is warped onto the head by the thin-plate spline of the given names
   and fitted to its surface (:func:`autobones.rig_transfer.correspondence.fit_surface`, the
   same dense fit ``transfer`` uses, the generic's jaw opened as far as the given mouth corners
   say), then stuck to it (:func:`autobones.rig_transfer.stick.stick`): every generic vertex
   gets its point on the head;
2. each name is read off the generic skin: a point of it sits at barycentric coordinates in a
   triangle of the skin; the same coordinates in the fitted triangle, snapped to the head's
   surface, are the proposal (:func:`read_off`). The point is the generic rig's own landmark,
   or for the built-in rig where hand-placed landmarks of human heads land on its fitted skin
   (:mod:`autobones.landmarks.assist_calibration`: the generic's landmarks follow geometric
   rules on a procedural head, not the way people place the names);
3. on a human face (:func:`autobones.landmarks.human_face.is_human_face`: the five against the
   generic's, which may wear an expression of its expression space) the menton is moved to the
   lowest point of the midline profile near it (:func:`autobones.landmarks.refine.on_profile`):
   the fitted chin is not the head's;
4. a confidence per name (:func:`confidence`) from how well the fit meets the head there and
   how far the name lies from the given points.

Works on any head the five names can be placed on (animals, cartoons, bodies: the fit is
not a face detector). The mesh's frame and units are its own: the fit is equivariant under
rotation, translation and uniform scale (tests/test_assist.py checks a rotated x1000 copy).
Distances in this module are in units of the given outer-eye-corner distance (ex-ex).
"""
from __future__ import annotations

import functools
import os
from dataclasses import dataclass, field

import numpy as np

from ..errors import AutobonesError
from ..geometry.closest import closest_points
from ..geometry.normals import vertex_normals
from ..geometry.topology import mesh_parts
from ..geometry.validate import mesh_arrays
from ..geometry.winding import outward_faces
from ..io.landmark_checks import validate_landmarks
from ..io.landmark_names import NAMES
from ..orient import Frame, frame_from_landmarks
from ..rig_transfer.under_skin import ride
from .human_face import FIVE, is_human_face
from .refine import on_profile, symmetry_plane

#: The names an assisted placement needs: well spread over the face, easy to click on any head.
REQUIRED = ("exocanthion_l", "exocanthion_r", "pronasale", "cheilion_l", "cheilion_r")

#: Confidence falls to 1/2 at this distance (ex-ex) from the nearest given name: the warp is
#: exact at the given points and extrapolates away from them.
HALF_DISTANCE = 1.0

#: Fit residual (ex-ex) at which confidence falls to 1/e: the fitted generic skin's distance
#: to the head before it was stuck on (a part of the generic the head does not have is far off).
RESIDUAL_SCALE = 0.1

#: A detection whose own five names lie farther than this (ex-ex, RMS) from the given ones found
#: another face, or this one badly: it is not used.
DETECTED_AGREE = 0.1


@dataclass(frozen=True)
class Assisted:
    """Landmarks proposed from a few given ones, in the mesh's own frame and units.

    Attributes
    ----------
    points : dict str -> (3,) float64
        Every contract name the head has: the given names unchanged, the others proposed.
    confidence : dict str -> float
        In [0, 1], per name of ``points`` (1 for a given name); see :func:`confidence`.
    omitted : dict str -> str
        Contract names neither given nor proposed, with the reason (the generic rig, or the ``reading``,
        carries no such landmark). A part the head lacks is proposed at a confidence near 0.
    frame : Frame or None
        The head's frame from the landmarks (:func:`autobones.orient.frame_from_landmarks`).
    unit : float
        The given ex-ex distance, mesh units (the unit of the confidence's distances).
    human : bool
        Whether the given five are a person's face (:func:`autobones.landmarks.human_face.is_human_face`):
        the chin's profile rule and the detector apply only then.
    detected : tuple of str
        The proposed names taken from the automatic detector (empty: all from the generic's fit).
    """

    points: dict
    confidence: dict
    omitted: dict = field(default_factory=dict)
    frame: Frame | None = None
    unit: float = 1.0
    human: bool = False
    detected: tuple = ()


def check_given(given):
    """``given`` as a dict name -> (3,) float64, or AutobonesError naming what is wrong or missing."""
    if not isinstance(given, dict):
        raise AutobonesError(f"given landmarks must be a dict name -> [x, y, z], got {type(given).__name__}")
    unknown = sorted(n for n in given if n not in NAMES)
    if unknown:
        raise AutobonesError(f"unknown landmark names {', '.join(map(str, unknown))} (see the landmark contract)")
    missing = [n for n in REQUIRED if n not in given]
    if missing:
        raise AutobonesError(f"assisted landmarks need {', '.join(REQUIRED)}; missing {', '.join(missing)}")
    out = {}
    for n, p in given.items():
        p = np.asarray(p, dtype=np.float64)
        if p.shape != (3,) or not np.isfinite(p).all():
            raise AutobonesError(f"landmark {n}: expected 3 finite coordinates, got {np.asarray(p).tolist()}")
        out[n] = p.copy()
    unit = float(np.linalg.norm(out["exocanthion_l"] - out["exocanthion_r"]))
    if not unit > 0:
        raise AutobonesError("exocanthion_l and exocanthion_r are the same point: place the two outer eye corners")
    # the five alone tell left from right: +X (the subject's left) = up x front, with up from the
    # mouth to the eyes and front from the eye-mouth plane to the nose; a swapped set would mirror the fit
    eyes = (out["exocanthion_l"] + out["exocanthion_r"]) / 2
    mouth = (out["cheilion_l"] + out["cheilion_r"]) / 2
    left = np.cross(eyes - mouth, out["pronasale"] - (eyes + mouth) / 2)
    if (out["exocanthion_l"] - out["exocanthion_r"]) @ left < 0 and (out["cheilion_l"] - out["cheilion_r"]) @ left < 0:
        raise AutobonesError("the _l and _r landmarks look exchanged: _l is the subject's own left (the viewer's "
                             "right in a frontal view); swap them")
    return out


def read_off(points_src, V_src, F_src, P):
    """Points on a source skin carried through a dense correspondence.

    Parameters
    ----------
    points_src : (k, 3) float
        Points on (or near) the source skin, source frame.
    V_src, F_src : (n, 3) float, (m, 3) int
        The source skin.
    P : (n, 3) float
        Each source vertex's point on the target (target frame).

    Returns
    -------
    Q : (k, 3) float64
        The points at the same barycentric coordinates in the carried triangles (target frame;
        near, not on, the target surface).
    face : (k,) int64
        The source triangle of each point. (:func:`autobones.rig_transfer.under_skin.ride`.)
    """
    return ride(points_src, V_src, F_src, P, return_faces=True)


def confidence(distance, residual, agreement):
    """Confidence of a proposed name, in [0, 1].

    ``1 / (1 + (distance / HALF_DISTANCE)^2)``: 1 at a given point, 1/2 one ex-ex away (the
    warp is exact at the given names and extrapolates between and beyond them); times
    ``exp(-residual / RESIDUAL_SCALE)``: how closely the fitted generic skin met the head there
    before it was stuck on; times ``agreement``, the cosine between the fitted skin's normal and
    the head's at the point, clipped to [0, 1] (a fold or a part pressed onto the wrong side
    scores low). All three are arrays (k,), distances in ex-ex.
    """
    d = np.asarray(distance, dtype=np.float64)
    c = 1.0 / (1.0 + (d / HALF_DISTANCE) ** 2) * np.exp(-np.asarray(residual) / RESIDUAL_SCALE)
    return np.clip(c * np.clip(agreement, 0.0, 1.0), 0.0, 1.0)


@functools.lru_cache(maxsize=4)
def _generic_in_folder(folder, mesh_mtime_ns):
    # a pure function of the folder's files (its time stamp in the key): read-only for the callers
    from ..labelled_rig import LabelledRig

    generic = LabelledRig.load(folder)
    return generic, _jaw_prior(generic)


def _jaw_prior(generic):
    from ..rig_transfer.jaw_prior import jaw_prior

    return jaw_prior(generic) if {"jaw", "head"} <= set(generic.skeleton.names) else None


def generic_skin(rig=None):
    """The generic rig and its articulated jaw prior (None without ``jaw`` and ``head`` bones), as
    ``transfer`` fits them: ``rig`` a folder (None: the built-in one; loaded once per folder and
    ``mesh.obj`` time stamp) or a LabelledRig. Not :mod:`autobones.rig_transfer.pipeline`'s loaders:
    that module imports the landmark detector, which refines with this one."""
    if rig is None or isinstance(rig, (str, os.PathLike)):
        from ..generic_rig import default_rig_path

        folder = os.path.abspath(os.fspath(default_rig_path() if rig is None else rig))
        return _generic_in_folder(folder, os.stat(os.path.join(folder, "mesh.obj")).st_mtime_ns)
    return rig, _jaw_prior(rig)


@dataclass(frozen=True)
class GenericFit:
    """The generic skin fitted to a head: ``Vg`` (n, 3) and ``Fg`` (m, 3) the generic's rest skin (its
    frame and units), ``X`` (n, 3) the fitted vertices and ``P`` (n, 3) their points stuck on the head
    (the head's frame and units), ``reliable`` (n,) bool (False where the stick found a fold)."""

    Vg: np.ndarray
    Fg: np.ndarray
    X: np.ndarray
    P: np.ndarray
    reliable: np.ndarray


def fit_generic(V, F, given, rig=None):
    """Fit the generic rig's skin to the head (V (n, 3), F (m, 3)) through the given landmarks.

    The thin-plate spline of the names both carry, then the staged surface fit and the stick of
    :func:`autobones.rig_transfer.correspondence.dense_correspondence` (the generic's jaw opened as
    far as the given mouth says). Returns (GenericFit, the generic LabelledRig).
    """
    from ..rig_transfer.correspondence import fit_surface
    from ..rig_transfer.stick import stick

    generic, jaw = generic_skin(rig)
    Vg, Fg = mesh_arrays(generic.vertices, generic.faces, "generic rig skin")
    shared = sorted(n for n in given if n in generic.landmarks)
    src = {n: np.asarray(generic.landmarks[n], dtype=np.float64) for n in shared}
    X, labels = fit_surface(Vg, Fg, V, F, src, {n: given[n] for n in shared}, jaw=jaw)
    # each generic vertex stuck to the head part the fit restricted it to (dense_correspondence's stick)
    parts = mesh_parts(len(V), F)[F[:, 0]] if (labels >= 0).any() else None
    P, _, _, reliable = stick(X, Fg, V, F, labels=labels if parts is not None else None, face_labels=parts)
    return GenericFit(Vg, Fg, X, P, reliable), generic


def assist_landmarks(vertices, faces, given, rig=None, reading=None, detected=None):
    """Propose the contract's other landmarks on a head from five given ones.

    Parameters
    ----------
    vertices : (n, 3) float
        The head's vertices, in its own frame and units.
    faces : (m, 3) int
        Its triangles.
    given : dict str -> (3,)
        Landmarks placed on the head (its frame), at least :data:`REQUIRED`; any other contract
        names given are kept and used by the fit too.
    rig : str, LabelledRig or None
        The generic rig whose skin is fitted (None: the built-in one, as :func:`autobones.transfer`).
    reading : dict str -> (3,) or None
        Where on the generic skin (its frame) each name is read off. None: for the built-in rig its
        calibrated reading (:func:`autobones.landmarks.assist_calibration.built_in_reading`: where
        hand-placed landmarks of human heads land on the fitted generic skin), for another rig its
        own landmarks.
    detected : dict str -> (3,), callable, "auto" or None
        Landmarks found automatically on this head (:func:`autobones.detect_landmarks`; a
        ``DetectedLandmarks`` brings its confidences); a function of no argument returning them or
        None (called only on a human face: the editor keeps one detection per head); or ``"auto"``:
        run the detector. Used only when the five say the face is a person's
        (:func:`autobones.landmarks.human_face.is_human_face`, an expression allowed): the names it
        found replace the fit's proposals, when its own five agree with the given ones
        (:data:`DETECTED_AGREE`): on the nine human heads of the shared data set the names within
        5 % of ex-ex of the hand-placed ones went from 50 % to 71 % (benchmarks/README.md).
        None: the fit alone.

    Returns
    -------
    Assisted

    Raises
    ------
    AutobonesError
        A missing or unknown name, a bad coordinate, a bad mesh.
    """
    V, F = mesh_arrays(vertices, faces, "head mesh")
    F = outward_faces(V, F)[0]   # the fit matches normals: an inside-out head fitted inside out
    given = check_given(given)
    validate_landmarks(given, V, F, min_count=len(REQUIRED), source="given landmarks")
    unit = float(np.linalg.norm(given["exocanthion_l"] - given["exocanthion_r"]))
    fit, generic = fit_generic(V, F, given, rig)
    if reading is None:
        from .assist_calibration import built_in_reading

        reading = {**generic.landmarks, **(built_in_reading() if rig is None else {})}
    wanted = [n for n in NAMES if n in reading and n not in given]
    # a part the head lacks (ears on a cartoon) is still proposed, at a confidence near 0 (the fitted skin
    # hangs off the head there): no threshold told such parts from a real one the fit missed on the zoo
    # (a camel's back of the head lay 1.06 ex-ex off); a name the generic carries nowhere is omitted
    omitted = {n: "the generic rig has no such landmark to read off" for n in NAMES
               if n not in reading and n not in given}
    points, conf = dict(given), {n: 1.0 for n in given}
    if wanted:
        found, c = _read_names(fit, V, F, [reading[n] for n in wanted], given, unit)
        points.update(zip(wanted, found))
        conf.update(zip(wanted, map(float, c)))
    human = all(n in generic.landmarks for n in REQUIRED) and is_human_face(
        given, generic.landmarks, _reference_motion(generic, rig))
    if human and "menton" in points and "menton" not in given:
        # the fit leaves a human chin's lowest point 2-16 % of ex-ex off (its chin is not the head's);
        # the midline profile has it exactly (not on an animal: its "down" is not the face's)
        points = on_profile(V, F, points, *symmetry_plane(points), unit, names=("menton",))
    taken = ()
    if human and detected is not None:
        if isinstance(detected, str) and detected == "auto":
            found = _detect(V, F)
        else:
            found = detected() if callable(detected) else detected
        points, conf = with_detected(points, conf, given, found, unit)
        if detection_agrees(given, found, unit):
            taken = tuple(n for n in NAMES if n in found and n in points and n not in given)
    order = {n: i for i, n in enumerate(NAMES)}
    points = {n: points[n] for n in sorted(points, key=order.get)}
    return Assisted(points=points, confidence={n: conf[n] for n in points}, omitted=omitted,
                    frame=frame_from_landmarks(V, F, points), unit=unit, human=bool(human), detected=taken)


def _reference_motion(generic, rig):
    """How the generic's expression space and its jaw's hinge move the five names, (k, 5, 3), or None
    when the rig has no expression space (:func:`autobones.rig_transfer.pipeline.face_motion`)."""
    from ..rig_transfer.pipeline import face_motion

    motion = face_motion(generic, rig)
    return None if motion is None else motion(generic.landmarks, FIVE)


def _detect(V, F):
    """The automatic detector's landmarks on the head, or None (not installed, no face found)."""
    from .detect import detect_landmarks

    try:
        return detect_landmarks((V, F))
    except AutobonesError:
        return None


def with_detected(points, confidence, given, detected, unit):
    """``points`` / ``confidence`` (name -> (3,) / float) with the names ``detected`` has (and
    ``given`` has not) taken from it, when its version of the given names agrees with them
    (:func:`detection_agrees`); else unchanged. A detected name's confidence is the detector's
    (``detected.confidence``), else 1."""
    if not detection_agrees(given, detected, unit):
        return points, confidence
    scores = getattr(detected, "confidence", {}) or {}
    points, confidence = dict(points), dict(confidence)
    for n in detected:
        if n not in given and n in points:
            points[n] = np.asarray(detected[n], dtype=np.float64)
            confidence[n] = float(scores.get(n, 1.0))
    return points, confidence


def detection_agrees(given, detected, unit):
    """True when ``detected`` (name -> (3,), or None) has names of ``given`` and lies within
    :data:`DETECTED_AGREE` ex-ex of them (RMS; ``unit`` the ex-ex in mesh units): the same face, read well."""
    shared = [n for n in given if n in (detected or {})]
    return bool(shared) and np.sqrt(np.mean([np.sum((np.asarray(detected[n], dtype=np.float64) - given[n]) ** 2)
                                             for n in shared])) <= DETECTED_AGREE * unit


def _read_names(fit, V, F, where, given, unit):
    """Points ``where`` (k, 3) of the generic skin read off the fit and snapped to the head: (found (k, 3),
    confidence (k,))."""
    Q, gface = read_off(np.asarray(where, dtype=np.float64), fit.Vg, fit.Fg, fit.P)
    snapped, tface, tbary, _ = closest_points(Q, V, F)
    # how the fit met the head around each name: the fitted (unstuck) skin's distance to its stuck
    # point and its normal against the head's, averaged over the name's generic triangle
    corners = fit.Fg[gface]
    residual = np.linalg.norm(fit.X - fit.P, axis=1)[corners].mean(axis=1) / unit
    n_fit = vertex_normals(fit.X, fit.Fg)[corners].mean(axis=1)
    n_head = np.einsum("ij,ijk->ik", tbary, vertex_normals(V, F)[F[tface]])
    agreement = np.einsum("ij,ij->i", _unit_rows(n_fit), _unit_rows(n_head))
    agreement = np.where(fit.reliable[corners].all(axis=1), agreement, 0.5 * agreement)
    G = np.array(list(given.values()))
    distance = np.sqrt(((snapped[:, None, :] - G[None]) ** 2).sum(-1)).min(axis=1) / unit
    return snapped, confidence(distance, residual, agreement)


def _unit_rows(A):
    n = np.linalg.norm(A, axis=1, keepdims=True)
    return A / np.where(n > 0, n, 1.0)


__all__ = ["Assisted", "GenericFit", "REQUIRED", "assist_landmarks", "check_given", "confidence", "detection_agrees",
           "fit_generic", "generic_skin", "read_off"]
