"""Write a posed mesh (vertices and triangles, no rig) as OBJ or GLB, atomically.

The output of ``autobones pose``. Vertex *i* of the file is vertex *i* of the rig
(nothing merged, nothing reordered), in the rig's input frame and units.
"""
from __future__ import annotations

import io
import os

import numpy as np

from ..arguments import finite_output
from ..errors import AutobonesError
from .atomic import output_folder, write_bytes_atomic
from .gltf import glb_bytes

FORMATS = (".obj", ".glb")


def write_posed_mesh(path, V, F, comment=None):
    """Write ``V`` (n, 3) float and ``F`` (m, 3) int to ``path`` (.obj or .glb).

    OBJ: ``v`` lines with 9 significant digits (float32 precision and more), 1-based
    ``f`` lines. GLB: a static glTF 2.0 mesh (float32 positions, uint32 indices, no skin,
    no normals), written by :func:`autobones.io.gltf.glb_bytes`. The file is written under
    a temporary name in the target folder and renamed when complete.

    Parameters
    ----------
    path : str or os.PathLike
        Output file; its extension picks the format.
    V : (n, 3) float
        Vertices, any frame and unit (written as given).
    F : (m, 3) int
        Triangles, 0-based indices into ``V``.
    comment : str, optional
        One line written as an OBJ comment (ignored for GLB).
    """
    path = os.fspath(path)
    ext = os.path.splitext(path)[1].lower()
    if ext not in FORMATS:
        raise AutobonesError(f"{path}: the posed mesh is written as .obj or .glb, not {ext or 'no extension'!r}")
    output_folder(path)
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    finite_output(path, "the posed mesh", ("vertices", V))  # the last line of defence: no NaN, no inf written
    if ext == ".obj":
        buf = io.StringIO()
        if comment:
            buf.write("# " + " ".join(str(comment).split()) + "\n")
        np.savetxt(buf, V, fmt="v %.9g %.9g %.9g")
        np.savetxt(buf, F + 1, fmt="f %d %d %d")
        data = buf.getvalue().encode()
    else:
        data = glb_bytes(V, F, path=path)  # the rig's container writer, minus the skin
    write_bytes_atomic(path, data, "the posed mesh")
    return path
