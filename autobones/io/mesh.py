"""Load a triangle mesh keeping the user's vertices exactly, in the user's order.

Goes beyond the seeds: 003/004 assume a clean single mesh. Real heads arrive as
OBJ with quads and UV seams, PLY in odd units, glTF scenes, separate parts.
trimesh's default OBJ loader splits vertices at UV seams and merges duplicates,
so vertex i of the file would no longer be vertex i of the result; for OBJ we
read the ``v``/``f`` lines as they stand, for other formats we ask trimesh not
to process anything.
"""
from __future__ import annotations

import os

import numpy as np

from ..errors import AutobonesError

SUPPORTED = (".obj", ".ply", ".off", ".stl", ".glb", ".gltf")

# A file larger than this is refused before parsing: heads are well under it.
MAX_FILE_BYTES = 2 * 1024**3


def load_mesh(path):
    """Read a mesh file.

    Parameters
    ----------
    path : str or os.PathLike
        ``.obj``, ``.ply``, ``.off``, ``.stl``, ``.glb`` or ``.gltf``.

    Returns
    -------
    V : (n, 3) float64
        Vertex positions in the file's own frame and units, in file order.
    F : (m, 3) int64
        Triangles (polygons are fanned), indices into ``V``.

    Raises
    ------
    AutobonesError
        Missing, empty, unreadable or unsupported file; no faces; NaN or
        infinite coordinates; face indices out of range; a flat or tiny mesh.
    """
    path = os.fspath(path)
    name = os.path.basename(path)
    if not os.path.isfile(path):
        raise AutobonesError(f"{path}: no such file")
    ext = os.path.splitext(path)[1].lower()
    if ext not in SUPPORTED:
        raise AutobonesError(
            f"{path}: unsupported extension {ext or '(none)'}; use one of {', '.join(SUPPORTED)}")
    size = os.path.getsize(path)
    if size == 0:
        raise AutobonesError(f"{path}: the file is empty")
    if size > MAX_FILE_BYTES:
        raise AutobonesError(f"{path}: {size / 1024**3:.1f} GiB is too large for a head mesh")
    try:
        if ext == ".obj":
            V, F = _read_obj(path)
        else:
            V, F = _read_trimesh(path)
    except AutobonesError:
        raise
    except Exception as exc:  # any parser failure is the file's fault, not ours
        text = str(exc)
        if any(k in text for k in ("unexpected length", "reshape", "buffer is smaller", "truncated")):
            why = "the file is shorter than its header says: truncated or corrupt"
        else:
            why = f"{exc.__class__.__name__}: {text}"
        raise AutobonesError(f"{path}: not a readable {ext[1:].upper()} mesh ({why})") from exc
    return check_mesh(V, F, name=name)


def check_mesh(V, F, name="mesh"):
    """Validate plain arrays and return them as ``(float64 (n,3), int64 (m,3))``."""
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F)
    if V.ndim != 2 or V.shape[1] != 3 or len(V) == 0:
        raise AutobonesError(f"{name}: no vertices found; is this a mesh file?")
    if F.size == 0:
        raise AutobonesError(f"{name}: {len(V)} vertices but no faces; a point cloud cannot be rigged")
    if F.ndim != 2 or F.shape[1] != 3:
        raise AutobonesError(f"{name}: faces must be triangles, got shape {F.shape}")
    F = F.astype(np.int64)
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        raise AutobonesError(
            f"{name}: {int(bad.sum())} vertices have NaN or infinite coordinates (first: vertex {int(np.argmax(bad))})")
    if F.min() < 0 or F.max() >= len(V):
        raise AutobonesError(f"{name}: face indices out of range (0..{len(V) - 1}), file is corrupt")
    used = np.unique(F)
    extent = V[used].max(axis=0) - V[used].min(axis=0)
    if len(F) < 4 or len(used) < 4:
        raise AutobonesError(f"{name}: only {len(F)} faces; a head needs a real surface")
    if extent.max() <= 0 or extent.min() < 1e-4 * extent.max():
        raise AutobonesError(f"{name}: the mesh is flat (extent {extent.tolist()}); a head has volume")
    area = np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    if not (area > 0).any():
        raise AutobonesError(f"{name}: every face has zero area")
    return V, F


def _read_obj(path):
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


def _read_trimesh(path):
    import trimesh

    loaded = trimesh.load(path, process=False, maintain_order=True)
    if isinstance(loaded, trimesh.Scene):
        geoms = [g for g in loaded.dump() if isinstance(g, trimesh.Trimesh)] if loaded.geometry else []
        if not geoms:
            raise AutobonesError(f"{path}: the file holds no triangle mesh")
        offsets = np.cumsum([0] + [len(g.vertices) for g in geoms[:-1]])
        V = np.concatenate([np.asarray(g.vertices) for g in geoms])
        F = np.concatenate([np.asarray(g.faces) + o for g, o in zip(geoms, offsets)])
        return V, F
    if not isinstance(loaded, trimesh.Trimesh):
        n = len(getattr(loaded, "vertices", []))
        raise AutobonesError(f"{path}: {n} points but no faces; a point cloud cannot be rigged")
    return np.asarray(loaded.vertices), np.asarray(loaded.faces)
