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
   canals (:func:`anchor_joints_at_the_ears`; Chancey et al. 2007);
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
from .expression_prior import shape_set_expression
from .jaw_prior import jaw_prior
from .eyes import bind_eyeballs, centre_eye_bones
from .jaw import repair_jaw_weights
from .neck import still_neck_base
from .fields import transfer_fields
from .symmetry import MAX_LANDMARK_MISMATCH, Symmetry
from .under_skin import carry_muscles, under_skin_warp
from ..errors import AutobonesError, counted
from ..io.jsonable import jsonable
from ..io.landmarks import NAMES, resolve_landmarks, validate_landmarks
from ..io.mesh import resolve_mesh, stray_parts
from ..orient import detect_frame, frame_from_landmarks
from ..geometry.weights import prune_weights
from ..rig import Rig
from ..timing import Stopwatch

log = logging.getLogger("autobones")

MIN_LANDMARKS = 10


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


def transfer(head, landmarks=None, rig=None, up=None, front=None, control_points=400, details=None, arkit=False,
             symmetric="auto", expression_fit=True, **fit_options):
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
    body = stray_parts(V, F)
    if body is not None:   # small parts far off: rigged without them, then weighted to the neck (io.mesh)
        return body.restore(transfer((body.V, body.F), landmarks, rig, up, front, control_points, details, arkit,
                                     symmetric, expression_fit, **fit_options), source)
    generic = load_generic(rig)
    lap("load")
    lm, frame, detected, shared = _head_landmarks(V, F, source, landmarks, generic, up, front)
    lap("landmarks")
    src = {n: generic.landmarks[n] for n in shared}
    if detected is not None:
        # the same detector on the generic skin: its biases (brows, eye corners) then cancel
        # instead of pulling the correspondence
        mirror = generic_detected_landmarks(generic, rig)
        if mirror is not None and all(n in mirror for n in shared):
            src = {n: mirror[n] for n in shared}
        lap("generic_landmarks")
    dst = {n: lm[n] for n in shared}
    # a smooth symmetric head gives its points nothing to stop them sliding across the midline: there the
    # correspondence is kept symmetric (not with automatic landmarks, whose mirror plane is a degree off);
    # the rig's own landmarks give its exact plane
    symmetry = Symmetry(symmetric, 0.0 if detected is not None else MAX_LANDMARK_MISMATCH).fit(
        generic.vertices, generic.faces, generic.landmarks, V, F, dst)
    fit_options.setdefault("symmetry", symmetry.fit_option())
    lap("symmetry")
    rig_option = "built-in" if rig is None else str(rig) if isinstance(rig, (str, os.PathLike)) else "object"
    found, found_details = {}, {}
    space = generic_expression_space(generic, rig) if expression_fit and "expressions" not in fit_options else None
    if space is not None or arkit:
        from ..arkit.targets import rig_shape_set

        shapes = rig_shape_set(rig_option)
        if shapes.identity is None or detected is not None:
            # without identity modes a face's own shape is taken for an expression, and the detector's
            # biases against the set's hand-placed landmarks are (a neutral ICT identity gained 0.47)
            space = None
    if space is not None:
        # the expression solved on the ARKit set's skin (a real face, with its identity modes: what its
        # warp leaves between the landmarks is then the expression; on the generic's own skin it would
        # be the generic's identity) and worn by the generic skin in its fit
        found, found_details = shape_set_expression(shapes, V, F, lm, identity=shapes.identity)
        lap("expression")
    pending = None
    if arkit:
        # the ARKit shape set's own correspondence needs only the head and its landmarks: fitted on the
        # second core while this thread fits the generic rig (most of both runs outside the GIL)
        from concurrent.futures import ThreadPoolExecutor

        from ..arkit.targets import shape_correspondence

        pool = ThreadPoolExecutor(1)
        pending = pool.submit(shape_correspondence, shapes, V, F, lm)
        pool.shutdown(wait=False)  # the worker ends with its one task
    fit_timings = {}
    if "jaw" not in fit_options:
        # the generic's jaw opened as far as the head's landmarks say before the warp: a smooth warp
        # cannot open a mouth, and the chin and neck slid without it (benchmarks/correspondence.py)
        fit_options["jaw"] = generic_jaw_prior(generic, rig)
    if "expressions" not in fit_options:
        fit_options["expressions"] = {**space, "weights": found} if any(found.values()) else None
    fit_details = {}
    P, _, _, ok = dense_correspondence(generic.vertices, generic.faces, V, F, src, dst, timings=fit_timings,
                                       details=fit_details, **fit_options)
    timings.update({f"fit_{k}": v for k, v in fit_timings.items()})
    if details is not None:
        details.update(correspondence=P, reliable=ok)
    lap("correspond")

    partners = symmetry.partners(generic.vertices, generic.faces)   # None unless the fit was symmetric
    under = under_skin_warp(generic.vertices, P, ok, control_points, partners=partners)
    skeleton = generic.skeleton.transformed(under.transform)
    # the dense warp follows the skull and neck, so the joints drift 0.08-0.16 ex-ex off the ear
    # canals' anatomy on the zoo's humans; where the head has tragions they say where it is
    skeleton, from_ears = anchor_joints_at_the_ears(skeleton, generic, {n: lm[n] for n in shared}, V, F)
    muscles = carry_muscles(generic.muscles, under, generic.vertices, generic.faces, P)
    lap("skeleton")

    fields, W, skeleton, reliable = _carry_attributes(generic, P, ok, V, F, skeleton, under)
    lap("attributes")
    labels = fields["depth_group"].astype(np.int8) if "depth_group" in fields else np.zeros(len(V), np.int8)
    facial_mask = labels == 0
    if "region" in fields and "region" in generic.labels and "neck" in generic.labels["region"]:
        facial_mask &= fields["region"] != generic.labels["region"].index("neck")
    # the neck base still on a head turn, the head/neck blend on the head joint (the generic's own blend
    # lies far below it and the warp drags it anywhere: benchmarks zoo check 3); the face is untouched.
    # Before the jaw's repair, which has the last word where the chin reaches the neck base (a chin at
    # the mesh's bottom: the bunny) and keeps the jaw weight's falloff smooth
    W, still = still_neck_base(V, F, W, skeleton, frame, lm, facial_mask)
    lap("neck")
    # the jaw weight as the head's landmarks say: on the chin and lower lip, smooth off the lip line
    jaw_details = {}
    W = repair_jaw_weights(V, F, W, skeleton.names, lm, details=jaw_details, still=still)
    if jaw_details.get("note"):
        log.warning("jaw: %s", jaw_details["note"])   # a head the landmarks cannot give a clean jaw cut
    lap("jaw")

    options = {"command": "transfer", "landmarks_used": shared, "up": up, "front": front,
               "landmarks_source": "file" if isinstance(landmarks, (str, os.PathLike)) else
               "detected" if detected is not None else "given",
               "rig": rig_option,
               "jaw_prior_degrees": round(float(fit_details.get("jaw_deg", 0.0)), 3),
               "joints_from_ears": from_ears,
               "symmetric": symmetry.record_,
               "expression_fit": _expression_record(found_details, fit_details, expression_fit, space,
                                                    detected is not None),
               **({"jaw": jaw_details["note"]} if jaw_details.get("note") else {})}
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
    return out


def _expression_record(found, fit_details, asked, space, detected):
    """The sidecar's ``expression_fit``: the expression the head seems to wear (``weights`` {name:
    weight} over 0.05, empty for a neutral head; ``gain``: the share of the neutral skin's misfit it
    removes) and the weights the generic skin wore in its fit (``generic``), or why it did not run."""
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
            "generic": fit_details.get("expression", {}).get("weights", {})}


EAR_LANDMARKS = ("tragion_l", "tragion_r", "exocanthion_l", "exocanthion_r")


def anchor_joints_at_the_ears(skeleton, generic, landmarks, V, F, names=("head", "jaw")):
    """The carried ``head`` and ``jaw`` joints moved to where the generic's sit relative to its ear canals.

    The generic rig's joints are placed from its tragions (the occiput-C1 centre of rotation and the
    condyles; Chancey, Ottaviano, Myers & Nightingale 2007, :mod:`autobones.rig_building.anatomy`).
    The dense warp carries them by the whole head's shape, which on the zoo's SMPL heads put the
    head joint 0.08-0.13 ex-ex off and the jaw 0.05-0.08. Here each joint is the head's tragion
    midpoint plus the generic's offset from its own, turned by the landmarks' similarity (Umeyama
    1991) and scaled by the ex-ex ratio (the measurement's own scaling): 0.03-0.05 and 0.01-0.02
    ex-ex there; then put on the landmarks' midplane (``landmarks.refine.symmetry_plane``). A joint
    that would fall outside the head (winding number below 1/2) is moved back toward the carried one
    until inside, or left where the warp put it.

    Parameters
    ----------
    skeleton : Skeleton
        The carried skeleton, head frame.
    generic : LabelledRig
        The generic rig (its ``skeleton`` and ``landmarks``, its own frame).
    landmarks : dict str -> (3,) float
        The head's landmarks shared with the generic rig, head frame; without both tragions and
        both exocanthions nothing moves.
    V, F : (n, 3) float, (m, 3) int
        The head.
    names : tuple of str
        Joints to anchor.

    Returns
    -------
    (Skeleton, list of str)
        The skeleton (a parent bone whose tail was at a moved joint follows it) and the joints moved.
    """
    from ..geometry.rotations import similarity
    from ..landmarks.refine import symmetry_plane
    from ..skeleton import Skeleton

    G = generic.landmarks
    if not all(n in landmarks and n in G for n in EAR_LANDMARKS):
        return skeleton, []
    shared = [n for n in landmarks if n in G]
    P = np.array([G[n] for n in shared], dtype=np.float64)
    Q = np.array([landmarks[n] for n in shared], dtype=np.float64)
    _, R = similarity(P, Q)

    def ears(L):
        L = {n: np.asarray(L[n], dtype=np.float64) for n in EAR_LANDMARKS}
        return 0.5 * (L["tragion_l"] + L["tragion_r"]), float(np.linalg.norm(L["exocanthion_l"] - L["exocanthion_r"]))

    (ear_g, ex_g), (ear_t, ex_t) = ears(G), ears(landmarks)
    # both joints are midline ones (the generic's are, rig_building.anatomy): the similarity's small
    # roll and asymmetric tragions put them 0.02-0.04 ex-ex beside the landmarks' midplane on the cat
    # and the stuffed toy (benchmarks/joints.py); they go onto it
    normal, offset = symmetry_plane(landmarks)
    heads, tails = np.array(skeleton.heads, dtype=np.float64), np.array(skeleton.tails, dtype=np.float64)
    bones, gbones = list(skeleton.names), list(generic.skeleton.names)
    size = float(np.ptp(V, axis=0).max())
    moved = []
    for name in (n for n in names if n in bones and n in gbones):
        i = bones.index(name)
        want = ear_t + (ex_t / ex_g) * (R @ (np.asarray(generic.skeleton.heads[gbones.index(name)]) - ear_g))
        want = want - (float(want @ normal) - offset) * normal
        p = _inside_toward(V, F, want, heads[i])
        if p is None:
            continue
        # the bone ending at this joint (the neck's tail at the head joint) keeps meeting it
        tails[np.linalg.norm(tails - heads[i], axis=1) <= 1e-9 * size] = p
        heads[i] = p
        moved.append(name)
    return Skeleton(bones, np.array(skeleton.parents).copy(), heads, tails), moved


def _inside_toward(V, F, p, anchor, steps=20):
    """``p`` (3,) if inside the head, else the first point inside on the way to ``anchor`` (3,), else
    None. Inside: a winding number above 1/2, or at least the anchor's own where that is lower (an
    open mouth or neck lowers it around a joint that is inside all the same)."""
    import igl

    Q = p + np.linspace(0.0, 1.0, steps + 1)[:, None] * (anchor - p)
    w = igl.fast_winding_number(np.ascontiguousarray(V, dtype=np.float64), np.ascontiguousarray(F, dtype=np.int64),
                                np.ascontiguousarray(Q))
    inside = np.flatnonzero(w > min(0.5, w[-1] - 1e-9))
    return Q[inside[0]] if len(inside) and inside[0] < steps else None


def _head_landmarks(V, F, source, landmarks, generic, up, front):
    """The head's landmarks and frame: read and validated, or detected when ``landmarks`` is None.

    Returns ``lm`` (dict str -> (3,) float64, input frame), ``frame`` (orient.Frame),
    ``detected`` (the detector's result, or None for given landmarks) and ``shared`` (the
    contract names in both ``lm`` and the generic rig, contract order).
    """
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
            f"{where}: only {counted(len(shared), 'landmark name')} {'is' if len(shared) == 1 else 'are'} shared with the generic rig "
            f"({', '.join(shared) or 'none'}); at least {MIN_LANDMARKS} well-spread ones are needed")
    return lm, frame, detected, shared


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
