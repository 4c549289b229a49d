"""The carried head and jaw joints put where the head's anatomy is: from its ear canals or its face, on its midplane.

``transfer`` carries the generic rig's skeleton by the under-skin warp of the dense correspondence
(:mod:`.under_skin`), which follows the whole head's shape: on the zoo's SMPL heads it put the head
joint 0.08-0.13 ex-ex from the occiput-C1 centre and the jaw 0.05-0.08 from the condyle, and on
heads without ear landmarks 0.04-0.06 ex-ex beside the landmarks' midplane (James, the bunny:
``benchmarks/zoo.py`` check 4). Where a landmark file stops at the face (a face scan's, a mask's),
the warp extrapolates the generic's back of the head from the face alone: on the eight human heads of
the shared data given only their face's landmarks it put the head joint 0.10-0.40 ex-ex from the
occiput-C1 centre and the jaw 0.15-0.42 from the condyle, on the same heads cut into masks behind or
in front of their ears up to 0.57 and 0.49 (``benchmarks/joints.py --given face``).
Both joints are midline ones (the generic's are, :mod:`autobones.rig_building.anatomy`).
"""
from __future__ import annotations

import functools
import os

import numpy as np

from ..geometry.head_share import face_only
from ..geometry.mirror_plane import onto_plane
from ..io.landmark_names import mirror_name

EAR_LANDMARKS = ("tragion_l", "tragion_r", "exocanthion_l", "exocanthion_r")
MIN_PAIRS = 2   # left/right landmark pairs needed to say where the midplane is
# landmarks beyond the face: with one the warp has the back or top of the head or the jaw's angle to
# follow (the SMPL heads with opisthocranion, vertex and gonions but no tragions: head 0.06-0.09 ex-ex
# off by the warp, 0.12-0.13 by the face's similarity)
BACK_LANDMARKS = ("tragion_l", "tragion_r", "opisthocranion", "vertex", "gonion_l", "gonion_r")
MIN_FACE = 6        # landmarks the face's similarity needs
JAW_CARRIED = ("menton", "pogonion", "labiale_inferius", "sublabiale")   # move with an open jaw
# ex-ex: the largest RMS residual of the face's similarity to the generic's landmarks (every shared name)
# for a human face: the shared humans' face landmarks 0.043-0.082, ICT's generic head with its jaw open
# 0.116; the zoo's animals, cartoons, toys and robot 0.135-0.422 (the ogre the nearest), whose joints the
# warp places better (a human's proportions put a cat's head joint 0.84 ex-ex off, the warp 0.67). The
# beast, a monster with a human face, measures 0.083 and takes a human's joints.
HUMAN_FIT = 0.12
# ex-ex: the same gate with the generic's face free to wear its expression space and open its jaw
# (``pipeline.face_motion``; :func:`autobones.landmarks.human_face.face_distance` over the shared names). The
# neutral residual grows with an expression as far as an ogre's: ICT identity000 with its jaw open 0.117
# (refused by the face's own fit), surprised 0.106, against the ogre's 0.130. Wearing one: the shared humans,
# neutral or expressive, 0.028-0.084 (0.088 with the expression left out of the space); the animals, toys
# and robot 0.105 (the ogre) to 0.269; the beast 0.066 (a human face, as before). With the detector's
# landmarks on both skins (``place`` on a face mask): humans 0.050-0.078, the stuffed toy 0.142
HUMAN_FIT_EXPRESSIVE = 0.095
FACE_JOINTS_FILE = "face_joints.json"   # in a rig's folder: where human faces put its joints
FACE_JOINTS_FORMAT = "autobones-face-joints/1"


def anchor_joints(skeleton, generic, landmarks, V, F, source=None, frame=None, by_face=True,
                  names=("head", "jaw"), calibrated=None, motion=None):
    """The carried ``head`` and ``jaw`` joints moved to where the generic's sit relative to the head's
    ear canals, or else to its human face, and onto the landmarks' midplane.

    The generic rig's joints are placed from its tragions (the occiput-C1 centre of rotation and the
    condyles; Chancey, Ottaviano, Myers & Nightingale 2007, :mod:`autobones.rig_building.anatomy`).
    Where the head has both tragions and both exocanthions, each joint is the head's tragion
    midpoint plus the generic's offset from its own, turned by the landmarks' similarity (Umeyama
    1991) and scaled by the ex-ex ratio (the measurement's own scaling): 0.03-0.05 and 0.01-0.02
    ex-ex from the anatomy on the SMPL heads. Without them, on a human face whose landmarks stop at
    the face (none of ``BACK_LANDMARKS``: the ears, the back and top of the head, the jaw's angles; at
    least ``MIN_FACE`` shared with the generic; the similarity's RMS residual within ``HUMAN_FIT``
    ex-ex), each joint is the generic's, or where human faces put it (``calibrated``), mapped by the
    landmarks' similarity (fitted on the names the jaw does not carry): the generic's own 0.09-0.22
    ex-ex from the occiput-C1 centre and 0.11-0.22 from the condyle on those heads, whole or cut into
    masks (the beast, a sculpted monster whose face's landmarks fit a human's, 0.08, gets its jaw 0.21
    from the condyle, the warp's 0.07; 0.17 where faces put it). Either way, with at least
    ``MIN_PAIRS`` left/right pairs, each joint then goes onto the landmarks' midplane
    (``landmarks.refine.symmetry_plane``):
    the similarity's small roll and asymmetric tragions put them 0.02-0.04 ex-ex beside it on the
    cat and the stuffed toy, the warp 0.04-0.06 on James. A joint that would fall outside the head
    (winding number below 1/2) is moved back toward the carried one until inside, or left where the
    warp put it; a face mask has no inside, and its joints stay behind it where the face puts them.

    Parameters
    ----------
    skeleton : Skeleton
        The carried skeleton, head frame.
    generic : LabelledRig
        The generic rig (its ``skeleton`` and ``landmarks``, its own frame).
    landmarks : dict str -> (3,) float
        The head's landmarks shared with the generic rig, head frame.
    V, F : (n, 3) float, (m, 3) int
        The head.
    source : dict str -> (3,) float, optional
        The same names' points on the generic skin (its frame; the detector's own on the generic
        when the head's were detected, so their biases cancel); default ``generic.landmarks``.
    frame : autobones.orient.Frame, optional
        The head's frame: it tells a face-only capture (:func:`autobones.geometry.head_share.face_only`)
        when the face places the joints; None: the head is taken for a closed one.
    by_face : bool
        Whether a face's similarity may place the joints. Not for automatic landmarks: with the
        detector's on both skins the warp has nothing to unlearn, and it put the head joint of ICT's
        identities and James 0.03-0.07 ex-ex from the occiput-C1 centre, the similarity 0.10-0.22
        (the SMPL heads and Lee Perry-Smith: warp 0.14-0.17, similarity 0.10-0.14).
    names : tuple of str
        Joints to place.
    calibrated : dict str -> (3,) float, optional
        Where human faces put these joints against ``source`` (the generic's frame;
        :func:`face_points`), mapped instead of the generic's
        own joints when the face places them: the generic's, mapped by hand-placed face landmarks,
        sat 0.09-0.22 ex-ex from the occiput-C1 centre and 0.11-0.22 from the condyle on the shared
        human heads; calibrated on the heads of the other source families, 0.06-0.21 and 0.03-0.17.
    motion : callable, optional
        How the generic's face moves (:func:`autobones.rig_transfer.pipeline.face_motion`): a face
        that fits the generic only wearing an expression (a smile, an open jaw) still places the joints.

    Returns
    -------
    (Skeleton, dict)
        The skeleton (a parent bone whose tail was at a moved joint follows it) and the joints placed
        ``from_ears``, ``from_face`` and put ``on_midplane`` (lists of names).
    """
    from ..landmarks.refine import symmetry_plane
    from ..skeleton import Skeleton

    G = generic.landmarks if source is None else source
    from_ears = _from_the_ears(G, landmarks)
    from_face = None if from_ears is not None or not by_face else face_similarity(G, landmarks, motion)
    mapped = from_ears or from_face
    pairs = sum(1 for n in landmarks if n.endswith("_l") and mirror_name(n) in landmarks)
    plane = symmetry_plane(landmarks) if pairs >= MIN_PAIRS else None
    placed = {"from_ears": [], "from_face": [], "on_midplane": []}
    if mapped is None and plane is None:
        return skeleton, placed
    # a face mask has no inside to keep the face's joints in (asked only when the face places them)
    face_mask = from_face is not None and frame is not None and face_only(frame.to_canonical(V), F)
    heads, tails = np.array(skeleton.heads, dtype=np.float64), np.array(skeleton.tails, dtype=np.float64)
    bones, gbones = list(skeleton.names), list(generic.skeleton.names)
    size = float(np.ptp(V, axis=0).max())
    for name in (n for n in names if n in bones and n in gbones):
        i = bones.index(name)
        at = generic.skeleton.heads[gbones.index(name)]
        if from_face is not None and calibrated is not None and name in calibrated:
            at = calibrated[name]
        want = heads[i] if mapped is None else mapped(at)
        if plane is not None:
            want = onto_plane(want, *plane)
        p = want if face_mask else _inside_toward(V, F, want, heads[i])
        if p is None:
            continue
        # the bone ending at this joint (the neck's tail at the head joint) keeps meeting it
        tails[np.linalg.norm(tails - heads[i], axis=1) <= 1e-9 * size] = p
        heads[i] = p
        if mapped is not None:
            placed["from_ears" if from_ears is not None else "from_face"].append(name)
        if plane is not None:
            placed["on_midplane"].append(name)
    return Skeleton(bones, np.array(skeleton.parents).copy(), heads, tails), placed


def face_similarity(G, landmarks, motion=None):
    """A map from a generic joint (3,) (the generic's frame) to where it goes on a human face by the
    landmarks' similarity (Umeyama 1991) from the generic's ``G`` (dict str -> (3,)) to ``landmarks``
    (dict str -> (3,), the head's frame), or None: see :func:`face_fit` (``motion`` its gate's)."""
    fit = face_fit(G, landmarks, motion)
    if fit is None:
        return None
    s, R, p0, q0 = fit
    return lambda joint: q0 + s * (R @ (np.asarray(joint, dtype=np.float64) - p0))


def onto_face(G, landmarks, points, motion=None):
    """``points`` (dict str -> (3,), the generic's frame) mapped onto a human face by the similarity of
    the generic's landmarks ``G`` to the face's ``landmarks`` (both dict str -> (3,)), then onto the
    landmarks' midplane (``landmarks.refine.symmetry_plane``); None where no similarity fits
    (:func:`face_fit`, ``motion`` its gate's)."""
    from ..landmarks.refine import symmetry_plane

    shared = {n: np.asarray(p, dtype=np.float64) for n, p in landmarks.items() if n in G}
    mapped = face_similarity(G, shared, motion)
    if mapped is None:
        return None
    plane = symmetry_plane(shared)
    return {k: onto_plane(mapped(p), *plane) for k, p in points.items()}


def face_fit(G, landmarks, motion=None):
    """The similarity ``x -> q0 + s R (x - p0)`` (scale, (3, 3), (3,), (3,)) from the generic's
    landmarks ``G`` (dict str -> (3,)) to a human face's ``landmarks`` (dict str -> (3,), the head's
    frame), or None: landmarks behind the face, fewer than ``MIN_FACE`` shared, or a face no
    similarity of the generic's fits (an animal's, a cartoon's).

    The gate's residual is over every shared name (the humans' 0.04-0.08 ex-ex stand furthest from the
    animals' so): within ``HUMAN_FIT`` of the neutral generic's, or with ``motion``
    (:func:`autobones.rig_transfer.pipeline.face_motion`) within ``HUMAN_FIT_EXPRESSIVE`` of the
    generic wearing the expression that fits best (a smiling or open-mouthed face is a human's too).
    The map is fitted on the names the jaw does not carry (``JAW_CARRIED``) when there are ``MIN_FACE``
    of them: an open jaw (ICT's jawOpen) moved the head joint 0.18 ex-ex with them, 0.08 without. With
    ``motion`` each of those names weighs by how still the generic's expressions leave it
    (:func:`autobones.landmarks.human_face.stillness`): a smile's mouth corners and surprised brows
    put ICT's people's head joints 0.12-0.20 ex-ex from the anatomy, 0.06-0.10 weighted (their family
    held out of the calibration: benchmarks/README.md, "the face's pose from what expressions leave
    still")."""
    from ..geometry.rotations import similarity

    shared = [n for n in landmarks if n in G]
    eyes = ("exocanthion_l", "exocanthion_r")
    if any(n in landmarks for n in BACK_LANDMARKS) or len(shared) < MIN_FACE or not all(n in G for n in eyes):
        return None

    def fit(names, weights=None):
        P = np.array([G[n] for n in names], dtype=np.float64)
        Q = np.array([landmarks[n] for n in names], dtype=np.float64)
        s, R = similarity(P, Q, weights)
        p0, q0 = np.average(P, axis=0, weights=weights), np.average(Q, axis=0, weights=weights)
        return s, R, p0, q0, np.sqrt((((Q - q0) - s * (P - p0) @ R.T) ** 2).sum(axis=1).mean())

    g_exex = float(np.linalg.norm(np.asarray(G["exocanthion_l"]) - np.asarray(G["exocanthion_r"])))
    upper = [n for n in shared if n not in JAW_CARRIED]
    names = upper if len(upper) >= MIN_FACE else shared
    if motion is not None and all(n in landmarks for n in eyes):
        from ..landmarks.human_face import face_distance, stillness

        gate = list(eyes) + [n for n in shared if n not in eyes]
        D = motion(G, gate)
        if not face_distance(landmarks, G, D, names=gate) <= HUMAN_FIT_EXPRESSIVE:
            return None
        weights = stillness(D[:, [gate.index(n) for n in names]], g_exex)
    else:
        s, _, _, _, residual = fit(shared)
        if not residual <= HUMAN_FIT * (s * g_exex):
            return None
        weights = None
    return fit(names, weights)[:4]


def _from_the_ears(G, landmarks):
    """A map from a generic joint (3,) to where it goes on the head by its ear canals, or None
    without both tragions and both exocanthions on both (``G`` the generic's landmarks)."""
    from ..geometry.rotations import similarity

    if not all(n in landmarks and n in G for n in EAR_LANDMARKS):
        return None
    shared = [n for n in landmarks if n in G]
    _, R = similarity(np.array([G[n] for n in shared], dtype=np.float64),
                      np.array([landmarks[n] for n in shared], dtype=np.float64))

    def ears(L):
        L = {n: np.asarray(L[n], dtype=np.float64) for n in EAR_LANDMARKS}
        return 0.5 * (L["tragion_l"] + L["tragion_r"]), float(np.linalg.norm(L["exocanthion_l"] - L["exocanthion_r"]))

    (ear_g, ex_g), (ear_t, ex_t) = ears(G), ears(landmarks)
    return lambda joint: ear_t + (ex_t / ex_g) * (R @ (np.asarray(joint, dtype=np.float64) - ear_g))


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


def face_points(folder, kind="given"):
    """Where human faces put the ``head`` and ``jaw`` joints against a generic rig's landmarks (dict str ->
    (3,), the generic's frame), or None: ``face_joints.json`` in the rig's ``folder`` (the built-in rig's
    from ``tools/calibrate_face_joints.py``; a rig of one's own has none, and its own joints are mapped;
    ``folder`` None, a rig given as an object, likewise). ``kind``: ``"detected"`` against the detector's
    landmarks of the generic skin (``place`` on a face mask), ``"given"`` against its contract landmarks
    (``transfer`` with a face's landmark file)."""
    path = None if folder is None else os.path.join(folder, FACE_JOINTS_FILE)
    if path is None or not os.path.isfile(path):
        return None
    return _face_points_in_file(path, os.stat(path).st_mtime_ns).get(kind) or None


@functools.lru_cache(maxsize=4)
def _face_points_in_file(path, mtime_ns):
    # a pure function of the file (its time stamp in the key); read-only for its callers
    from ..io.files import read_json

    data = read_json(path, "rig", "rig folder's face_joints.json", "not readable face joints JSON")
    if not isinstance(data, dict) or data.get("format") != FACE_JOINTS_FORMAT:
        return {}
    return {kind: {n: np.asarray(p, dtype=np.float64) for n, p in data.get(kind, {}).items()}
            for kind in ("detected", "given")}
