"""Find a head's up, front and left-right symmetry plane; map to and from the canonical frame.

Goes beyond the papers we implement: the bone-placement method of ``place`` assumes the head
already stands +Y up facing +Z.
Real heads arrive Z-up or Y-up, facing +-X or +-Z, in millimetres or metres.

Method
------
1. The symmetry plane: reflective ICP on an area-uniform sample (pair each point with the nearest
   point to its mirror image; the pair differences give the normal, their midpoints the offset),
   started from the best directions of the sample's own principal frame
   (:func:`autobones.geometry.mirror_plane.shape_starts`). The plane that mirrors the sample onto
   itself best wins.
2. Up and front: 12 ups round the symmetry plane, from the main cut's far side or the sample's own
   longest in-plane axis (:mod:`autobones.frame_candidates`), each with both fronts. When one
   direction clearly has a cut at its far end (a flat base or an open rim: neck cut, bust base; on a
   closed mesh, flat caps all at one level, :func:`autobones.cut_cues.cap_score`; holes that do not
   cross the symmetry plane, or are short, are no cut: :func:`autobones.cut_cues.midline_cuts`), it and its
   neighbours are down -- unless the mesh is a face-only capture: an open shell faces away
   from its opening, which is then its back, and only the fronts along that way stay. The remaining
   choices are scored by how well the head's top slice overlays the same slice of a reference head
   (:mod:`autobones.reference_overlay`: a trimmed similarity ICP that may turn by at most 35
   degrees), and the angle between the best one and its neighbours is settled by a golden-section
   search. A head no human face matches that is cut at the neck stands on its cut instead
   (:func:`autobones.cut_cues.cut_up_front`).
   Throughout, a connected part beside the skin covering a tenth of the area or more (hair, a beard,
   as a shell or a volume; a hat set on it) is left out (:func:`autobones.geometry.topology.without_large_parts`).
3. With landmarks (``frame_from_landmarks``), the frame comes from them instead.

Unless ``up`` or ``front`` is forced, no step reads the file's axes (the sample's faces and
barycentric coordinates, the starts, candidates, thresholds and tie rules all come from the shape),
so a head turned by any rotation and scaled gets the same canonical head, to round-off
(``benchmarks/frames.py``: every landmarked shared head under 6 random rotations, x0.001 and x1000).

The canonical frame is the glTF/landmark-contract frame: +Y up, +Z out of the
face, +X toward the subject's own left ear, origin on the symmetry plane at the
sample's centroid, and coordinates divided by the head size (the largest
extent of the mesh in the canonical axes), so canonical heads measure about 1.
"""
from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial import cKDTree

from .cut_cues import bottom_cut, cut_cues as _cut_cues, cut_up_front, is_planar_cut, midline_cuts
from .errors import AutobonesError
from .frame_candidates import axis_candidates, cut_candidates, shape_candidates
from .geometry.mirror_plane import best_plane, mirror_error, onto_plane, reflect, refine_plane, shape_starts
from .geometry.sample import sample_surface
from .geometry.topology import distinct_faces, used_vertices, without_large_parts
from .reference_overlay import SAMPLE_COUNT, best_part_scores, default_reference, overlay_scores, refine_angle

__all__ = ["Frame", "anatomical_axes", "detect_frame", "frame_from_landmarks", "nearest_axis", "parse_axis",
           "reflect", "default_reference", "SAMPLE_COUNT"]

AXES = {
    "+x": (1.0, 0.0, 0.0), "-x": (-1.0, 0.0, 0.0),
    "+y": (0.0, 1.0, 0.0), "-y": (0.0, -1.0, 0.0),
    "+z": (0.0, 0.0, 1.0), "-z": (0.0, 0.0, -1.0),
}

# the reference head's overlay score (trimmed distances in RMS radii) above which a head is not taken
# for a human face: human heads and busts of the shared and zoo sets score 0.08-0.12 in their true
# frame, the zoo's animals and cartoons 0.13-0.46
HUMAN_LIKE = 0.13
# the same for a head taken for a face-only capture (scored against the reference's front part): the
# shared heads' front halves and quarters score 0.08-0.25, the zoo's wide-necked beast 0.30
FACE_UNLIKE = 0.28
# a face-only capture whose opening is a planar cut stays one only when the reference's face overlays it
# better than this share of the whole reference head stood on that cut does (the shared heads' front
# halves and quarters: 0.25-0.70 of it; the zoo's wide-necked armadillo and beast: 0.85-0.94)
FACE_VS_NECK = 0.75
# a front told from the back by a small margin is said (``Frame.front_check``), so that rig gets a look or a
# --front. By the reference's overlay: the best candidate's score against the best one facing the other way,
# relative; the shared and held-out humans and busts 0.026-0.22, the robot heads 0.001-0.059 (their mirror
# images taken from behind at 0.001 and 0.007), the falcon 0.013-0.019. By a neck cut: the share of the
# midline profile's reach that lies ahead of the cut (:func:`autobones.cut_cues.cut_up_front`); the zoo's
# animals 0.52-0.74, spot taken from behind at 0.58
CLOSE_OVERLAY = 0.02
CLOSE_CUT = 0.6


@dataclass(frozen=True)
class Frame:
    """A rigid map between a mesh's own frame and the canonical head frame.

    Attributes
    ----------
    rotation : (3, 3) float
        Rows are the canonical +X (subject's left), +Y (up) and +Z (front)
        directions expressed in the input frame; orthonormal, det +1.
    origin : (3,) float
        The canonical origin in input coordinates.
    size : float
        Head size in input units: canonical coordinates are input units / size.
    symmetry_error : float
        Mean distance, in head sizes, between the sample and its mirror image.
    cut : ((3,) float, (3,) float) or None
        A planar neck cut or bust base found by :func:`detect_frame`: its centre (canonical) and unit
        normal pointing out of the mesh (canonical); None when there is none (or not detected). Not
        written by :meth:`to_dict`: it is the detection's, kept so ``place`` need not look again.
    axes : (3, 3) float or None
        The head's anatomical axes (rows left, up, front, input frame) where they differ from
        ``rotation``'s: a transferred rig's, from its landmarks (:func:`anatomical_axes`), whose
        ``rotation`` takes up along menton -> vertex (the frame its generic rig's expression model,
        jaw glide and mouth parts are set in) and so leans with the face (23-73 degrees on the zoo's
        animals and bodies). None: the rotation's own (no landmark marks the back of the head).
        The head, neck and eyes turn about :attr:`turn_axes`, and the exported joints take their roll
        (their +X) from its left.
    front_check : dict or None
        How clearly :func:`detect_frame` told the front from the back: ``told_by`` ("reference head"
        or "neck cut"), ``margin`` (the reference's overlay: the best front's score against the best
        facing the other way, relative; the neck cut: the share of the profile's reach ahead of it)
        and ``close`` (under :data:`CLOSE_OVERLAY` / :data:`CLOSE_CUT`: check the rig, or give the
        front); ``against`` ``"down"`` when a face-only capture's up was told from its down instead (every
        candidate faced one way). None when the front was given, or nothing faced or stood the other way.
    """

    rotation: np.ndarray
    origin: np.ndarray
    size: float
    symmetry_error: float = float("nan")
    cut: tuple = None
    axes: np.ndarray = None
    front_check: dict = None

    @property
    def turn_axes(self):
        """(3, 3) rows left, up, front (input frame) the head turns about and the bones' roll is set
        from: :attr:`axes`, else :attr:`rotation`."""
        return self.rotation if self.axes is None else self.axes

    def to_canonical(self, P):
        """(k, 3) input-frame points -> (k, 3) canonical points (head sizes)."""
        return (np.asarray(P, dtype=np.float64) - self.origin) @ self.rotation.T / self.size

    def from_canonical(self, Q):
        """(k, 3) canonical points -> (k, 3) input-frame points (input units)."""
        return np.asarray(Q, dtype=np.float64) * self.size @ self.rotation + self.origin

    @property
    def up(self):
        """The input axis nearest to the head's up (:attr:`turn_axes`), e.g. ``'+z'``."""
        return nearest_axis(self.turn_axes[1])

    @property
    def front(self):
        """The input axis nearest to the direction the face looks (:attr:`turn_axes`), e.g. ``'-x'``."""
        return nearest_axis(self.turn_axes[2])

    @classmethod
    def from_dict(cls, d):
        """The frame :meth:`to_dict` wrote (a sidecar's ``frame``); ``symmetry_error`` null or absent
        (undefined, e.g. a transferred rig's) reads as NaN. KeyError / TypeError / ValueError on a
        malformed dict."""
        if not isinstance(d, dict):
            raise TypeError(f"a frame is an object, not {type(d).__name__}")
        sym = d.get("symmetry_error")
        axes = d.get("axes")
        check = d.get("front_check")
        return cls(np.asarray(d["rotation"], dtype=np.float64), np.asarray(d["origin"], dtype=np.float64),
                   float(d["head_size"]), float("nan") if sym is None else float(sym),
                   axes=None if axes is None else np.asarray(axes, dtype=np.float64),
                   front_check=None if check is None else dict(check))

    def to_dict(self):
        out = {
            "up": self.up, "front": self.front,
            "rotation": self.rotation.tolist(), "origin": self.origin.tolist(),
            "head_size": float(self.size), "symmetry_error": float(self.symmetry_error),
        }
        if self.axes is not None:
            out["axes"] = np.asarray(self.axes, dtype=np.float64).tolist()
        if self.front_check is not None:
            out["front_check"] = dict(self.front_check)
        return out


def nearest_axis(d):
    """The signed input axis closest to direction ``d`` (3,), e.g. ``'-x'``."""
    d = np.asarray(d, dtype=np.float64)
    i = int(np.argmax(np.abs(d)))
    return ("+" if d[i] > 0 else "-") + "xyz"[i]


def parse_axis(name, what="axis"):
    """``'+y'``, ``'y'``, ``'-Z'`` -> unit (3,) vector; AutobonesError otherwise."""
    key = str(name).strip().lower()
    key = key if key[:1] in "+-" else "+" + key
    if key not in AXES:
        raise AutobonesError(f"--{what} {name!r}: expected one of +x -x +y -y +z -z")
    return np.array(AXES[key])


def detect_frame(V, F, up=None, front=None, reference=None):
    """Find the canonical frame of a head mesh.

    Parameters
    ----------
    V : (n, 3) float
        Vertices in the mesh's own frame and units.
    F : (m, 3) int
        Triangles.
    up, front : str or None
        Force the up or front axis (``'+z'``, ``'-x'``...); the other is detected.
    reference : (k, 3) float or None
        Canonical sample of the reference head to score orientations against;
        default: the built-in default head.

    Returns
    -------
    Frame
    """
    # a triangle written twice (a double-sided export's back faces) weighs twice in the sample and makes
    # its edges non-manifold, so no rim reads as a cut: counted once (the SMPL woman with a third of her
    # triangles repeated stood 99 degrees off)
    F = distinct_faces(F)
    # the frame is found from the head without large parts beside it (hair, a beard: open shells or
    # closed volumes), which the bald reference overlays badly and whose rims read as cuts
    head = without_large_parts(V, F)
    P, _, _ = sample_surface(V, head, SAMPLE_COUNT, seed=0)
    center = P.mean(axis=0)
    rms = np.sqrt(((P - center) ** 2).sum(axis=1).mean())
    tree = cKDTree(P)
    up_v = None if up is None else parse_axis(up, "up")
    front_v = None if front is None else parse_axis(front, "front")

    if up_v is not None and front_v is not None:
        if abs(up_v @ front_v) > 0.5:
            raise AutobonesError(f"--up {up} and --front {front} must be different axes")
        normal, offset = np.cross(up_v, front_v), center @ np.cross(up_v, front_v)
        sym_err = mirror_error(P, tree, normal, offset) / rms
        candidates, cues = [(up_v, front_v)], None
    else:
        sym_err, normal, offset, cues = _symmetry_plane(V, head, P, tree, rms, up_v, front_v)
    if cues is None:
        cues = _cut_cues(V, head)  # only the frame's cut needs them when up is forced
    cues = midline_cuts(cues, normal, offset)  # holes in mirrored pairs are no cut
    if up_v is None or front_v is None:
        # free (nothing forced): no step reads the file's axes, so a turned or scaled copy of a head
        # gets this frame turned or scaled (to round-off); a forced axis is the user's, kept as given
        free = up_v is None and front_v is None
        candidates = shape_candidates(P, normal, cues) if free else axis_candidates(normal, up_v, front_v)

    ref = default_reference() if reference is None else np.asarray(reference, dtype=np.float64)
    up_d, front_d, check = _choose_up_front(P, normal, offset, candidates, cues, ref, up_v, front_v)
    return replace(_exact_frame(V, F, center, normal, offset, up_d, front_d, cues, sym_err), front_check=check)


def _choose_up_front(P, normal, offset, candidates, cues, ref, up_v, front_v):
    """The (up, front) unit pair (3,), (3,) of the head, input frame, among ``candidates`` (list of
    (up, front) pairs): the one whose top slice best overlays the reference head ``ref`` ((k, 3)
    canonical sample), after the cut cues ``cues`` have ruled out ups (or marked a face-only
    capture), the angle refined when nothing is forced; a non-human head cut at the neck stands on
    its cut. ``P`` (s, 3) the surface sample, ``normal`` (3,) and ``offset`` the symmetry plane.
    Also returns how clearly the front was told (:attr:`Frame.front_check`, or None)."""
    free = up_v is None and front_v is None
    planar = is_planar_cut(cues)
    face_only = False
    every, full_ref = candidates, ref
    if len(candidates) > 1 and up_v is None:
        candidates, ref, face_only = cut_candidates(P, normal, candidates, cues, ref)
    if len(candidates) <= 1:
        return (*candidates[0], None)
    if face_only:  # a face capture: each candidate against the better of its two front parts
        scores, ref = best_part_scores(P, candidates, ref)
    else:
        scores = overlay_scores(P, candidates, ref)
    if face_only and front_v is None and planar:
        # a head cut at a wide neck looks as open as a face cut behind the ears: a face-only
        # capture must overlay the reference's face far better than its whole head stood on
        # the cut, straight across it (the 12 ups start there; ups 30-60 degrees off it laid
        # Lee Perry-Smith's front half on its back)
        neck = [(u, f) for u, f in every if u @ -cues["loop_normal"] > 0.95]
        neck_scores = overlay_scores(P, neck, full_ref) if neck else []
        if neck and min(scores) > FACE_VS_NECK * min(neck_scores):
            candidates, scores, ref, face_only = neck, neck_scores, full_ref, False
    best = int(np.argmin(scores))
    up_d, front_d = candidates[best]
    check = None if front_v is not None else _overlay_check(scores, candidates, best)
    if free:
        # candidates 30 degrees apart round the plane: settle the angle between them
        up_d, front_d = refine_angle(P, normal, up_d, front_d, ref[best] if isinstance(ref, list) else ref)
    if free and planar and cues.get("far_loop") is None and min(scores) > (FACE_UNLIKE if face_only else HUMAN_LIKE):
        # no human face matches (an animal, a cartoon): the reference head cannot tell its
        # front from its back, the neck cut can. Not a head open at both ends (a scan missing its
        # crown: the face overlays worse, but which end is the neck only the overlay tells)
        up_d, front_d, share = cut_up_front(P, normal, offset, cues)
        check = {"told_by": "neck cut", "margin": round(float(share), 4), "close": bool(share < CLOSE_CUT)}
    return up_d, front_d, check


def close_front(frame):
    """One line saying that ``frame``'s front was told from its back by a small margin
    (:attr:`Frame.front_check`) and what to do should the head face the other way; None when it
    was clear (or given)."""
    check = frame.front_check
    if not check or not check["close"]:
        return None
    if check.get("against") == "down":
        # a face-only capture: its front is the way it faces, its up was the doubt (the menpo template
        # cropped under its chin stood upside down at 0.3 %)
        return (f"up {frame.up} is a close call against down (by the reference head: it overlays "
                f"{check['margin']:.1%} better than standing the other way up; under {CLOSE_OVERLAY:.0%} is close): "
                "look at the rig (autobones view); if the face stands upside down, give the file's axes: "
                "--up AXIS --front AXIS (up=, front= in Python)")
    if check["told_by"] == "neck cut":
        how = (f"by its neck cut: {check['margin']:.0%} of the head's reach lies ahead of it; under "
               f"{CLOSE_CUT:.0%} is close")
    else:
        how = (f"by the reference head: it overlays {check['margin']:.1%} better than facing the other way; "
               f"under {CLOSE_OVERLAY:.0%} is close")
    # no axis is offered: the other way is seldom one of the file's axes (spot's lies between -y and -z), and a
    # forced front is taken exactly, so --front -y stood spot 65 degrees off where --up +y --front -z is right
    return (f"front {frame.front} is a close call against its back ({how}): look at the rig (autobones view); "
            "if the face looks backwards, give the file's axes: --up AXIS --front AXIS (up=, front= in Python)")


def _overlay_check(scores, candidates, best):
    """:attr:`Frame.front_check` of the reference's choice: the ``best`` of ``candidates`` ((up, front)
    pairs) by overlay ``scores`` against the best candidate facing the other way; where all face one way
    (a face-only capture faces away from its opening), against the best one standing the other way up
    (``against`` ``"down"``); None if none does either."""
    up, front = candidates[best]
    away = [s for s, (_, f) in zip(scores, candidates) if f @ front < 0]
    down = [s for s, (u, _) in zip(scores, candidates) if u @ up < 0]
    if not away and not down:
        return None
    margin = (min(away or down) - scores[best]) / max(scores[best], 1e-300)
    check = {"told_by": "reference head", "margin": round(float(margin), 4), "close": bool(margin < CLOSE_OVERLAY)}
    return check if away else {**check, "against": "down"}


def _exact_frame(V, F, center, normal, offset, up_d, front_d, cues, sym_err):
    """The :class:`Frame` of vertices ``V`` (n, 3) (input frame and units; ``F`` (m, 3) for the
    vertices in use) from the symmetry plane (unit ``normal`` (3,), ``offset``), the chosen
    ``up_d`` and ``front_d`` (3,) and the sample's centroid ``center`` (3,); the neck cut of
    ``cues`` in canonical terms when it is planar, ``sym_err`` the mirror error in RMS radii."""
    # an exact frame from the refined symmetry normal and the chosen up, in an order that does
    # not depend on which input axis was which (so rotated inputs give the same frame)
    left = normal * np.sign(normal @ np.cross(up_d, front_d))
    up_d = up_d - (up_d @ left) * left
    up_d /= np.linalg.norm(up_d)
    cues = bottom_cut(cues, up_d)   # open at both ends: the neck's cut, not a missing crown
    R = np.vstack([left, up_d, np.cross(left, up_d)])
    origin = onto_plane(center, normal, offset)
    used = used_vertices(F, len(V))
    local = (V[used] - origin) @ R.T
    size = float((local.max(axis=0) - local.min(axis=0)).max())
    cut = ((cues["loop_centre"] - origin) @ R.T / size, cues["loop_normal"] @ R.T) if is_planar_cut(cues) else None
    return Frame(rotation=R, origin=origin, size=size, symmetry_error=float(sym_err), cut=cut)


def _symmetry_plane(V, F, P, tree, rms, up_v, front_v):
    """The symmetry plane of the sample ``P`` (input frame) as (mirror error in RMS radii, unit
    normal, offset), and the cut cues (None when up is given), computed beside the plane's ICPs.
    Nothing forced: started only from the sample's own directions (:func:`shape_starts`), so the
    plane turns with the head (the input axes, started from too until 2026-12-04, made a head
    authored on its axes and its turned copy end on planes up to 0.5 degrees apart); with up or
    front forced, from the input axes across it."""
    center = P.mean(axis=0)
    given = up_v if up_v is not None else front_v
    if given is None:
        starts_job = lambda: shape_starts(P, tree)
    else:
        starts_job = lambda: [np.array(a) for a in np.eye(3) if abs(a @ given) < 0.5]
    # independent ICPs whose time is in k-d tree queries and numpy, which release the GIL: on
    # threads, beside the cut cues (needed when up is not given), in about half the time
    with ThreadPoolExecutor(max_workers=min(4, os.cpu_count() or 1)) as pool:
        cues_job = pool.submit(_cut_cues, V, F) if up_v is None else None
        planes = list(pool.map(lambda n0: refine_plane(P, tree, n0, center @ n0, rms), starts_job()))
        cues = None if cues_job is None else cues_job.result()
    best = best_plane(P, tree, planes, rms)
    return best[0] / rms, best[1], best[2], cues


TOP = ("vertex", "glabella", "nasion")
BOTTOM = ("menton", "pogonion", "labiale_inferius", "stomion", "subnasale")
FRONT = ("pronasale", "nasion", "stomion", "subnasale", "glabella")


def anatomical_axes(V, F, landmarks, centroid_back=True):
    """(3, 3) rows left, up, front of the landmarks' anatomical frame, or None when they lack the
    pronasale, a top (vertex, else nasion) or a chin (menton, else pogonion), or these are degenerate,
    or (``centroid_back`` False) a back of the head.

    Front from the back of the head (opisthocranion, else the tragions' midpoint, else the centroid of
    the used vertices of ``V`` (n, 3) under ``F`` (m, 3)) to the pronasale; up from the chin to the top
    made orthogonal to that front (both lie in the midplane, so the front alone sets it and the chin
    and top only its sign); left completing the frame. Menton -> vertex itself leans with the face:
    26 degrees on an upright human, 36-73 on the zoo's animals (a long snout puts the chin far ahead
    of the vertex), and it moves with the jaw (ICT's open jaw: 24 degrees).
    """
    def pick(names):   # the first of ``names`` the landmarks have, or None
        return next((np.asarray(landmarks[n], dtype=np.float64) for n in names if n in landmarks), None)

    nose, top, bottom = pick(("pronasale",)), pick(("vertex", "nasion")), pick(("menton", "pogonion"))
    if nose is None or top is None or bottom is None:
        return None
    back = pick(("opisthocranion",))
    if back is None and "tragion_l" in landmarks and "tragion_r" in landmarks:
        back = 0.5 * (np.asarray(landmarks["tragion_l"], dtype=np.float64) + np.asarray(landmarks["tragion_r"]))
    if back is None and not centroid_back:
        return None
    if back is None:
        back = np.asarray(V, dtype=np.float64)[used_vertices(F, len(V))].mean(axis=0)
    front, up = nose - back, top - bottom
    if np.linalg.norm(front) == 0:
        return None
    front = front / np.linalg.norm(front)
    up = up - (up @ front) * front
    if np.linalg.norm(up) < 1e-6 * np.linalg.norm(top - bottom):
        return None
    up /= np.linalg.norm(up)
    return np.vstack([np.cross(up, front), up, front])


def frame_from_landmarks(V, F, landmarks):
    """The canonical frame from landmarks, when they tell it: up from a top midline landmark to a
    bottom one, front from the mesh's centroid to the nose (or another front midline landmark),
    left completing the frame; the symmetry plane through the midline landmarks and the midpoints
    of the bilateral pairs; and, where the landmarks mark the back of the head (the opisthocranion or
    both tragions), the head's anatomical axes (:func:`anatomical_axes`) as :attr:`Frame.axes`, which
    the head, neck and eyes turn about.

    Up along menton -> vertex leans with the face (23-73 degrees off the anatomical up on the zoo's
    animals and the SMPL bodies, whose files mark the back of the head): the rig's own computations
    run in it (the generic rig's expression model, jaw glide and mouth parts are set in it), but a
    head turned about it also rolled (its eyes 0.10-0.25 ex-ex out of level on a 15 degree turn), and
    an ARKit eyeLookIn / Out, a capture's HeadYaw and the viewer's sliders with it. Without a back,
    the mesh's centroid stands in badly where a neck or a bust hangs below the head (a held-out
    woman's head with a long neck and the 27 names the detector finds: 15 degrees off her upright
    model, menton -> nasion 4), so the axes are the rotation's own.

    Left is derived without the bilateral names, so a set with left and right swapped is
    caught by :func:`autobones.io.landmarks.validate_landmarks`. Returns None when the
    landmarks lack a top, a bottom or a front point (use :func:`detect_frame` then).

    Parameters
    ----------
    V : (n, 3) float
        Vertices, input frame.
    F : (m, 3) int
        Triangles.
    landmarks : dict of str -> (3,)
        Contract landmarks in the input frame.

    Returns
    -------
    Frame or None
    """
    used = used_vertices(F, len(V))
    centroid = V[used].mean(axis=0)
    R = _leaning_axes(V[used], landmarks, centroid)
    if R is None:
        return None
    left = R[0]
    # the symmetry plane passes through midline points and pair midpoints
    mids = [np.asarray(p, float) for n, p in landmarks.items() if not n.endswith(("_l", "_r"))]
    mids += [(np.asarray(landmarks[n], float) + np.asarray(landmarks[n[:-2] + "_r"], float)) / 2
             for n in landmarks if n.endswith("_l") and n[:-2] + "_r" in landmarks]
    x0 = float(np.median(np.array(mids) @ left))
    origin = centroid - (centroid @ left - x0) * left
    local = (V[used] - origin) @ R.T
    axes = anatomical_axes(V, F, landmarks, centroid_back=False)
    if axes is not None and axes[1] @ R[1] <= 0:
        axes = None   # landmarks that disagree on which way is up: the rotation's own
    return Frame(rotation=R, origin=origin, size=float(np.ptp(local, axis=0).max()), axes=axes)


def _leaning_axes(U, landmarks, centroid):
    """(3, 3) rows left, up, front of :func:`frame_from_landmarks`' rotation: up from a top midline
    landmark to a bottom one, front from the ``centroid`` (3,) of the used vertices ``U`` (k, 3) to
    the nose (or another front midline landmark) made orthogonal to it; None when they lack a top, a
    bottom or a front point, or these are degenerate."""
    pick = lambda names: next((np.asarray(landmarks[n], float) for n in names if n in landmarks), None)
    top, bottom, nose = pick(TOP), pick(BOTTOM), pick(FRONT)
    if top is None or bottom is None or nose is None:
        return None
    up = top - bottom
    front = nose - centroid
    if np.linalg.norm(up) == 0 or np.linalg.norm(front) == 0:
        return None
    up /= np.linalg.norm(up)
    front -= (front @ up) * up
    if np.linalg.norm(front) < 1e-6 * np.ptp(U, axis=0).max():
        return None
    front /= np.linalg.norm(front)
    return np.vstack([np.cross(up, front), up, front])
