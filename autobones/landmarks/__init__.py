"""``autobones landmarks``: the landmark contract's names found automatically on human heads.

The head is rendered from several views, a bundled 2-D face model (MediaPipe Face Mesh) finds its
points in each picture, the points are lifted to the surface, combined, and refined by the head's
own geometry (symmetry plane, midline profile). ``preview`` draws landmarks over the head.

Modules: :mod:`~autobones.landmarks.detect` (the detector and :func:`detect_landmarks`),
:mod:`~autobones.landmarks.mediapipe` (the 2-D face model), :mod:`~autobones.landmarks.views`
(cameras around the face, lifting pixels to the surface), :mod:`~autobones.landmarks.orientation`
(which way the face is turned), :mod:`~autobones.landmarks.refine` (symmetry refinement) and
:mod:`~autobones.landmarks.preview`.
"""
from .detect import DetectedLandmarks, LandmarkDetector, NoFaceError, detect_landmarks

__all__ = ["DetectedLandmarks", "LandmarkDetector", "NoFaceError", "detect_landmarks"]
