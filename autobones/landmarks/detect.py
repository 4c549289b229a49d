"""Find the contract's landmarks on a human head automatically: render, detect in 2-D, lift to 3-D.

Goes beyond the seeds (004 asks for hand-placed landmarks). The method is the one
commercial scan tools use:

1. Orientation (:func:`autobones.orient.detect_frame`): the head is brought to the
   canonical frame (+Y up, +Z out of the face), so the pictures are upright.
2. Pictures (:mod:`autobones.render`): a whole-head front picture finds the face;
   then the face is rendered, filling the picture, from the front and from a few
   views around it (by default +-30 degrees of yaw and +-15 of pitch). Orthographic,
   Lambert-shaded with a head-on light, on the CPU.
3. 2-D landmarks: MediaPipe Face Mesh (468 points; its face detector and landmark
   models ship inside the ``mediapipe`` wheel, nothing is downloaded). The table
   :data:`MEDIAPIPE_POINTS` maps its points to the contract's names.
4. Lift and combine: each view's point is lifted to the surface it is drawn on;
   the views' 3-D points are combined by a weighted median (weights: how squarely
   the view sees the surface there). A name whose views disagree by more than
   ``max_disagreement`` is dropped rather than returned wrong; per-name confidence
   falls from 1 (views agree) to 0 (at the threshold).
5. Geometric refinement, where geometry is more precise than a picture: midline
   names are moved onto the symmetry plane, bilateral pairs are made mirror images
   of each other (a pair whose sides disagree by more than ``max_mirror_error`` is
   flagged; a side whose views disagreed is replaced by the mirror image of the other,
   flagged, at half its confidence), pronasale becomes the most anterior point of the nose tip region and
   menton the lowest point of the chin on the symmetry plane; everything is
   snapped to the surface.

Distances in this module are in units of the detected outer-eye-corner distance
(ex-ex, ~93 mm on an adult), the unit the benchmark reports.
"""
from __future__ import annotations

import contextlib
import os
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..errors import AutobonesError
from ..io.landmarks import NAMES, mirror_name
from ..orient import Frame, detect_frame, reflect
from ..render.rasterize import Camera, look_at, orthographic_camera, rasterize, shade, surface_points
from ..geometry.normals import vertex_normals

#: MediaPipe Face Mesh point indices -> contract name (the mean of the listed points).
#: Indices from MediaPipe's canonical face model (``mesh_map.jpg``); the subject's
#: right eye is 33 (outer) / 133 (inner), the left 263 / 362.
MEDIAPIPE_POINTS = {
    "nasion": (168,),
    "pronasale": (4,),
    "subnasale": (2,),
    "labiale_superius": (0,),
    "stomion": (13, 14),
    "labiale_inferius": (17,),
    "menton": (152,),
    "brow_outer_r": (70,), "brow_outer_l": (300,),
    "brow_middle_r": (105,), "brow_middle_l": (334,),
    "brow_inner_r": (107,), "brow_inner_l": (336,),
    "alare_r": (98,), "alare_l": (327,),
    "exocanthion_r": (33,), "exocanthion_l": (263,),
    "endocanthion_r": (133,), "endocanthion_l": (362,),
    "palpebrale_superius_r": (159,), "palpebrale_superius_l": (386,),
    "palpebrale_inferius_r": (145,), "palpebrale_inferius_l": (374,),
    "cheilion_r": (61,), "cheilion_l": (291,),
    "crista_philtri_r": (37,), "crista_philtri_l": (267,),
}

#: Default views: (yaw, pitch) in degrees; yaw turns the camera toward the subject's
#: left, pitch raises it.
DEFAULT_VIEWS = ((0.0, 0.0), (30.0, 0.0), (-30.0, 0.0), (0.0, 15.0), (0.0, -15.0))

#: Degrees between the face's eye-over-mouth line and the vertical in which the nose tip
#: is the most anterior and the menton the lowest midline point (measured on the published
#: ICT and menpo3d landmarks: 15 degrees on both sources).
PROFILE_TILT = 15.0

#: Field of view of the face pictures, in face widths (the face detector wants some
#: background around the face, which a face-only scan does not have).
FACE_FIELD = 1.5


#: Picture size for finding the face on the whole head (the face detector works at 128 px).
SEARCH_SIZE = 256

#: Key light in camera coordinates: above the camera, like a studio portrait. Measured
#: against a head-on light: brows 6.6 vs 7.8%, mean 3.8 vs 4.3% of ex-ex over five views.
KEY_LIGHT = (0.0, 0.6, 1.0)

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
# the 2-D detector


@contextlib.contextmanager
def _quiet_stderr():
    """Silence the C++ logging MediaPipe and TFLite print straight to file descriptor 2."""
    try:
        saved = os.dup(2)
    except OSError:
        yield
        return
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(null)


class MediaPipeFaceMesh:
    """MediaPipe Face Mesh as a function of an image: (H, W, 3) uint8 -> (468, 3) or None:
    pixel x (column), y (row), and depth in pixels (relative, growing away from the viewer).

    ``points`` maps the contract's names to its point indices (:data:`MEDIAPIPE_POINTS`).

    Parameters
    ----------
    min_confidence : float
        Face detection confidence below which no face is reported.
    """

    points = MEDIAPIPE_POINTS

    def __init__(self, min_confidence=0.5):
        self.min_confidence = min_confidence
        self._model = None

    def _load(self):
        os.environ.setdefault("GLOG_minloglevel", "2")
        os.environ.setdefault("TF_CPP_MIN_LOG_LEVEL", "2")
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                from mediapipe.python.solutions import face_mesh
        except ImportError as exc:
            raise AutobonesError(
                "automatic landmarks need the optional face detector: pip install 'autobones[landmarks]' "
                f"(MediaPipe; import failed: {exc})") from None
        with _quiet_stderr():  # also when used on its own
            self._model = face_mesh.FaceMesh(static_image_mode=True, max_num_faces=1,
                                             refine_landmarks=False,
                                             min_detection_confidence=self.min_confidence)

    def __call__(self, image):
        if self._model is None:
            self._load()
        with _quiet_stderr(), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = self._model.process(np.ascontiguousarray(image))
        if not result.multi_face_landmarks:
            return None
        H, W = image.shape[:2]
        lm = result.multi_face_landmarks[0].landmark
        # MediaPipe's coordinates are fractions of the image with 0 at the image edge;
        # pixel centres here are at integers
        # depth: MediaPipe's z, on the scale of x, growing away from the viewer
        return np.array([[p.x * W - 0.5, p.y * H - 0.5, p.z * W] for p in lm], dtype=np.float64)

    def close(self):
        if self._model is not None:
            self._model.close()
            self._model = None


# ---------------------------------------------------------------------------
# views and lifting


#: Midline names from top to bottom: a face's landmarks come in this order along its up.
TOP_DOWN = ("nasion", "pronasale", "subnasale", "labiale_superius", "stomion", "labiale_inferius", "menton")


def nose_forward(P, table):
    """Whether the nose tip is nearer the viewer (+z) than the outer eye corners, given the
    table's points lifted to the surface ((p, 3), picture frame). False for the inside of a
    face-only shell seen from behind, which a face detector takes for a face (the hollow-face
    illusion)."""
    if not all(n in table for n in ("pronasale", "exocanthion_l", "exocanthion_r")):
        return True
    tip = P[table["pronasale"][0], 2]
    eyes = P[[table["exocanthion_l"][0], table["exocanthion_r"][0]], 2]
    return bool(np.isfinite(tip) and np.all(np.isfinite(eyes)) and tip > eyes.mean())


def plausible(landmarks):
    """Whether detected landmarks look like a face in their frame: midline names in top-down
    order, eyes above the mouth, the nose tip in front of the eyes, every ``_l`` on the
    subject's left of its ``_r``. Guards against a face the detector imagines in a head
    pictured upside down or from behind."""
    Q = {n: landmarks.frame.to_canonical(np.asarray(p)[None])[0] for n, p in landmarks.items()}
    eyes = [Q[n][2] for n in ("exocanthion_l", "exocanthion_r") if n in Q]
    if "pronasale" in Q and eyes and Q["pronasale"][2] <= np.mean(eyes):
        return False
    ys = [Q[n][1] for n in TOP_DOWN if n in Q]
    if any(a < b for a, b in zip(ys, ys[1:])):
        return False
    for eye, mouth in (("exocanthion_l", "cheilion_l"), ("exocanthion_r", "cheilion_r")):
        if eye in Q and mouth in Q and Q[eye][1] <= Q[mouth][1]:
            return False
    return all(Q[n][0] > Q[mirror_name(n)][0] for n in Q if n.endswith("_l") and mirror_name(n) in Q)


def face_axes(points, table):
    """The subject's left and up as unit (3,) vectors in the picture's frame (x right, y up,
    z toward the viewer), from a detector's points with depth ((p, 3): pixels, depth in pixels
    growing away from the viewer); (None, None) without depth. Left: mean direction right ->
    left over the table's bilateral pairs; up: menton -> nasion."""
    if points.shape[1] < 3 or "menton" not in table or "nasion" not in table:
        return None, None
    P = points * np.array([1.0, -1.0, -1.0])
    u = [P[table[n][0]] - P[table[mirror_name(n)][0]] for n in table
         if n.endswith("_l") and mirror_name(n) in table]
    if not u:
        return None, None
    u = np.array(u)
    left = (u / np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-12)).mean(axis=0)
    up = P[table["nasion"][0]] - P[table["menton"][0]]
    if np.linalg.norm(left) == 0 or np.linalg.norm(up) == 0:
        return None, None
    return left / np.linalg.norm(left), up / np.linalg.norm(up)


def squared_frame(frame, landmarks):
    """``frame`` turned so that its left axis is the normal of the landmarks' own mirror plane
    (yaw and roll corrected, pitch kept)."""
    names = list(landmarks)
    Q = frame.to_canonical(np.array([landmarks[n] for n in names]))
    normal, _ = symmetry_plane(dict(zip(names, Q)))
    up = np.array([0.0, 1.0, 0.0]) - normal[1] * normal
    up /= np.linalg.norm(up)
    M = np.vstack([normal, up, np.cross(normal, up)])
    return Frame(rotation=M @ frame.rotation, origin=frame.origin, size=frame.size,
                 symmetry_error=frame.symmetry_error)


def turn_degrees(A, B):
    """Angle in degrees of the rotation taking the (3, 3) rotation ``B`` to ``A``."""
    return float(np.degrees(np.arccos(np.clip((np.trace(A @ B.T) - 1.0) / 2.0, -1.0, 1.0))))


def turns(search=True):
    """Candidate rotations of the canonical frame: None (keep it) first, then with ``search``
    the (3, 3) rotations that bring each axis direction to the front and another to the top
    (the identity among them)."""
    yield None
    if not search:
        return
    axes = [np.array(a, dtype=np.float64) for a in
            ((0, 0, 1), (0, 0, -1), (1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0))]
    for front in axes:
        for up in axes:
            if abs(front @ up) > 0.5:
                continue
            yield np.vstack([np.cross(up, front), up, front])


def skin_faces(V, F):
    """(m,) bool: the triangles of the skin, the connected part with the largest area (after
    welding coincident vertices), when it holds at least half the area; else every triangle.

    Scanned or modelled heads often carry eyeballs, eyelashes, teeth in separate parts; a
    landmark lifted from an oblique picture must land on the skin, not on an eyelash."""
    from ..geometry.topology import mesh_parts
    from ..geometry.topology import weld

    area = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    _, Fw, index = weld(V, F, 1e-9 * max(float(np.ptp(V, axis=0).max()), 1e-300))
    part = mesh_parts(int(index.max()) + 1, index[F])[index[F[:, 0]]]
    totals = np.bincount(part, weights=area)
    if totals.max() < 0.5 * totals.sum():
        return np.ones(len(F), dtype=bool)
    return part == int(np.argmax(totals))


def view_direction(yaw, pitch):
    """Unit (3,) canonical direction from the head toward a camera turned by ``yaw`` (toward
    the subject's left, +X) and ``pitch`` (upward) degrees from straight ahead (+Z)."""
    a, b = np.radians(yaw), np.radians(pitch)
    return np.array([np.sin(a) * np.cos(b), np.sin(b), np.cos(a) * np.cos(b)])


def face_camera(target, view_dir, width, size):
    """An orthographic camera looking at ``target`` (3,) along ``-view_dir``, ``width`` canonical
    units across the picture, ``size`` pixels square; world +Y shows upward."""
    view = look_at(np.asarray(target) + 4.0 * np.asarray(view_dir), target, (0.0, 1.0, 0.0))
    return Camera(view=view, scale=size / float(width), center=np.zeros(2), width=size, height=size)


def lift(points_map, px, reach=3):
    """Surface points under pixel positions.

    Parameters
    ----------
    points_map : (H, W, 3) float
        :func:`autobones.render.surface_points` (NaN where empty).
    px : (k, 2) float
        Pixel coordinates (x = column, y = row).
    reach : int
        An empty pixel takes the nearest covered pixel within this many pixels.

    Returns
    -------
    (k, 3) float64
        Bilinear interpolation of the four surrounding pixels' points where all four
        are covered; else the nearest covered pixel within ``reach``; else NaN.
    """
    H, W, _ = points_map.shape
    px = np.asarray(px, dtype=np.float64)
    out = np.full((len(px), 3), np.nan)
    x0 = np.floor(px[:, 0]).astype(np.int64)
    y0 = np.floor(px[:, 1]).astype(np.int64)
    inside = (x0 >= 0) & (y0 >= 0) & (x0 < W - 1) & (y0 < H - 1)
    i = np.flatnonzero(inside)
    fx = (px[i, 0] - x0[i])[:, None]
    fy = (px[i, 1] - y0[i])[:, None]
    c = [points_map[y0[i] + dy, x0[i] + dx] for dy, dx in ((0, 0), (0, 1), (1, 0), (1, 1))]
    bil = (c[0] * (1 - fx) * (1 - fy) + c[1] * fx * (1 - fy) + c[2] * (1 - fx) * fy + c[3] * fx * fy)
    ok = np.all(np.isfinite(bil), axis=1)
    out[i[ok]] = bil[ok]
    rest = np.flatnonzero(~np.all(np.isfinite(out), axis=1))
    if len(rest):
        covered = np.argwhere(np.isfinite(points_map[..., 0]))      # (c, 2) row, col
        if len(covered):
            d, j = cKDTree(covered[:, ::-1].astype(np.float64)).query(px[rest])
            near = d <= reach
            rc = covered[j[near]]
            out[rest[near]] = points_map[rc[:, 0], rc[:, 1]]
    return out


def weighted_median(X, w):
    """Per-coordinate weighted median of candidate points.

    Parameters
    ----------
    X : (v, k, 3) float
        ``v`` candidates for each of ``k`` points; NaN rows are ignored.
    w : (v, k) float
        Non-negative weights (0 ignores a candidate).

    Returns
    -------
    (k, 3) float64
        NaN where a point has no candidate with positive weight.
    """
    w = np.where(np.all(np.isfinite(X), axis=2), w, 0.0)
    out = np.full(X.shape[1:], np.nan)
    for d in range(3):
        x = np.where(w > 0, X[..., d], np.inf)
        order = np.argsort(x, axis=0)
        xs = np.take_along_axis(x, order, axis=0)
        ws = np.take_along_axis(w, order, axis=0)
        cw = np.cumsum(ws, axis=0)
        total = cw[-1]
        idx = np.argmax(cw >= 0.5 * total[None], axis=0)
        val = np.take_along_axis(xs, idx[None], axis=0)[0]
        out[:, d] = np.where(total > 0, val, np.nan)
    return out


# ---------------------------------------------------------------------------
# the detector


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
    size: int = 512
    max_disagreement: float = 0.08
    max_mirror_error: float = 0.06
    refine: bool = True
    search: bool = True
    max_turn: float = 10.0
    detector: object = None

    def detect(self, V, F, frame=None, what="the head"):
        """Landmarks of the mesh ``(V, F)``; ``frame`` from :func:`autobones.orient.detect_frame`
        (found when None). Returns :class:`DetectedLandmarks`; raises AutobonesError when no face
        is found."""
        V = np.asarray(V, dtype=np.float64)
        F = np.asarray(F, dtype=np.int64)
        frame = detect_frame(V, F) if frame is None else frame
        detector = self.detector if self.detector is not None else MediaPipeFaceMesh()
        # MediaPipe's graph threads log to file descriptor 2 while they work
        quiet = _quiet_stderr() if isinstance(detector, MediaPipeFaceMesh) else contextlib.nullcontext()
        with quiet:
            skin = skin_faces(V, F)             # the same in every frame the loop below tries
            found = self._detect(V, F, skin, frame, detector, what, search=self.search)
            # a face turned away from the frame's front (a head turned in its file, a face-only
            # scan): look again, square to the face the landmarks describe
            for _ in range(3):          # a face first found from far off its front converges
                again = squared_frame(found.frame, found)
                if turn_degrees(again.rotation, found.frame.rotation) <= self.max_turn:
                    break
                try:
                    found = self._detect(V, F, skin, again, detector, what, search=False)
                except NoFaceError:
                    break               # keep what the first pictures gave
        if not plausible(found):
            raise NoFaceError(NO_FACE.format(what=what))
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
            P0 = lift(surface_points(Vt, F, buf), found[:, :2])
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
                found2, P2 = look(Vc @ (Q @ M).T, self.size, 0.05 if first else margin)
                if P2 is not None and nose_forward(P2, table):
                    M, P0 = Q @ M, P2
            return M, P0
        raise NoFaceError(NO_FACE.format(what=what))

    def _detect(self, V, F, skin, frame, detector, what, search):
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
        for yaw, pitch in self.views:
            d = view_direction(yaw, pitch)
            cam = face_camera(target, d, width, self.size)
            buf = rasterize(Vc, F, cam)
            light = cam.view[:3, :3].T @ (np.array(KEY_LIGHT) / np.linalg.norm(KEY_LIGHT))
            px = detector(shade(Vc, F, buf, light_dir=light, ambient=0.15))
            px = None if px is None else px[:, :2]
            view_info.append({"yaw": float(yaw), "pitch": float(pitch), "face": px is not None})
            if px is None:
                continue
            P = lift(surface_points(Vc, F, buf), px)
            if not cands:
                # outward normals whichever way the file winds its triangles: the face seen
                # from the first view faces that view (a centroid test fails on a face-only shell)
                shown = F[buf.face_id[buf.mask]]
                N *= 1.0 if (N[shown].sum(axis=(0, 1)) @ d) >= 0 else -1.0
            # how squarely the view sees the surface where each point lands: grazing views lift
            # badly, and a point that lands on a surface facing away (the far side of an
            # eyeball, an eyelash) is no sight of the skin at all
            _, near = tree.query(np.nan_to_num(P))
            facing = np.clip(N[near] @ d, 0.0, 1.0)
            cands.append(P)
            weights.append(np.where(np.all(np.isfinite(P), axis=1), facing ** 2, 0.0))
        if not cands:
            raise NoFaceError(NO_FACE.format(what=what))
        X, w = np.array(cands), np.array(weights)
        table = getattr(detector, "points", MEDIAPIPE_POINTS)
        names = [n for n in table]
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
        return self._finish(V, Fs, Vc, frame, names, comb, spread, unit_c, view_info)

    def _finish(self, V, F, Vc, frame, names, comb, spread, unit_c, view_info):
        """Drop, refine and snap onto the triangles ``F`` (the skin)."""
        from ..geometry.closest import closest_points

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
        P = np.array([points[n] for n in points])
        P = closest_points(P, Vc, F)[0]
        Pin = frame.from_canonical(P)
        ordered = {n: Pin[i] for i, n in enumerate(points)}
        ordered = {n: ordered[n] for n in NAMES if n in ordered}
        return DetectedLandmarks(ordered, confidence, dropped, flagged, view_info, frame,
                                 unit=unit_c * frame.size)


def symmetry_plane(points):
    """The face's own mirror plane from landmarks: normal from the bilateral pairs' directions
    (right -> left), offset the median of the midline points and pair midpoints.

    Parameters
    ----------
    points : dict of str -> (3,)

    Returns
    -------
    normal : (3,) float64
        Unit normal pointing toward the subject's left.
    offset : float
        ``normal . p = offset`` on the plane.
    """
    pairs = [(np.asarray(points[n]), np.asarray(points[mirror_name(n)]))
             for n in points if n.endswith("_l") and mirror_name(n) in points]
    if not pairs:
        return np.array([1.0, 0.0, 0.0]), 0.0
    u = np.array([(a - b) / max(np.linalg.norm(a - b), 1e-12) for a, b in pairs])
    normal = np.median(u, axis=0)
    normal /= np.linalg.norm(normal)
    on = [np.asarray(p) for n, p in points.items() if not n.endswith(("_l", "_r"))]
    on += [(a + b) / 2.0 for a, b in pairs]
    return normal, float(np.median(np.array(on) @ normal))


def midline_profile(V, F, normal, offset):
    """(k, 3) points where the surface crosses the plane ``normal . p = offset`` (segment ends)."""
    import trimesh

    mesh = trimesh.Trimesh(V, F, process=False)
    seg = trimesh.intersections.mesh_plane(mesh, normal, normal * offset)
    return np.asarray(seg, dtype=np.float64).reshape(-1, 3)


def refine(Vc, F, points, unit, max_mirror_error):
    """Geometric refinement of canonical landmarks (see the module docstring).

    Parameters
    ----------
    Vc : (n, 3) float
        Canonical vertices (+Y up, +Z front).
    F : (m, 3) int
    points : dict of str -> (3,)
        Canonical landmarks.
    unit : float
        ex-ex distance, canonical units.
    max_mirror_error : float
        Flag threshold, ex-ex units.

    Returns
    -------
    points : dict of str -> (3,)
        Refined (not yet snapped to the surface).
    flagged : dict of str -> str
    """
    out = {n: np.array(p, dtype=np.float64) for n, p in points.items()}
    flagged = {}
    n_, c = symmetry_plane(out)
    for n in list(out):
        if n.endswith("_l") and mirror_name(n) in out:
            m = mirror_name(n)
            a, b = out[n], reflect(out[m], n_, c)
            err = float(np.linalg.norm(a - b)) / unit
            if err > max_mirror_error:
                flagged[n] = flagged[m] = (f"left and right are not mirror images "
                                           f"({100 * err:.1f}% of the eye-corner distance apart)")
            mid = (a + b) / 2.0
            out[n], out[m] = mid, reflect(mid, n_, c)
        elif not n.endswith(("_l", "_r")):
            out[n] = out[n] - (out[n] @ n_ - c) * n_
    for n in list(out):
        if n.endswith(("_l", "_r")) and mirror_name(n) not in out:
            # its own views disagreed: the mirror image of the other side stands in
            out[mirror_name(n)] = reflect(out[n], n_, c)
            flagged[mirror_name(n)] = f"mirrored from {n}"
    # the face's own vertical: eye corners over the mouth, in the mirror plane
    eyes = [out[k] for k in ("exocanthion_l", "exocanthion_r", "endocanthion_l", "endocanthion_r") if k in out]
    mouth = [out[k] for k in ("stomion", "labiale_superius", "labiale_inferius") if k in out]
    if not eyes or not mouth:
        return out, flagged
    up = np.mean(eyes, axis=0) - np.mean(mouth, axis=0)
    up -= (up @ n_) * n_
    up /= np.linalg.norm(up)
    front = np.cross(n_, up)
    profile = midline_profile(Vc, F, n_, c)
    tilt = np.radians(PROFILE_TILT)
    for name, direction, reach in (
            # the eye-mouth line leans back from the Frankfort vertical, so straight ahead
            # and straight down in the face's frame are turned by PROFILE_TILT
            ("pronasale", np.cos(tilt) * front - np.sin(tilt) * up, 0.15),
            ("menton", -np.cos(tilt) * up + np.sin(tilt) * front, 0.25)):
        if name in out and len(profile):
            near = profile[np.linalg.norm(profile - out[name], axis=1) < reach * unit]
            if len(near):
                out[name] = near[np.argmax(near @ direction)]
    return out, flagged


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
    """
    from ..placement.pipeline import resolve_mesh

    V, F, source = resolve_mesh(mesh)
    frame = detect_frame(V, F, up=up, front=front)
    return LandmarkDetector(**options).detect(V, F, frame=frame, what=name or source or "the head")
