"""The 52 ARKit blendshape names and how ICT-FaceKit and Live Link Face spell them.

Goes beyond the seeds (issue #15). ARKit's ``Left`` is the subject's own left (Apple's
ARFaceAnchor: +x points to the face's own left, the viewer's right), as is ICT-FaceKit's
``_L`` (its ``eyeBlink_L`` moves the lids at +X, where the landmark contract puts
``exocanthion_l``): ``eyeBlink_L`` -> ``eyeBlinkLeft``.
"""
from __future__ import annotations

# ARKit's names in the order Unreal's EARFaceBlendShape (and so Live Link Face's CSV) lists them
ARKIT_NAMES = (
    "eyeBlinkLeft", "eyeLookDownLeft", "eyeLookInLeft", "eyeLookOutLeft", "eyeLookUpLeft", "eyeSquintLeft",
    "eyeWideLeft", "eyeBlinkRight", "eyeLookDownRight", "eyeLookInRight", "eyeLookOutRight", "eyeLookUpRight",
    "eyeSquintRight", "eyeWideRight", "jawForward", "jawLeft", "jawRight", "jawOpen", "mouthClose", "mouthFunnel",
    "mouthPucker", "mouthLeft", "mouthRight", "mouthSmileLeft", "mouthSmileRight", "mouthFrownLeft",
    "mouthFrownRight", "mouthDimpleLeft", "mouthDimpleRight", "mouthStretchLeft", "mouthStretchRight",
    "mouthRollLower", "mouthRollUpper", "mouthShrugLower", "mouthShrugUpper", "mouthPressLeft", "mouthPressRight",
    "mouthLowerDownLeft", "mouthLowerDownRight", "mouthUpperUpLeft", "mouthUpperUpRight", "browDownLeft",
    "browDownRight", "browInnerUp", "browOuterUpLeft", "browOuterUpRight", "cheekPuff", "cheekSquintLeft",
    "cheekSquintRight", "noseSneerLeft", "noseSneerRight", "tongueOut",
)
assert len(ARKIT_NAMES) == 52 and len(set(ARKIT_NAMES)) == 52

# shapes the ICT set lacks: written as all-zero targets so every client finds its 52 names
ABSENT = ("tongueOut",)

# the eyeball turns: on a head with separate eyeballs these rotate them about the eye bones
EYE_LOOK = tuple(n for n in ARKIT_NAMES if n.startswith("eyeLook"))

# Live Link Face's extra CSV columns after the 52 shapes: radians (ARKit's head and eye angles)
CAPTURE_ANGLES = ("HeadYaw", "HeadPitch", "HeadRoll", "LeftEyeYaw", "LeftEyePitch", "LeftEyeRoll",
                  "RightEyeYaw", "RightEyePitch", "RightEyeRoll")


def ict_names(name):
    """ICT-FaceKit expression names whose displacements sum to ARKit shape ``name``.

    ``browInnerUp`` and ``cheekPuff`` are split L/R in ICT (both halves); ``...Left`` is
    ICT's ``..._L``; ``tongueOut`` has none (an empty tuple).
    """
    if name in ABSENT:
        return ()
    if name in ("jawLeft", "jawRight", "mouthLeft", "mouthRight"):  # ICT spells these as ARKit does
        return (name,)
    if name in ("browInnerUp", "cheekPuff"):
        return (name + "_L", name + "_R")
    for side, suffix in (("Left", "_L"), ("Right", "_R")):
        if name.endswith(side):
            return (name[: -len(side)] + suffix,)
    return (name,)


def capture_column(name):
    """Live Link Face's CSV column of an ARKit name: the name capitalised (``eyeBlinkLeft`` -> ``EyeBlinkLeft``)."""
    return name[0].upper() + name[1:]
