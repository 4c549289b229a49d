"""autobones: rig arbitrary head meshes without a technical artist.

Public API::

    import autobones
    rig = autobones.place("scan.obj", density="dense")
    rig.save("scan.glb")          # + scan.rig.json, scan.weights.npz
    rig = autobones.load_rig("head.glb")    # a saved transferred rig, posed:
    V = rig.pose(au={12: 0.8, 6: 0.4}, jaw_deg=10)
"""
__version__ = "0.1.0"

from .errors import AutobonesError
from .io.mesh import load_mesh
from .orient import Frame, detect_frame
from .place import place
from .rig import Rig
from .skeleton import Skeleton
from .transfer import transfer
from .attributes import transfer_attributes
from .labelled_rig import LabelledRig
from .detect import detect_landmarks
from .expressions import ExpressionModel
from .load import load_rig


def build_rig(base, landmarks, **kwargs):
    """A labelled generic rig from a base head (path or (V, F)) and its landmarks (path or dict);
    see :func:`autobones.build_rig.build_rig`."""
    from .build_rig import build_rig as _build
    from .io.landmarks import resolve_landmarks
    from .place import resolve_mesh

    V, F, _ = resolve_mesh(base)
    lm, _ = resolve_landmarks(landmarks)
    return _build(V, F, lm, **kwargs)

__all__ = ["AutobonesError", "ExpressionModel", "Frame", "LabelledRig", "Rig", "Skeleton", "build_rig", "detect_frame", "detect_landmarks", "load_mesh", "load_rig",
           "place", "transfer", "transfer_attributes", "__version__"]
