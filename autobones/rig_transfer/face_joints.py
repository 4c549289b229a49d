"""The generic rig's joints on a face mask, from the face's automatic landmarks: ``place``'s pivot where
the mesh has no back.

Goes beyond the papers we implement. A face mask (a face-only capture, a scan cut in front of or behind the
ears) has no back of the head and no neck to measure; ``place``'s rule from its nose and width
(:mod:`autobones.placement.joints`) reads the mask's pitch and the width of wherever it was cut, and put the
head pivot 0.12-0.65 ex-ex from the occiput-C1 centre on the shared human heads cut 0.3 ex-ex behind their
ear canals and 0.38-1.12 on them cut 0.5 in front (``benchmarks/joints.py`` ``mask-behind`` / ``mask-front``).
On a human face the detector finds the face's landmarks whatever the cut, and the generic rig's joints go
where the landmarks' similarity maps them (:func:`.joints.onto_face`, the detector's own landmarks of
the generic skin on the other side), then onto the landmarks' midplane: 0.09-0.21 on the masks cut behind,
0.13-0.18 on those cut in front where a face is found. The biases did not cancel: the generic's own head
joint mapped so sat above Chancey's centre on all eight shared human heads (0.01-0.16 ex-ex), so the head
joint is now the point human faces put there (``face_joints.json`` in the built-in rig's folder,
:func:`.joints.face_points`, learned from those eight heads of four source families by
``tools/calibrate_face_joints.py``): with each head's family held out of it, over 21 copies (as is, cut
behind and in front of the ears) 0.14 -> 0.10 ex-ex on average, 14 -> 19 within 0.15. Arrays in the
mesh's own frame and units.
"""
from __future__ import annotations

from ..errors import AutobonesError
from ..generic_rig import default_rig_path
from .joints import face_points, onto_face
from .pipeline import face_motion, generic_detected_landmarks, load_generic


def face_joints(V, F, frame=None, names=("head",)):
    """The generic rig's joints ``names`` on the face of ``(V, F)``, from its automatic landmarks.

    Parameters
    ----------
    V, F : (n, 3) float, (m, 3) int
        The mesh, its own frame and units.
    frame : autobones.orient.Frame, optional
        Its frame (found when None).
    names : tuple of str
        Joints of the built-in generic rig.

    Returns
    -------
    joints : dict str -> (3,) float or None
        Each joint in the mesh's frame, on the landmarks' midplane; None when no human face is found.
    note : str or None
        Why not (no detector installed, no face found, a face no human's fits), else None.
    """
    from ..landmarks.detect import LandmarkDetector
    from ..landmarks.mediapipe import MediaPipeFaceMesh

    if not MediaPipeFaceMesh.installed():   # asked before rendering the views it would read
        return None, f"no face detector installed ({MediaPipeFaceMesh.INSTALL})"
    try:
        found = dict(LandmarkDetector().detect(V, F, frame=frame, what="the face"))
    except AutobonesError as exc:
        return None, str(exc)
    generic = load_generic()
    source = generic_detected_landmarks(generic, None)
    if source is None:
        return None, "the generic rig's own landmarks were not found"
    bones = list(generic.skeleton.names)
    calibrated = face_points(default_rig_path(), "detected") or {}
    joints = onto_face(source, found, {n: calibrated.get(n, generic.skeleton.heads[bones.index(n)]) for n in names},
                       face_motion(generic))
    return (None, "the landmarks found fit no human face") if joints is None else (joints, None)
