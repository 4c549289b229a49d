"""The one Wavefront OBJ reader and writer: ``v`` and ``f`` lines, vertex order kept.

Other OBJ content (normals, texture coordinates, groups, materials) is ignored on
reading and never written.
"""
from __future__ import annotations

import numpy as np

from ..errors import AutobonesError


def read_obj(path):
    """Vertices and triangles of an OBJ file, exactly as its ``v`` and ``f`` lines state them.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    V : (n, 3) float64
        ``v`` lines in file order (extra columns such as colours ignored).
    F : (m, 3) int64
        0-based; polygons are fanned ``(0, k, k+1)``; negative indices count back from the
        last vertex read so far; ``f 1/2/3`` keeps the vertex index. (0, 3) when there is none.

    Raises
    ------
    AutobonesError
        A ``v`` line with fewer than 3 coordinates, face index 0, a face of fewer than 3
        vertices, or no ``v`` line at all. Unparsable numbers raise ValueError.
    """
    verts, faces = [], []
    with open(path, "rb") as fh:
        for lineno, raw in enumerate(fh, 1):
            if raw[:2] == b"v ":
                parts = raw.split()
                if len(parts) < 4:
                    raise AutobonesError(f"{path}:{lineno}: vertex line needs 3 coordinates")
                verts.append((float(parts[1]), float(parts[2]), float(parts[3])))
            elif raw[:2] == b"f ":
                idx = []
                for tok in raw.split()[1:]:
                    i = int(tok.split(b"/")[0])
                    # OBJ is 1-based; negative indices count back from the last vertex so far
                    idx.append(i - 1 if i > 0 else len(verts) + i)
                    if i == 0:
                        raise AutobonesError(f"{path}:{lineno}: face index 0 (OBJ indices start at 1)")
                if len(idx) < 3:
                    raise AutobonesError(f"{path}:{lineno}: a face needs at least 3 vertices")
                # polygons are fanned: (0, k, k+1)
                faces.extend((idx[0], idx[k], idx[k + 1]) for k in range(1, len(idx) - 1))
    if not verts:
        raise AutobonesError(f"{path}: no vertex lines ('v x y z') found; not an OBJ mesh")
    return np.array(verts, dtype=np.float64), np.array(faces, dtype=np.int64).reshape(-1, 3)


def write_obj(path, V, F, comment=None):
    """Write ``v`` and ``f`` lines (1-based) with the shortest round-trip repr of each coordinate,
    so :func:`read_obj` gives back the same float64 bits.

    Parameters
    ----------
    path : str or os.PathLike
    V : (n, 3) float
    F : (m, 3) int
        0-based triangles.
    comment : str, optional
        One ``# comment`` line written first.
    """
    with open(path, "w", encoding="ascii") as fh:
        if comment is not None:
            fh.write(f"# {comment}\n")
        fh.write("".join(f"v {float(a)!r} {float(b)!r} {float(c)!r}\n" for a, b, c in np.asarray(V).tolist()))
        np.savetxt(fh, np.asarray(F) + 1, fmt="f %d %d %d")
