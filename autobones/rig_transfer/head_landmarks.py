"""The head's landmarks and frame for ``transfer``: read from a file and validated, or found by the
automatic detector on a human face (:mod:`autobones.landmarks.detect`).

With a landmark file the frame is the landmarks' own (:func:`autobones.orient.frame_from_landmarks`,
unless an axis is forced); without one it is the detected frame the detector renders the head in, and a
face found there settles which way it looks (its ``front_check`` is dropped).
"""
from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np

from ..errors import AutobonesError, counted
from ..io.landmarks import NAMES, resolve_landmarks, validate_landmarks
from ..orient import detect_frame, frame_from_landmarks

log = logging.getLogger("autobones")

MIN_LANDMARKS = 10   # contract names shared with the generic rig that a transfer needs


def head_landmarks(V, F, source, landmarks, generic, up, front):
    """The head's landmarks and frame: read and validated, or detected when ``landmarks`` is None.

    ``V`` (n, 3) float and ``F`` (m, 3) int the head (its own frame and units), ``source`` its file
    name for messages (or None), ``landmarks`` what :func:`autobones.io.landmarks.resolve_landmarks`
    takes (or None), ``generic`` the LabelledRig, ``up`` / ``front`` forced axes (or None).

    Returns ``lm`` (dict str -> (3,) float64, input frame), ``frame`` (orient.Frame),
    ``detected`` (the detector's result, or None for given landmarks) and ``shared`` (the
    contract names in both ``lm`` and the generic rig, contract order).
    """
    detected = None
    if landmarks is None:
        from ..landmarks.detect import LandmarkDetector

        frame = detect_frame(V, F, up=up, front=front)
        detected = LandmarkDetector().detect(V, F, frame=frame, what=source or "the head")
        frame = replace(frame, front_check=None)   # a face found there settles a close call on its front
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
