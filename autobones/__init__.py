"""autobones: rig arbitrary head meshes without a technical artist.

Public API::

    import autobones
    rig = autobones.place("scan.obj", density="dense")
    rig.save("scan.glb")          # + scan.rig.json, scan.weights.npz
"""
__version__ = "0.1.0"

from .errors import AutobonesError
from .io.mesh import load_mesh
from .orient import Frame, detect_frame
from .place import place
from .rig import Rig
from .skeleton import Skeleton

__all__ = ["AutobonesError", "Frame", "Rig", "Skeleton", "detect_frame", "load_mesh", "place", "__version__"]
