"""ARKit's 52 face blendshapes on any landmarked head (issue #15), one operation per module.

- :mod:`.names`: the 52 names, ICT-FaceKit's names for them, Live Link Face's CSV columns;
- :mod:`.shapes`: the packaged source shape set (ICT-FaceKit's neutral skin and its displacements);
- :mod:`.deformation_transfer`: Sumner & Popovic 2004 onto a head's own triangles;
- :mod:`.targets`: the 52 displacement fields of a transferred rig (eyeballs turned for eyeLook*);
- :mod:`.capture`: a Live Link Face CSV recording read and checked;
- :mod:`.animation`: that recording as a glTF animation of morph-target weights and bones.
"""
from .names import ARKIT_NAMES

__all__ = ["ARKIT_NAMES"]
