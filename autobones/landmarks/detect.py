"""Find the contract's landmarks on a human head automatically: render, detect in 2-D, lift to 3-D.

Orvalho, Zacur & Susin 2008 take the landmarks as placed by hand; this goes beyond them
with the method commercial scan tools use:

1. Orientation (:func:`autobones.orient.detect_frame`): the head is brought to the
   canonical frame (+Y up, +Z out of the face), so the pictures are upright; when its
   front shows no face, the other axis directions are tried
   (:mod:`autobones.landmarks.orientation`).
2. Pictures (:mod:`autobones.render`): a whole-head front picture finds the face;
   then the face is rendered, filling the picture, from the front and from a few
   views around it (by default +-30 degrees of yaw and +-15 of pitch). Orthographic,
   Lambert-shaded with a key light, on the CPU (:mod:`autobones.landmarks.views`).
3. 2-D landmarks: MediaPipe Face Mesh (:mod:`autobones.landmarks.mediapipe`), whose
   table :data:`~autobones.landmarks.mediapipe.MEDIAPIPE_POINTS` maps its points to the
   contract's names.
4. Lift and combine: each view's point is lifted to the surface it is drawn on;
   the views' 3-D points are combined by a weighted median (weights: how squarely
   the view sees the surface there). A name whose views disagree by more than
   ``max_disagreement`` is dropped rather than returned wrong; per-name confidence
   falls from 1 (views agree) to 0 (at the threshold).
5. Geometric refinement (:mod:`autobones.landmarks.refine`), where geometry is more
   precise than a picture: midline names onto the symmetry plane, bilateral pairs made
   mirror images of each other (a pair whose sides disagree by more than
   ``max_mirror_error`` is flagged; a side whose views disagreed is replaced by the
   mirror image of the other, flagged, at half its confidence), pronasale and menton
   placed on the midline profile; everything is snapped to the surface.

Distances in this module are in units of the detected outer-eye-corner distance
(ex-ex, ~93 mm on an adult), the unit the benchmark reports.
"""
from __future__ import annotations

import contextlib
import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import partial

import numpy as np
from scipy.spatial import cKDTree

from ..errors import AutobonesError
from ..geometry.closest import closest_points
from ..geometry.normals import vertex_normals
from ..geometry.topology import submesh, used_vertices
from ..geometry.winding import outward_faces
from ..io.landmark_names import NAMES, mirror_name
from ..io.mesh import resolve_mesh
from ..orient import Frame, detect_frame
from ..render.camera import orthographic_camera
from ..render.raster import rasterize, shade, surface_points
from .mediapipe import MEDIAPIPE_POINTS, MediaPipeFaceMesh, quiet_stderr
from .orientation import face_axes, nose_forward, plausible, squared_frame, turn_degrees, turns
from .refine import refine
from .views import face_camera, lift, pictured_mesh, view_direction, weighted_median

#: Default views: (yaw, pitch) in degrees; yaw turns the camera toward the subject's
#: left, pitch raises it.
DEFAULT_VIEWS = ((0.0, 0.0), (30.0, 0.0), (-30.0, 0.0), (0.0, 15.0), (0.0, -15.0))

#: Field of view of the face pictures, in face widths (the face detector wants some
#: background around the face, which a face-only scan does not have).
FACE_FIELD = 1.5

#: Picture size for finding the face on the whole head (the face detector works at 128 px).
SEARCH_SIZE = 256

#: Key light in camera coordinates: above the camera, like a studio portrait; it finds the
#: brows better than a head-on light in the landmark benchmark (benchmarks/landmarks.py).
KEY_LIGHT = (0.0, 0.6, 1.0)

# the least a reading of a face must give: this share of the detector's names, at this mean confidence
# (legitimate heads in benchmarks/landmarks.py: every name, mean confidence 0.44-0.79)
MIN_FOUND = 2.0 / 3.0
MIN_CONFIDENCE = 0.3
NO_FACE = ("no face found in the renders of {what}: automatic landmarks work on human and "
           "human-like faces; give its landmarks in a file instead (the contract's JSON, a MeshLab "
           ".pp or an iBUG-68 list: transfer --landmarks FILE, landmarks --from FILE)")


class NoFaceError(AutobonesError):
    """The pictures show no face the detector knows (an animal, a robot, the back of a head)."""


class DetectedLandmarks(dict):
    """Contract name -> (3,) position in the mesh's own frame and units.

    Attributes
    ----------
    confidence : dict of str -> float
        In [0, 1]: 1 when every view put the point at the same place, 0 at the
        disagreement threshold.
    dropped : dict of str -> str
        Names the detector maps but did not return, with the reason.
    flagged : dict of str -> str
        Names returned with a warning (e.g. a bilateral pair whose sides are not
        mirror images of each other).
    views : list of dict
        Per view: yaw, pitch (degrees) and whether a face was found.
    frame : autobones.orient.Frame
        The canonical frame the head was rendered in.
    unit : float
        The detected outer-eye-corner distance, mesh units.
    """

    def __init__(self, points, confidence, dropped, flagged, views, frame, unit):
        super().__init__(points)
        self.confidence = confidence
        self.dropped = dropped
        self.flagged = flagged
        self.views = views
        self.frame = frame
        self.unit = unit


# ---------------------------------------------------------------------------
# the detector


def _used_only(V, F):
    """``(V, F)`` without the vertices no triangle uses, ``F`` renumbered: a leftover vertex far away is not
    pictured, and framed into the pictures it shrank the face to a few pixels ("no face found")."""
    used = used_vertices(F, len(V))
    return (V, F) if len(used) == len(V) or not len(F) else submesh(V, F, used)


@dataclass
class LandmarkDetector:
    """Automatic contract landmarks for human heads.

    Parameters
    ----------
    views : sequence of (yaw, pitch) degrees
        Views of the face to detect in and combine; the first should be (0, 0).
    size : int
        Picture size in pixels (square).
    max_disagreement : float
        A name is dropped when its views' points lie further than this from their
        combined point (median over views), in ex-ex units.
    max_mirror_error : float
        A bilateral pair whose mirrored sides are further apart than this, ex-ex units,
        is flagged.
    refine : bool
        Apply the geometric refinement (symmetry, pronasale, menton).
    search : bool
        When the detected frame's front shows no face, look from the other axis
        directions (and with other ups) before giving up; the face found sets the frame.
    max_turn : float
        Degrees: when the mirror plane of the first landmarks is turned further than this
        from the frame the pictures were taken in (a head turned in its file, a face-only
        scan), the face is pictured and detected again square to it.
    detector : callable or None
        Image -> (p, 2) pixels (or (p, 3) with relative depth, which lets a turned face be
        squared before the pictures) or None, with a ``points`` attribute mapping contract
        names to its point indices; None is :class:`MediaPipeFaceMesh`.
    """

    views: tuple = DEFAULT_VIEWS
    # 384: MediaPipe's face mesh reads a 192-pixel crop, and the lift gains nothing from more
    # (benchmarks/landmarks.py on 6 heads: 512 px 3.60% ex-ex, 384 3.44%, 320 3.60%; 384 px
    # draws 1.8x fewer pixels than 512)
    size: int = 384
    max_disagreement: float = 0.08
    max_mirror_error: float = 0.06
    refine: bool = True
    search: bool = True
    max_turn: float = 10.0
    detector: object = None

    def detect(self, V, F, frame=None, what="the head", up=None, front=None):
        """Landmarks of the mesh ``(V, F)``; ``frame`` from :func:`autobones.orient.detect_frame`
        (found when None, with ``up`` and ``front`` as given). Returns :class:`DetectedLandmarks`;
        raises AutobonesError when no face is found."""
        V, F = _used_only(np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64))
        F = outward_faces(V, F)[0]   # the pictures are shaded by the normals: an inside-out head reads dark
        # the frame from the whole mesh (a clustered copy's rim and flat cut read differently), found
        # on a second thread while the pictured copy is made: both are mostly numpy outside the GIL;
        # the skin is the same in every frame the loop below tries
        with ThreadPoolExecutor(max_workers=1) as pool:
            pending = pool.submit(detect_frame, V, F, up, front) if frame is None else None
            Vp, Fp, skin_in, skin = pictured_mesh(V, F)
            frame = frame if pending is None else pending.result()
        # the landmarks end on the input's own skin (None: the pictured mesh is the input)
        snap = None if Vp is V else (V, F if skin_in.all() else F[skin_in])
        V, F = Vp, Fp
        detector = self.detector if self.detector is not None else MediaPipeFaceMesh()
        # MediaPipe's graph threads log to file descriptor 2 while they work
        quiet = quiet_stderr() if isinstance(detector, MediaPipeFaceMesh) else contextlib.nullcontext()
        with quiet:
            found = self._detect(V, F, skin, frame, detector, what, search=self.search, snap=snap)
            # a face turned away from the frame's front (a head turned in its file, a face-only
            # scan): look again, square to the face the landmarks describe
            for _ in range(3):          # a face first found from far off its front converges
                again = squared_frame(found.frame, found)
                if turn_degrees(again.rotation, found.frame.rotation) <= self.max_turn:
                    break
                try:
                    found = self._detect(V, F, skin, again, detector, what, search=False, snap=snap)
                except NoFaceError:
                    break               # keep what the first pictures gave
        if not plausible(found):
            raise NoFaceError(NO_FACE.format(what=what))
        # a face read from a picture upside down or half off the surface keeps a few names the
        # views happen to agree on: that is no reading of the face, and a transfer from it would
        # be wrong without a word
        names = getattr(detector, "points", MEDIAPIPE_POINTS)
        mean = float(np.mean(list(found.confidence.values()))) if found.confidence else 0.0
        if len(found) < MIN_FOUND * len(names) or mean < MIN_CONFIDENCE:
            raise NoFaceError(_unreliable(what, len(found), len(names), mean))
        return found

    def _find_face(self, Vc, F, detector, what, search):
        """Find the face on whole-head pictures: from the front of the canonical frame, else (a
        face-only scan, a frame guessed wrong) from the other axis directions. When the detector
        reports depth (MediaPipe does) and the face is turned from the picture, the frame is
        turned to face it (yaw and roll) and pictured again.

        Returns (M, P0): the (3, 3) rotation to apply to the canonical frame, and the face's
        points lifted to the surface in the turned frame ((p, 3), NaN where off the surface).
        """
        table = getattr(detector, "points", MEDIAPIPE_POINTS)

        def look(Vt, size, margin):
            cam = orthographic_camera(Vt, (0.0, 0.0, 1.0), (0.0, 1.0, 0.0), size=(size, size), margin=margin)
            buf = rasterize(Vt, F, cam)          # camera axes = the frame's axes
            found = detector(shade(Vt, F, buf, light_dir=(0.0, 0.0, 1.0), ambient=0.15))
            if found is None:
                return None, None
            P0 = lift(partial(surface_points, Vt, F, buf), buf.mask, found[:, :2])
            return found, (P0 if np.isfinite(P0[:, 0]).sum() >= 0.5 * len(P0) else None)

        for M in turns(search):
            first = M is None
            M = np.eye(3) if first else M
            # the search is coarser, with a wide margin: the face detector wants some
            # background around a face-only scan
            size, margin = (self.size, 0.05) if first else (SEARCH_SIZE, 0.25)
            found, P0 = look(Vc @ M.T, size, margin)
            if P0 is None or not nose_forward(P0, table):
                continue
            left, face_up = face_axes(found, table)
            if left is not None and np.degrees(np.arccos(np.clip(left[0], -1, 1))) > self.max_turn:
                # keep the picture's up (and so the frame's pitch) unless the face is upside
                # down or on its side in the picture
                up = np.array([0.0, 1.0, 0.0]) if face_up[1] > 0.5 else face_up
                up = up - (up @ left) * left
                up /= np.linalg.norm(up)
                Q = np.vstack([left, up, np.cross(left, up)])
                _, P2 = look(Vc @ (Q @ M).T, self.size, 0.05 if first else margin)
                if P2 is not None and nose_forward(P2, table):
                    M, P0 = Q @ M, P2
            return M, P0
        raise NoFaceError(NO_FACE.format(what=what))

    def _detect(self, V, F, skin, frame, detector, what, search, snap):
        Vc = frame.to_canonical(V)

        # 1. find the face on a whole-head picture and turn the frame to face it
        M, P0 = self._find_face(Vc, F, detector, what, search)
        if not np.array_equal(M, np.eye(3)):
            frame = Frame(rotation=M @ frame.rotation, origin=frame.origin, size=frame.size,
                          symmetry_error=frame.symmetry_error)
            Vc = Vc @ M.T
        ok = np.all(np.isfinite(P0), axis=1)
        lo, hi = np.percentile(P0[ok], 0, axis=0), np.percentile(P0[ok], 100, axis=0)
        target = (lo + hi) / 2.0
        width = FACE_FIELD * float(max(hi[0] - lo[0], hi[1] - lo[1]))

        # 2. every view: picture, 2-D points, lift
        cands, weights, view_info = [], [], []
        Fs = F if skin.all() else F[skin]
        N = vertex_normals(Vc, F)
        tree = cKDTree(Vc)
        def picture(view):
            d = view_direction(*view)
            cam = face_camera(target, d, width, self.size)
            buf = rasterize(Vc, F, cam)
            light = cam.view[:3, :3].T @ (np.array(KEY_LIGHT) / np.linalg.norm(KEY_LIGHT))
            return d, buf, shade(Vc, F, buf, light_dir=light, ambient=0.15)

        # the pictures are independent numpy work: drawn two at a time; the detector reads them in order
        with ThreadPoolExecutor(max_workers=min(len(self.views), os.cpu_count() or 1)) as pool:
            pictures = list(pool.map(picture, self.views))
        for (yaw, pitch), (d, buf, image) in zip(self.views, pictures):
            px = detector(image)
            px = None if px is None else px[:, :2]
            view_info.append({"yaw": float(yaw), "pitch": float(pitch), "face": px is not None})
            if px is None:
                continue
            P = lift(partial(surface_points, Vc, F, buf), buf.mask, px)
            if not cands:
                # outward normals whichever way the file winds its triangles: the face seen
                # from the first view faces that view (a centroid test fails on a face-only shell)
                shown = F[buf.face_id[buf.mask]]
                N *= 1.0 if (N[shown].sum(axis=(0, 1)) @ d) >= 0 else -1.0
            # how squarely the view sees the surface where each point lands: grazing views lift
            # badly, and a point that lands on a surface facing away (the far side of an
            # eyeball, an eyelash) is no sight of the skin at all
            _, near = tree.query(np.nan_to_num(P), workers=-1)
            facing = np.clip(N[near] @ d, 0.0, 1.0)
            cands.append(P)
            weights.append(np.where(np.all(np.isfinite(P), axis=1), facing ** 2, 0.0))
        if not cands:
            raise NoFaceError(NO_FACE.format(what=what))
        X, w = np.array(cands), np.array(weights)
        table = getattr(detector, "points", MEDIAPIPE_POINTS)
        names = list(table)
        Xn = np.stack([X[:, list(table[n])].mean(axis=1) for n in names], axis=1)
        wn = np.stack([w[:, list(table[n])].min(axis=1) for n in names], axis=1)
        # a name every view saw only grazing or on a surface facing away (an eye corner whose
        # nearest vertex is on the eyeball) still has its points: count them all alike
        unseen = ~(wn > 0).any(axis=0)
        wn[:, unseen] = np.all(np.isfinite(Xn[:, unseen]), axis=2).astype(np.float64)
        comb = weighted_median(Xn, wn)
        # the unit: ex-ex of the combined points
        iex = names.index("exocanthion_l"), names.index("exocanthion_r")
        unit_c = float(np.linalg.norm(comb[iex[0]] - comb[iex[1]]))
        if not np.isfinite(unit_c) or unit_c <= 0:
            raise NoFaceError(NO_FACE.format(what=what))
        dev = np.linalg.norm(Xn - comb[None], axis=2) / unit_c          # (v, k)
        dev = np.where(wn > 0, dev, np.nan)
        spread = np.nanmedian(dev, axis=0) if len(cands) > 1 else np.zeros(len(names))
        return self._finish(Fs, Vc, frame, names, comb, spread, unit_c, view_info, snap, what)

    def _finish(self, F, Vc, frame, names, comb, spread, unit_c, view_info, snap, what):
        """Drop, refine on the triangles ``F`` (the pictured skin), and snap onto it, or onto
        ``snap`` (the input's vertices and skin triangles) when the pictures were of a coarser copy."""
        points = {n: comb[i] for i, n in enumerate(names) if np.all(np.isfinite(comb[i]))}
        dropped, flagged, confidence = {}, {}, {}
        for i, n in enumerate(names):
            if n not in points:
                dropped[n] = "no view saw it on the surface"
            elif spread[i] > self.max_disagreement:
                dropped[n] = f"views disagree by {100 * spread[i]:.1f}% of the eye-corner distance"
                del points[n]
            else:
                confidence[n] = float(np.clip(1.0 - spread[i] / self.max_disagreement, 0.0, 1.0))
        if self.refine:
            points, flagged = refine(Vc, F, points, unit_c, self.max_mirror_error)
            for n in points:
                if n in dropped:            # stood in for by its mirrored partner
                    del dropped[n]
                    confidence[n] = 0.5 * confidence[mirror_name(n)]
        if not points:  # every name dropped: nothing to snap, no face read
            raise NoFaceError(_unreliable(what, 0, len(names), 0.0))
        P = np.array([points[n] for n in points]).reshape(-1, 3)
        if snap is None:
            Pin = frame.from_canonical(closest_points(P, Vc, F)[0])
        else:
            Pin = closest_points(frame.from_canonical(P), *snap)[0]
        ordered = {n: Pin[i] for i, n in enumerate(points)}
        ordered = {n: ordered[n] for n in NAMES if n in ordered}
        return DetectedLandmarks(ordered, confidence, dropped, flagged, view_info, frame,
                                 unit=unit_c * frame.size)


def _unreliable(what, found, names, mean):
    """The one-line refusal of a reading with too few names or too little confidence."""
    return (f"no face read reliably in the renders of {what}: only {found} of {names} landmarks found, mean "
            f"confidence {mean:.2f} (at least {int(np.ceil(MIN_FOUND * names))} and {MIN_CONFIDENCE:g} needed); "
            f"if the head's up or front was guessed wrong give --up/--front, else give its landmarks in a file "
            f"(transfer --landmarks FILE, landmarks --from FILE)")


def detect_landmarks(mesh, up=None, front=None, name=None, **options):
    """The contract's landmarks on a human head, found automatically.

    Parameters
    ----------
    mesh : path, (V, F) pair, or None
        The head (None: the built-in default head); any frame and unit.
    up, front : str or None
        Input axes (``'+z'``, ``'-x'``...) when the orientation finder should not guess.
    name : str or None
        What to call the head in messages (default: its file name).
    **options
        :class:`LandmarkDetector` parameters (``views``, ``size``, ``max_disagreement``...).

    Returns
    -------
    DetectedLandmarks
        ``{name: (3,) array}`` in the mesh's own frame and units, with ``.confidence``,
        ``.dropped`` and ``.flagged``.

    Raises
    ------
    AutobonesError
        No face in the pictures (animals, most cartoons, a back-of-head scan), or the
        optional detector is not installed.

    Examples
    --------
    Needs the optional detector (``pip install 'autobones[landmarks]'``):

    >>> import autobones
    >>> from autobones import samples
    >>> lm = autobones.detect_landmarks(samples.path("bust.obj"))
    >>> len(lm) >= 20, "pronasale" in lm, lm["pronasale"].shape
    (True, True, (3,))
    >>> all(0 <= c <= 1 for c in lm.confidence.values())
    True
    """
    V, F, source = resolve_mesh(mesh)
    return LandmarkDetector(**options).detect(V, F, what=name or source or "the head", up=up, front=front)
