"""``transfer``: a labelled generic rig carried onto a landmarked head.

After Orvalho, Zacur & Susin 2008 ("Transferring the Rig and Animations from a Character to
Different Face Models", §3.7 for the whole method); one module a stage:

1. landmarks (io.landmarks): read, checked against the head (names, units,
   left/right, distance to the surface), or found automatically (landmarks.detect);
2. correspondence (correspondence, stick): the generic skin is warped onto the head by
   thin-plate splines from the shared landmarks, fitted to the surface and stuck to it:
   every generic vertex gets its point on the head (a dense correspondence);
3. under-skin points (under_skin): a second TPS, fitted on a well-spread subsample of
   that correspondence, carries the skeleton and the muscle origins (their §3.4);
   muscle insertions ride the correspondence itself; on a head with tragions the
   ``head`` and ``jaw`` joints then sit where the generic's do relative to its ear
   canals or, on a human face whose landmarks stop at the face, from its landmarks
   (:func:`~.joints.anchor_joints`; Chancey et al. 2007);
4. attributes (fields, eyes, jaw, neck): skin weights, region labels and every other field land on
   the head's own vertices, with unreliable matches inpainted; eyeballs follow the eye bones; the
   jaw weight is repaired from the landmarks and the neck base made still (the head/neck blend
   through the head joint, as ``place``'s);
5. the result is a :class:`autobones.rig.Rig`, saved as the same skinned glTF as ``place``
   with muscles and fields in the sidecars.

Frames: the generic rig's data are in its own frame and units, everything returned in
the head's input frame and units.
"""
from __future__ import annotations

import functools
import logging
import os

import numpy as np

from .correspondence import dense_correspondence
from .joints import anchor_joints, face_points
from .expression_prior import MAX_MISFIT, shape_set_expression
from .jaw_prior import jaw_prior
from .eyes import bind_eyeballs, centre_eye_bones
from .jaw import repair_jaw_weights
from .mouth_parts import carried_mouth_parts, rigid_mouth_parts
from .neck import ANGLE, still_neck_base
from .fields import transfer_fields
from .head_landmarks import head_landmarks
from .symmetry import MAX_LANDMARK_MISMATCH, Symmetry
from .under_skin import carry_muscles, ride, under_skin_warp
from ..io.jsonable import jsonable
from ..io.mesh import resolve_mesh, wound_outward
from ..io.parts import stray_parts, worn_parts
from ..geometry.rigid_parts import closed_small_parts, rigid_weights
from ..geometry.weights import prune_weights
from ..rig import Rig
from ..timing import Stopwatch

log = logging.getLogger("autobones")


def load_generic(rig=None):
    """A LabelledRig from a folder (None: the built-in generic rig) or as given."""
    from ..generic_rig import default_rig_path

    from ..labelled_rig import LabelledRig

    if rig is None or isinstance(rig, (str, os.PathLike)):
        return LabelledRig.load(default_rig_path() if rig is None else rig)
    return rig


def detect_generic_landmarks(generic):
    """Automatic landmarks of a generic rig's own skin, or None when it shows no face the detector knows.

    Parameters
    ----------
    generic : LabelledRig

    Returns
    -------
    dict str -> (3,) float or None
        In the generic rig's frame and units.
    """
    from ..landmarks.detect import LandmarkDetector, NoFaceError

    try:
        return dict(LandmarkDetector().detect(generic.vertices, generic.faces, what="the generic rig"))
    except NoFaceError:
        return None


def _rig_folder(rig):
    """The absolute folder a ``rig`` argument names (None: the built-in rig's), or None for a rig
    given as an object: the key of the per-folder memos below."""
    if rig is not None and not isinstance(rig, (str, os.PathLike)):
        return None
    from ..generic_rig import default_rig_path

    return os.path.abspath(os.fspath(default_rig_path() if rig is None else rig))


@functools.lru_cache(maxsize=4)
def _detect_in_folder(folder, mesh_mtime_ns):
    # a pure function of the folder's skin: the file's time stamp is part of the key, so an
    # edited rig is detected again; the result is only read (copied into ``src`` by name)
    from ..labelled_rig import LabelledRig

    return detect_generic_landmarks(LabelledRig.load(folder))


def generic_detected_landmarks(generic, rig=None):
    """:func:`detect_generic_landmarks` of the generic rig ``rig`` names (already loaded as ``generic``).

    For a rig folder (``rig`` None: the built-in one, or a path) the result is memoised per
    folder and ``mesh.obj`` time stamp (``functools.lru_cache`` of the last 4 folders), so a
    batch of automatic-landmark transfers detects on the generic skin once per worker; a
    :class:`LabelledRig` object is detected each call (nothing is stored on it).
    """
    folder = _rig_folder(rig)
    if folder is not None:
        return _detect_in_folder(folder, os.stat(os.path.join(folder, "mesh.obj")).st_mtime_ns)
    return detect_generic_landmarks(generic)


@functools.lru_cache(maxsize=4)
def _jaw_prior_in_folder(folder, mesh_mtime_ns):
    # as _detect_in_folder: a pure function of the folder's files, read-only for its callers
    from ..labelled_rig import LabelledRig

    return jaw_prior(LabelledRig.load(folder))


def generic_jaw_prior(generic, rig=None):
    """The articulated jaw prior (:func:`autobones.rig_transfer.jaw_prior.jaw_prior`) of the generic rig
    ``rig`` names (loaded as ``generic``), or None when it has no ``jaw`` and ``head`` bones.

    Memoised per rig folder and ``mesh.obj`` time stamp like :func:`generic_detected_landmarks`.
    """
    if not {"jaw", "head"} <= set(generic.skeleton.names):
        return None
    folder = _rig_folder(rig)
    if folder is not None:
        return _jaw_prior_in_folder(folder, os.stat(os.path.join(folder, "mesh.obj")).st_mtime_ns)
    return jaw_prior(generic)


EXPRESSION_FILE = "expressions.npz"


@functools.lru_cache(maxsize=4)
def _expressions_in_folder(path, mtime_ns):
    # a pure function of the file (its time stamp in the key); read-only for its callers
    with np.load(path, allow_pickle=False) as z:
        return {"names": [str(n) for n in z["names"]], "basis": z["basis"].astype(np.float64)}


def generic_expression_space(generic, rig=None):
    """The generic skin's expression space (``expressions=`` of the fit,
    :mod:`autobones.rig_transfer.expression_prior`): the ARKit shapes carried onto the generic rig's
    own skin, ``expressions.npz`` in its folder (``names`` (k,), ``basis`` (k, n, 3) float16; the
    built-in rig's from ``generic_rig/build_expression_space.py``). None for a rig folder without
    the file, or a rig given as an object, or a file for another skin."""
    folder = _rig_folder(rig)
    if folder is None:
        return None
    path = os.path.join(folder, EXPRESSION_FILE)
    if not os.path.isfile(path):
        return None
    space = _expressions_in_folder(path, os.stat(path).st_mtime_ns)
    return space if space["basis"].shape[1:] == (len(generic.vertices), 3) else None


def face_motion(generic, rig=None):
    """How the generic rig's face moves, for the face gates (:func:`.joints.face_fit`,
    ``landmarks --assist``): a function ``(points, names) -> (k, len(names), 3)``, the displacement of
    ``points`` (dict str -> (3,) on the generic's skin, its frame) under each shape of its expression
    space and its jaw's hinge (:func:`autobones.landmarks.human_face.face_motion_fields`); None when
    the rig (``generic``, loaded from ``rig``: a folder, None the built-in one) has no space."""
    from ..landmarks.human_face import face_motion_fields

    space = generic_expression_space(generic, rig)
    if space is None:
        return None
    jaw = generic_jaw_prior(generic, rig)
    return lambda points, names: face_motion_fields(points, generic.vertices, generic.faces, space["basis"],
                                                    jaw, names)


def transfer(head, landmarks=None, rig=None, up=None, front=None, control_points=400, details=None, arkit=False,
             symmetric="auto", expression_fit=True, aim_head=True, **fit_options):
    """Carry the generic rig onto a landmarked head.

    Parameters
    ----------
    head : str, (V, F), mesh object or None
        The head mesh, any frame and unit: a file, arrays, an object with ``vertices`` and
        ``faces`` (``trimesh.Trimesh``), or None for the built-in default head.
    landmarks : str, dict of str -> (3,), or None
        A landmark file (contract JSON, MeshLab .pp, iBUG-68 .json/.pts/.ljson)
        or a dict, in the head's own frame; at least 10 names shared with the rig.
        None: found automatically on a human head (:mod:`autobones.landmarks.detect`; needs the
        ``landmarks`` extra); the rig's ``options['landmarks_source']`` says which.
    rig : str, LabelledRig or None
        The generic rig (a folder written by ``build_rig``); None: the built-in one. Not modified.
    up, front : str or None
        Override the detected axes (used to check left/right of the landmarks).
    control_points : int
        Size of the correspondence subsample the under-skin TPS is fitted on.
    details : dict, optional
        Filled with ``correspondence`` ((n_rig, 3): each generic vertex's point on
        the head) and ``reliable`` ((n_rig,) bool), for evaluation.
    arkit : bool
        Also make the 52 ARKit shapes on this head (:func:`autobones.arkit.targets.arkit_targets`):
        ``rig.arkit_targets`` and the ``rig.arkit`` record; ``save`` writes them as morph targets.
    expression_fit : bool
        Fit the generic skin wearing the expression the head seems to wear (solved on the ARKit set's
        skin with its identity modes, :mod:`autobones.rig_transfer.expression_prior`: an open jaw, a
        smile, a pucker; a neutral head, or one no human face fits, stays neutral), so the skin does not
        slide where the landmarks say nothing; ``rig.options['expression_fit']`` says what was found.
        The ARKit set's own correspondence stays neutral (:func:`~autobones.arkit.targets.shape_correspondence`).
        False: the neutral generic skin, as before.
    symmetric : {"auto", "on", "off"}
        Keep the correspondence mirror-symmetric (:mod:`autobones.rig_transfer.symmetry`): ``auto``
        when the head's landmark pairs are mirror images and the head and the generic skin are
        symmetric about their landmarks' planes (sculpts, cartoons, robots; not real scans, whose
        asymmetry the rig must follow, nor a one-sided expression, nor automatic landmarks);
        ``rig.options['symmetric']`` says what was measured and done.
    aim_head : bool
        Turn the ``head`` bone about its joint onto the up the head turns about
        (:attr:`autobones.orient.Frame.turn_axes`), so an exported head joint twists about it; False: the
        generic's bone as carried (``place --landmarks`` weighs its facial bones against that one).
    **fit_options
        Options of :func:`autobones.rig_transfer.correspondence.fit_surface`; ``jaw`` defaults to the
        generic rig's articulated jaw prior (:func:`generic_jaw_prior`; ``jaw=None`` fits without it).

    Returns
    -------
    Rig
        In the head's frame and units: the rig's skeleton, skin weights, labels,
        fields and muscles on the head's own vertices.

    Examples
    --------
    >>> import autobones
    >>> from autobones import samples
    >>> rig = autobones.transfer(samples.path("goat.obj"), samples.path("goat.pp"))
    >>> rig.skeleton.names
    ['neck', 'head', 'jaw', 'eye_l', 'eye_r']
    >>> len(rig.muscles), len(rig.options["landmarks_used"])
    (40, 14)
    >>> rig.fields["jaw_weight"].shape == (len(rig.vertices),)
    True
    """
    watch = Stopwatch()
    lap, timings = watch.lap, watch.timings

    V, F, source = resolve_mesh(head, strays=True)
    body = stray_parts(V, F) or worn_parts(V, F)
    if body is not None:   # parts far off or set on the head: rigged without them (io.parts)
        return body.restore(transfer(body.as_mesh(source), landmarks, rig, up, front, control_points, details, arkit,
                                     symmetric, expression_fit, aim_head, **fit_options), source)
    F_given, (F, wound) = F, wound_outward(V, F, source)   # fitted outward, written as given
    generic = load_generic(rig)
    lap("load")
    lm, frame, detected, shared = head_landmarks(V, F, source, landmarks, generic, up, front)
    lap("landmarks")
    src, dst = _landmark_pairs(generic, rig, lm, shared, detected, lap)
    # a smooth symmetric head gives its points nothing to stop them sliding across the midline: there the
    # correspondence is kept symmetric (not with automatic landmarks, whose mirror plane is a degree off);
    # the rig's own landmarks give its exact plane
    symmetry = Symmetry(symmetric, 0.0 if detected is not None else MAX_LANDMARK_MISMATCH).fit(
        generic.vertices, generic.faces, generic.landmarks, V, F, dst)
    fit_options.setdefault("symmetry", symmetry.fit_option())
    lap("symmetry")
    rig_option = "built-in" if rig is None else str(rig) if isinstance(rig, (str, os.PathLike)) else "object"
    shapes, space, found, found_details = _head_expression(generic, rig, rig_option, V, F, lm, detected,
                                                           expression_fit and "expressions" not in fit_options,
                                                           arkit, lap)
    # the ARKit shape set's own correspondence needs only the head and its landmarks: fitted on the
    # second core while this thread fits the generic rig (most of both runs outside the GIL)
    pending = _in_background(shapes, V, F, lm) if arkit else None
    P, ok, fit_details = _fit(generic, rig, V, F, src, dst, space, (found, found_details), fit_options, timings)
    if details is not None:
        details.update(correspondence=P, reliable=ok)
    lap("correspond")

    under, skeleton, placed = _under_skin(generic, P, ok, control_points, symmetry, src, dst, V, F, frame,
                                          by_face=detected is None, calibrated=face_points(_rig_folder(rig), "given"),
                                          motion=face_motion(generic, rig) if detected is None else None)
    muscles = carry_muscles(generic.muscles, under, generic.vertices, generic.faces, P)
    lap("skeleton")

    fields, W, skeleton, reliable = _carry_attributes(generic, P, ok, V, F, skeleton, under)
    lap("attributes")
    labels, facial_mask = _face_labels(fields, generic, len(V))
    fitted = _fitted_landmarks(generic, P, ANGLE)
    W, jaw_note = _neck_and_jaw(V, F, W, skeleton, frame, lm, facial_mask, lap, fitted)
    if aim_head and "head" in skeleton.names:   # carried, it ran toward the vertex: 3-81 degrees off
        skeleton = skeleton.aimed("head", frame.turn_axes[1])
    options = {"command": "transfer", "landmarks_used": shared, "up": up, "front": front,
               "landmarks_source": "file" if isinstance(landmarks, (str, os.PathLike)) else
               "detected" if detected is not None else "given",
               "rig": rig_option,
               "jaw_prior_degrees": round(float(fit_details.get("jaw_deg", 0.0)), 3),
               "joints_from_ears": placed["from_ears"],
               "joints_from_face": placed["from_face"],
               "joints_on_midplane": placed["on_midplane"],
               "symmetric": symmetry.record_,
               "expression_fit": _expression_record(found_details, fit_details, expression_fit, space,
                                                    detected is not None),
               **({"jaw": jaw_note} if jaw_note else {}), **({"faces_turned": wound} if wound else {})}
    out = Rig(
        vertices=V, faces=F, skeleton=skeleton, weights=W, labels=labels, facial_mask=facial_mask,
        frame=frame, options=options, timings=timings, fields=fields,
        source=source, muscles=jsonable(muscles), landmarks={n: lm[n] for n in lm},
        **({} if detected is None else {"landmark_confidence": detected.confidence,
                                        "landmarks_dropped": detected.dropped,
                                        "landmarks_flagged": detected.flagged}),
        field_labels={k: list(v) for k, v in generic.labels.items()},
        reliable_fraction=float(reliable.mean()))
    if arkit:
        from ..arkit.targets import arkit_targets

        out.arkit_targets, out.arkit = arkit_targets(out, shapes=shapes, correspondence=pending.result()[0])
        out.options["arkit"] = True
        lap("arkit")
    out.faces = F_given
    return out


def _under_skin(generic, P, ok, control_points, symmetry, src, dst, V, F, frame, by_face=True, calibrated=None,
                motion=None):
    """(under, skeleton, placed): the under-skin warp fitted on the correspondence ``P`` (n_rig, 3)
    where ``ok``, and the generic skeleton carried by it, its head and jaw then placed by the head's
    ears or face and its midplane (:func:`~.joints.anchor_joints`: ``placed`` says which; ``src`` and
    ``dst`` the shared landmarks on the generic and on the head; ``frame`` the head's, which tells a face
    mask; ``by_face`` False for automatic landmarks; ``calibrated`` where faces put the joints,
    :func:`~.joints.face_points`; ``motion`` how the generic's face moves, :func:`face_motion`)."""
    partners = symmetry.partners(generic.vertices, generic.faces)   # None unless the fit was symmetric
    under = under_skin_warp(generic.vertices, P, ok, control_points, partners=partners)
    skeleton = generic.skeleton.transformed(under.transform)
    # the dense warp follows the skull and neck, so the joints drift 0.08-0.16 ex-ex off the ear
    # canals' anatomy on the zoo's humans, and extrapolates the back of the head from a face's landmarks;
    # where the head has tragions they say where the joints are, else a human face's landmarks, and its
    # landmark pairs where its midplane is
    skeleton, placed = anchor_joints(skeleton, generic, dst, V, F, source=src, frame=frame, by_face=by_face,
                                     calibrated=calibrated, motion=motion)
    return under, skeleton, placed


def _fitted_landmarks(generic, P, names):
    """{name: (3,)}: the generic rig's landmarks ``names`` (those it has) where the correspondence ``P``
    (n_rig, 3) carried its skin, head frame."""
    names = [n for n in names if n in generic.landmarks]
    if not names:
        return {}
    points = np.array([generic.landmarks[n] for n in names], dtype=np.float64)
    return dict(zip(names, ride(points, generic.vertices, generic.faces, P)))


def _neck_and_jaw(V, F, W, skeleton, frame, lm, facial_mask, lap, fitted=None):
    """(W, note): the carried weights ``W`` (n, b) with the neck base made still and the jaw weight
    repaired from the landmarks ``lm``; ``note`` says why the jaw could not be cut cleanly, or None.
    ``fitted``: the generic's landmarks on the head (the jaw's angle where ``lm`` has no gonions)."""
    # the neck base still on a head turn, the head/neck blend on the head joint (the generic's own blend
    # lies far below it and the warp drags it anywhere: benchmarks zoo check 3); the face is untouched.
    # Before the jaw's repair, which has the last word where the chin reaches the neck base (a chin at
    # the mesh's bottom: the bunny) and keeps the jaw weight's falloff smooth
    W, still = still_neck_base(V, F, W, skeleton, frame, lm, facial_mask, fitted=fitted)
    lap("neck")
    # the jaw weight as the head's landmarks say: on the chin and lower lip, smooth off the lip line
    jaw_details = {}
    # teeth, gums, a mouth bag: separate parts no landmark speaks for, carried as the model poses them,
    # smoothed by the repair, the teeth then moved whole (mouth_parts)
    W = carried_mouth_parts(V, F, W, skeleton.names, skeleton.heads, frame, lm)[0]
    W = repair_jaw_weights(V, F, W, skeleton.names, lm, details=jaw_details, still=still)
    W = rigid_mouth_parts(V, F, W, skeleton.names, skeleton.heads, frame, lm)[0]
    # any other small closed part (a cartoon's button eye off the eye bones, a stud) moves whole too
    W = rigid_weights(W, V, F, closed_small_parts(V, F))
    if jaw_details.get("note"):
        log.warning("jaw: %s", jaw_details["note"])   # a head the landmarks cannot give a clean jaw cut
    lap("jaw")
    return W, jaw_details.get("note")


def _landmark_pairs(generic, rig, lm, shared, detected, lap):
    """(src, dst): the ``shared`` names' points on the generic skin and on the head (dicts str -> (3,)).
    With automatic landmarks the generic's points are the same detector's on its own skin (when it
    finds every shared name), so the detector's biases (brows, eye corners) cancel instead of pulling
    the correspondence."""
    src = {n: generic.landmarks[n] for n in shared}
    if detected is not None:
        mirror = generic_detected_landmarks(generic, rig)
        if mirror is not None and all(n in mirror for n in shared):
            src = {n: mirror[n] for n in shared}
        lap("generic_landmarks")
    return src, {n: lm[n] for n in shared}


def _head_expression(generic, rig, rig_option, V, F, lm, detected, fit, arkit, lap):
    """(shapes, space, found, found_details): the ARKit shape set (None unless needed), the generic's
    expression space (None: the fit stays neutral), and the expression the head seems to wear
    ({name: weight} and the solve's record; empty when not solved).

    The expression is solved on the ARKit set's skin (a real face, with its identity modes: what its
    warp leaves between the landmarks is then the expression; on the generic's own skin it would be
    the generic's identity) and worn by the generic skin in its fit. ``fit``: the caller asked for the
    expression-aware fit and gave no space of its own."""
    shapes, found, found_details = None, {}, {}
    space = generic_expression_space(generic, rig) if fit else None
    if space is not None or arkit:
        from ..arkit.targets import rig_shape_set

        shapes = rig_shape_set(rig_option)
        if shapes.identity is None or detected is not None:
            # without identity modes a face's own shape is taken for an expression, and the detector's
            # biases against the set's hand-placed landmarks are (a neutral ICT identity gained 0.47)
            space = None
    if space is not None:
        found, found_details = shape_set_expression(shapes, V, F, lm, identity=shapes.identity)
        lap("expression")
    return shapes, space, found, found_details


def _in_background(shapes, V, F, lm):
    """A future of :func:`autobones.arkit.targets.shape_correspondence` on one worker thread."""
    from concurrent.futures import ThreadPoolExecutor

    from ..arkit.targets import shape_correspondence

    pool = ThreadPoolExecutor(1)
    pending = pool.submit(shape_correspondence, shapes, V, F, lm)
    pool.shutdown(wait=False)  # the worker ends with its one task
    return pending


def _fit(generic, rig, V, F, src, dst, space, expression, fit_options, timings):
    """The dense correspondence of the generic skin on the head: ``P`` (n_rig, 3) each generic vertex's
    point on the head (input frame), ``ok`` (n_rig,) bool reliable, and the fit's details; its
    timings go into ``timings`` as ``fit_*``. ``expression``: (found, record), the expression the head
    seems to wear and the solve's record (:func:`_head_expression`). ``fit_options`` (the caller's,
    completed here: the jaw prior, the expression worn and the warp's far field unless given) is
    changed in place."""
    found, solved = expression
    if "jaw" not in fit_options:
        # the generic's jaw opened as far as the head's landmarks say before the warp: a smooth warp
        # cannot open a mouth, and the chin and neck slid without it (benchmarks/correspondence.py)
        fit_options["jaw"] = generic_jaw_prior(generic, rig)
    if "expressions" not in fit_options:
        fit_options["expressions"] = {**space, "weights": found} if any(found.values()) else None
    if "far_field" not in fit_options and space is not None and solved.get("misfit", np.inf) <= MAX_MISFIT:
        # a face the expression space fits: the landmarks' spline only near them, their affine map far
        # from them, whatever it wears (the same warp for a person's every expression, so the generic
        # lands alike on each); what the space does not explain (a smile unlike its own) then stays
        # local instead of bending the ears, scalp and neck (benchmarks/expression_fit.py)
        fit_options["far_field"] = "local"
    fit_timings, fit_details = {}, {}
    P, _, _, ok = dense_correspondence(generic.vertices, generic.faces, V, F, src, dst, timings=fit_timings,
                                       details=fit_details, **fit_options)
    timings.update({f"fit_{k}": v for k, v in fit_timings.items()})
    return P, ok, fit_details


def _face_labels(fields, generic, n):
    """(labels, facial_mask): the carried depth groups ((n,) int8, 0 the face) and the face without the
    generic's neck region ((n,) bool)."""
    labels = fields["depth_group"].astype(np.int8) if "depth_group" in fields else np.zeros(n, np.int8)
    facial_mask = labels == 0
    if "region" in fields and "region" in generic.labels and "neck" in generic.labels["region"]:
        facial_mask &= fields["region"] != generic.labels["region"].index("neck")
    return labels, facial_mask


def _expression_record(found, fit_details, asked, space, detected):
    """The sidecar's ``expression_fit``: the expression the head seems to wear (``weights`` {name:
    weight} over 0.05, empty for a neutral head; ``gain``: the share of the neutral skin's misfit it
    removes), the weights the generic skin wore in its fit (``generic``) and the warp its fit started
    from (``warp``: ``local`` on a face the space fits, else ``spline``), or why it did not run."""
    if not asked:
        return {"off": "expression_fit=False (--no-expression-fit)"}
    if detected:
        return {"off": "automatic landmarks: their biases against the shape set's hand-placed ones would be taken "
                       "for an expression; give a landmark file to fit an expressive head"}
    if space is None:
        return {"off": "the generic rig has no expression space (expressions.npz), its shape set no identity modes, "
                       "or the fit was given one"}
    return {"weights": found.get("weights", {}), "gain": found.get("gain", 0.0),
            **({"note": found["note"]} if "note" in found else {}), "solved_on": "the ARKit shape set's skin",
            "generic": fit_details.get("expression", {}).get("weights", {}), "warp": fit_details.get("far_field")}


def _carry_attributes(generic, P, ok, V, F, skeleton, under):
    """Skin weights and fields of the generic rig on the head's vertices, eyeballs bound.

    ``P`` (n_rig, 3) and ``ok`` (n_rig,) bool are the correspondence; returns ``fields``
    (dict, one row per head vertex), ``W`` (n, b) pruned weights summing to 1, the skeleton
    with eye bones centred in modelled eyeballs, and ``reliable`` (n,) bool (copied, not inpainted).
    """
    fields = {"__weights__": generic.weights, **generic.fields}
    out, reliable = transfer_fields(P, generic.faces, fields, V, F, source_reliable=ok)
    W = np.clip(out.pop("__weights__"), 0.0, None)
    W = prune_weights(W / np.maximum(W.sum(axis=1, keepdims=True), 1e-300))  # inpainting leaves faint tails
    W, eyeballs = bind_eyeballs(V, F, W, skeleton, generic, under)
    return out, W, centre_eye_bones(V, skeleton, eyeballs), reliable
