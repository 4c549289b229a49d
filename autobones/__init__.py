"""autobones: rig arbitrary head meshes without a technical artist.

Public API::

    import autobones
    rig = autobones.place("scan.obj", density="dense")
    rig.save("scan.glb")          # + scan.rig.json, scan.weights.npz
    rig = autobones.load_rig("head.glb")    # a saved transferred rig, posed:
    V = rig.pose(au={12: 0.8, 6: 0.4}, jaw_deg=10)
"""
from .version import __version__

import importlib.util as _util
import os as _os

# Installed, cli/ and generic_rig/ are subpackages (pyproject's package-dir); in a source checkout
# they sit beside this folder. Let such a checkout import them the same way, and prefer its own copies
# even when another checkout is installed editable (its finder would otherwise serve that one's cli/
# to this one's autobones: a worktree on PYTHONPATH would run the main tree's commands).
_root = _os.path.dirname(_os.path.dirname(_os.path.abspath(__file__)))
if (_os.path.isfile(_os.path.join(_root, "cli", "commands.py"))
        and _os.path.isfile(_os.path.join(_root, "generic_rig", "default_head.obj"))) \
        or _util.find_spec(__name__ + ".generic_rig") is None:
    __path__.append(_root)

from .errors import AutobonesError
from .io.mesh import load_mesh
from .orient import Frame
# before .rig: placement's package imports the Rig as it loads (the order __init__ always had)
from .api import detect_frame, place, transfer, transfer_attributes  # their arguments checked (issue #33)
from .rig import Rig
from .skeleton import Skeleton
from .labelled_rig import LabelledRig
from .landmarks.detect import detect_landmarks
from .expressions.model import ExpressionModel
from .io.rig_files import load_rig


def build_rig(base, landmarks, **kwargs):
    """A labelled generic rig from a base head (path, (V, F) or mesh object) and its landmarks (path or dict);
    see :func:`autobones.rig_building.build.build_rig`."""
    from .rig_building.build import build_rig as _build
    from .io.landmarks import resolve_landmarks
    from .io.mesh import resolve_mesh, wound_outward

    from .io.landmark_checks import validate_landmarks

    V, F, what = resolve_mesh(base)
    F = wound_outward(V, F, what)[0]   # the generic skin is fitted by its normals: stored outward
    lm, source = resolve_landmarks(landmarks)
    # the unit and surface check transfer has (issue #33: landmarks in cm on a head in m built a rig 226 m off)
    lm = validate_landmarks(lm, V, F, min_count=1, source=source)
    return _build(V, F, lm, **kwargs)

__all__ = ["AutobonesError", "ExpressionModel", "Frame", "LabelledRig", "Rig", "Skeleton", "build_rig", "detect_frame", "detect_landmarks", "load_mesh", "load_rig",
           "place", "transfer", "transfer_attributes", "__version__"]
