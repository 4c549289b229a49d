"""MediaPipe Face Mesh as a 2-D landmark detector: an image in, 468 pixel positions out.

The face detector and landmark models ship inside the ``mediapipe`` wheel (the optional
``autobones[landmarks]`` extra); nothing is downloaded. :data:`MEDIAPIPE_POINTS` maps its
points to the contract's names.
"""
from __future__ import annotations

import contextlib
import os
import warnings

import numpy as np

from ..errors import AutobonesError

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


@contextlib.contextmanager
def quiet_stderr():
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
    #: what a user without the detector is told to run
    INSTALL = "pip install 'autobones[landmarks]'"

    def __init__(self, min_confidence=0.5):
        self.min_confidence = min_confidence
        self._model = None

    @staticmethod
    def installed():
        """Whether MediaPipe can be imported (without importing it: it loads TensorFlow Lite)."""
        import importlib.util

        return importlib.util.find_spec("mediapipe") is not None

    def _load(self):
        os.environ.setdefault("GLOG_minloglevel", "2")
        os.environ.setdefault("TF_CPP_MIN_LOG_LEVEL", "2")
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                from mediapipe.python.solutions import face_mesh
        except ImportError as exc:
            raise AutobonesError(
                f"automatic landmarks need the optional face detector: {MediaPipeFaceMesh.INSTALL} "
                f"(MediaPipe; import failed: {exc})") from None
        with quiet_stderr():  # also when used on its own
            self._model = face_mesh.FaceMesh(static_image_mode=True, max_num_faces=1,
                                             refine_landmarks=False,
                                             min_detection_confidence=self.min_confidence)

    def __call__(self, image):
        if self._model is None:
            self._load()
        with quiet_stderr(), warnings.catch_warnings():
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
