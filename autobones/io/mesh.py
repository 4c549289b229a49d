"""Load a triangle mesh keeping the user's vertices exactly, in the user's order.

The bone-placement method of ``place`` and Orvalho, Zacur & Susin 2008 assume a
clean single mesh. Real heads arrive as
OBJ with quads and UV seams, PLY in odd units, glTF scenes, separate parts.
trimesh's default OBJ loader splits vertices at UV seams and merges duplicates,
so vertex i of the file would no longer be vertex i of the result; for OBJ we
read the ``v``/``f`` lines as they stand, for other formats we ask trimesh not
to process anything.
"""
from __future__ import annotations

import logging
import os
import re
import struct

import numpy as np

from ..errors import AutobonesError, counted
from ..geometry.normals import triangle_normals
from ..geometry.topology import used_vertices
from .files import check_regular
from .obj import read_obj
from .parts import NamedMesh, parts_apart, stray_parts

log = logging.getLogger("autobones")

SUPPORTED = (".obj", ".ply", ".off", ".stl", ".glb", ".gltf")

# A file larger than this is refused before parsing: heads are well under it.
MAX_FILE_BYTES = 2 * 1024**3


def load_mesh(path, strays=False):
    """Read a mesh file.

    Parameters
    ----------
    path : str or os.PathLike
        ``.obj``, ``.ply``, ``.off``, ``.stl``, ``.glb`` or ``.gltf``.
    strays : bool
        Accept small parts far from the head (:func:`stray_parts`; the caller drops them) instead
        of refusing them as outliers.

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
        infinite coordinates; face indices out of range; a flat or tiny mesh; an
        outlier far from the rest (:data:`OUTLIER_REACH`); faces of (almost) zero area.
    """
    from ..arguments import path_argument

    path = path_argument(path, "path")
    name = os.path.basename(path)
    check_regular(path, "head mesh", "a folder, not a mesh file")
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
            V, F = read_obj(path)
        else:
            if ext in _SNIFF:
                _SNIFF[ext](path, size)
            V, F = _read_trimesh(path)
            _check_declared(path, ext, V, F)
    except AutobonesError:
        raise
    except Exception as exc:  # any parser failure is the file's fault, not ours
        text = str(exc)
        if any(k in text for k in ("unexpected length", "reshape", "buffer is smaller", "truncated",
                                   "not expected length")):
            why = "the file is shorter than its header says: truncated or corrupt"
        elif "with a sequence" in text or "inhomogeneous" in text:  # numpy on rows of different lengths
            why = "its rows hold different numbers of values: the file is cut short or corrupt"
        elif isinstance(exc, (UnicodeError, ImportError)):
            # trimesh guesses the encoding of text that is not UTF-8 with an optional module:
            # either way the file is not the text its format is
            why = f"not a valid {ext[1:].upper()} file: its text is not readable"
        else:
            why = f"{exc.__class__.__name__}: {text}"
        raise AutobonesError(f"{path}: not a readable {ext[1:].upper()} mesh ({why})") from exc
    return check_mesh(V, F, name=name, strays=strays, from_file=True)


def default_head():
    """(V, F) of the built-in default head (metres, +Y up, +Z front)."""
    from ..generic_rig import default_head_path

    return load_mesh(default_head_path())


def resolve_mesh(mesh, strays=False):
    """The mesh argument of ``place``, ``transfer``, ``transfer_attributes`` and ``build_rig``.

    Parameters
    ----------
    mesh : str, os.PathLike, (V, F) pair, mesh object or None
        A mesh file (:func:`load_mesh`); arrays ``V`` (n, 3) and ``F`` (m, 3); any object with
        ``vertices`` and ``faces`` attributes (``trimesh.Trimesh``, an ``open3d`` mesh's
        ``vertices``/``triangles`` are not this: convert first); None for the built-in default head.
    strays : bool
        Let small parts far from the head through (:func:`stray_parts`: the caller drops them).

    Returns
    -------
    V : (n, 3) float64
        Vertices in the mesh's own frame and units, in its order.
    F : (m, 3) int64
        Triangles.
    source : str or None
        The file's base name (the default head's for None); None for arrays and objects (but a
        :class:`~autobones.io.parts.NamedMesh`'s own).

    Raises
    ------
    AutobonesError
        Unreadable file, bad arrays (:func:`check_mesh`), or an argument of another type.
    """
    if mesh is None:
        from ..generic_rig import default_head_path

        return (*default_head(), os.path.basename(default_head_path()))
    if isinstance(mesh, (tuple, list)) and len(mesh) == 2:
        V, F = check_mesh(*mesh, strays=strays)
        return V, F, None
    if isinstance(mesh, (str, bytes, os.PathLike)):
        # the file name only: a sidecar must not change when the folder moves (batch, clusters)
        return (*load_mesh(mesh, strays=strays), os.path.basename(os.fspath(mesh)))
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):
        # a head rigged without its stray or worn parts keeps its file's name (io.parts.NamedMesh)
        source = mesh.source if isinstance(mesh, NamedMesh) else None
        name = source or type(mesh).__name__
        try:
            V, F = np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces)
        except (TypeError, ValueError) as exc:
            raise AutobonesError(f"{name}: its vertices and faces are not numeric arrays ({exc})") from None
        if not (np.issubdtype(F.dtype, np.integer) or (F.size == 0 and F.ndim == 2)):
            raise AutobonesError(f"{name}: faces must be integer vertex indices, got dtype {F.dtype}")
        V, F = check_mesh(V, F, name=name, strays=strays)
        return V, F, source
    raise AutobonesError(f"mesh: expected a file path, a (V, F) pair, an object with vertices and faces "
                         f"(trimesh.Trimesh) or None, got {type(mesh).__name__}")


def check_mesh(V, F, name="mesh", strays=False, from_file=False):
    """Validate plain arrays and return them as ``(float64 (n,3), int64 (m,3))``; AutobonesError
    naming ``name`` for anything :func:`load_mesh` refuses after parsing. ``strays``: small parts
    far from the head (:func:`stray_parts`) are left out of the outlier test (the caller drops them).
    ``from_file``: the arrays were read from a file (a bad index then means the file is corrupt)."""
    corrupt = ", file is corrupt" if from_file else ""
    V, F = _as_arrays(V, F, name)
    if V.ndim != 2 or V.shape[1] != 3 or len(V) == 0:
        raise AutobonesError(f"{name}: no vertices found; is this a mesh file?")
    if F.size == 0:
        raise AutobonesError(f"{name}: {counted(len(V), 'vertex', 'vertices')} but no faces; a point cloud cannot be rigged")
    if F.ndim != 2 or F.shape[1] != 3:
        raise AutobonesError(f"{name}: faces must be triangles, got shape {F.shape}")
    if not np.issubdtype(F.dtype, np.integer):  # 1.5 would be cut to 1 by astype: a silently different mesh
        if not (np.issubdtype(F.dtype, np.floating) and np.isfinite(F).all() and (F == np.round(F)).all()):
            raise AutobonesError(f"{name}: faces must be whole vertex indices, got {F.dtype} values such as "
                                 f"{float(F.ravel()[np.argmax(F.ravel() != np.round(F.ravel()))])!r}")
        if np.abs(F).max() >= 2 ** 53:
            raise AutobonesError(f"{name}: face indices out of range (0..{len(V) - 1}){corrupt}")
    F = F.astype(np.int64)
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        raise AutobonesError(
            f"{name}: NaN or infinite coordinates at {counted(int(bad.sum()), 'vertex', 'vertices')} (first: vertex {int(np.argmax(bad))})")
    if F.min() < 0 or F.max() >= len(V):
        raise AutobonesError(f"{name}: face indices out of range (0..{len(V) - 1}){corrupt}")
    used = used_vertices(F, len(V))
    if len(F) < 4 or len(used) < 4:
        raise AutobonesError(f"{name}: only {counted(len(F), 'face')}; a head needs a real surface")
    if strays:
        body = stray_parts(V, F)
        used = used if body is None else np.intersect1d(used, body.index, assume_unique=True)
    U = V[used]   # one copy: a 1M-vertex scan's is 24 MB
    _check_scale(U, name)
    _check_outliers(V, used, name)
    extent = U.max(axis=0) - U.min(axis=0)
    if extent.max() <= 0 or extent.min() < 1e-4 * extent.max():
        raise AutobonesError(f"{name}: the mesh is flat (extent {extent.tolist()}); a head has volume")
    _check_area(V, F, extent, name)
    _check_offset(V, F, U, extent, name)
    apart = parts_apart(V, F)
    if apart is not None:
        shares, gap = apart
        raise AutobonesError(f"{name}: {len(shares)} separate parts of head size stand apart "
                             f"({', '.join(f'{100 * a:.0f}%' for a in shares)} of the area, up to {gap:.2g} of a "
                             "part's size between them): one head per file; split them (Blender: Mesh > Separate > "
                             "By Loose Parts) and rig each")
    return V, F


def _as_arrays(V, F, name):
    """``V`` float64 and ``F`` as numpy arrays; AutobonesError naming ``name`` for ragged lists
    (rows of different lengths) or values that are not numbers."""
    try:
        kind = np.asarray(V).dtype.kind
        V = np.asarray(V, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise AutobonesError(f"{name}: the vertices are not an (n, 3) array of numbers ({str(exc)[:80]})") from None
    if kind in "USb":  # numpy would parse "0.5" and take True as 1: text or truth values are not coordinates
        raise AutobonesError(f"{name}: the vertices are not an (n, 3) array of numbers (dtype {kind!r})")
    try:
        F = np.asarray(F)
    except ValueError as exc:  # numpy refuses ragged nested lists
        raise AutobonesError(f"{name}: the faces are not an (m, 3) array of indices ({str(exc)[:80]})") from None
    if F.dtype == object or F.dtype.kind in "USb":
        raise AutobonesError(f"{name}: faces must be whole vertex indices, got {F.dtype} values")
    return V, F


# What the outputs can hold: a glb stores float32 positions (largest 3.4e38, smallest normal 1.2e-38),
# and the pipeline squares lengths. A head whose coordinates reach past MAX_COORDINATE, or which is
# smaller across than MIN_SIZE, would be written as infinities or as zero-area triangles (issue #33:
# x1e150 gave -inf positions, x1e-40 zero-area triangles, both with exit 0): refused, with the scale
# that brings it into range.
MAX_COORDINATE = 1e18
MIN_SIZE = 1e-18


def _check_scale(U, name):
    big = float(np.abs(U).max())
    if big > MAX_COORDINATE:
        raise AutobonesError(f"{name}: coordinates reach {big:.3g}, beyond the {MAX_COORDINATE:.0e} autobones "
                             "writes (a glb's float32 positions would be infinite); scale the mesh to its real "
                             "units (metres, centimetres) first")
    size = float(np.linalg.norm(U.max(axis=0) - U.min(axis=0)))  # after: at 1e200 its square overflows
    if 0 < size < MIN_SIZE:
        raise AutobonesError(f"{name}: the mesh is {size:.3g} across, below the {MIN_SIZE:.0e} autobones writes (a "
                             "glb's float32 positions would collapse its triangles to zero area); scale the mesh "
                             "to its real units (metres, centimetres) first")


# A glb's float32 positions are 2^-23 of their magnitude apart: a head far from the origin (a scan in
# world coordinates) is written on a grid that coarse, and near its edges' length its vertices snap
# together (a 0.2 m head 1e6 m out kept 31 distinct positions of 8,838, with exit 0). Refused when the
# grid's rounding reaches SNAP of the median edge, with the cure.
SNAP = 0.1


def _check_offset(V, F, U, extent, name):
    far = float(np.abs(U).max())
    rounding = far * 2.0 ** -24
    edge = float(np.median(np.linalg.norm(V[F[:, 1]] - V[F[:, 0]], axis=1)))
    if rounding > SNAP * edge:
        raise AutobonesError(f"{name}: the head lies {far:.3g} from the origin, {far / extent.max():,.0f} times its size: a "
                             f"glb's 32-bit positions there round by {rounding:.2g}, {rounding / edge:.0%} of its "
                             "median edge (its vertices would snap together); move it near the origin first "
                             "(subtract its centre)")


# A few vertices far outside the rest (a stray vertex, a spike triangle, a part at 1e9) set the
# bounding box, and with it the frame, the head size and every tolerance taken relative to it:
# such a mesh is refused rather than rigged wrong. The rest is the box of the vertices with
# OUTLIER_TRIM of them cut off at each end of each axis; a vertex farther outside that box than
# OUTLIER_REACH times its largest side is an outlier. Both are fractions: the rule is scale-free.
OUTLIER_TRIM = 0.005
OUTLIER_REACH = 1.0

# A triangle whose area is below DEGENERATE_AREA times its longest edge squared has its corners
# on one line (up to rounding); a mesh whose total area is below MIN_AREA times its bounding-box
# diagonal squared is a line or a point however many faces it has (a head's is about 0.5).
DEGENERATE_AREA = 1e-10
MIN_AREA = 1e-6


def _check_outliers(V, used, name):
    U = V[used]
    lo, hi = np.quantile(U, OUTLIER_TRIM, axis=0), np.quantile(U, 1.0 - OUTLIER_TRIM, axis=0)
    core = float((hi - lo).max())
    if not core > 0:
        return  # a flat or collapsed mesh: refused below, with its own message
    outside = np.linalg.norm(np.maximum(lo - U, 0.0) + np.maximum(U - hi, 0.0), axis=1) / core
    far = outside > OUTLIER_REACH
    if far.any():
        k = int(far.sum())
        raise AutobonesError(
            f"{name}: an outlier: {k} {'vertices lie' if k > 1 else 'vertex lies'} (first: vertex "
            f"{int(used[np.argmax(far)])}) {outside.max():.3g} times the size of the rest of the mesh away from it "
            f"(a stray vertex or a spike triangle) and would decide the head's size and frame; remove "
            f"{'them' if k > 1 else 'it'} first")


def _check_area(V, F, extent, name, chunk=65536):
    # in chunks, stopping at the first chunk with a proper face: a million faces in well under a second
    total, proper = 0.0, False
    for s in range(0, len(F), chunk):
        A, B, C = (V[F[s:s + chunk, i]] for i in range(3))
        area2 = np.linalg.norm(triangle_normals(V, F[s:s + chunk]), axis=1)
        total += 0.5 * area2.sum()
        if not proper:
            edge2 = np.maximum(np.maximum(((B - A) ** 2).sum(axis=1), ((C - B) ** 2).sum(axis=1)),
                               ((A - C) ** 2).sum(axis=1))
            proper = bool((area2 > DEGENERATE_AREA * edge2).any())
    if not proper:
        raise AutobonesError(f"{name}: every face has zero area (its corners coincide or lie on one line)")
    diag = float(np.linalg.norm(extent))
    if total < MIN_AREA * diag ** 2:
        raise AutobonesError(f"{name}: the faces have almost zero area ({total:.3g} in all, for a bounding box "
                             f"{diag:.3g} across): a line or a sliver, not a surface")


def _text_head(path, n=4096):
    """The first ``n`` bytes of ``path`` as text, or None when they are not UTF-8 (a character
    cut at the end is fine)."""
    with open(path, "rb") as fh:
        head = fh.read(n)
    try:
        return head.decode("utf-8")
    except UnicodeDecodeError as exc:
        if exc.start >= len(head) - 3 and len(head) == n:
            return head[:exc.start].decode("utf-8")
        return None


def _sniff_stl(path, size):
    """AutobonesError unless ``path`` looks like a binary STL (its size matches its triangle count)
    or an ASCII one (text starting with ``solid``); checked before trimesh, which would try to
    decode random bytes as text."""
    if size >= 84:
        with open(path, "rb") as fh:
            fh.seek(80)
            (count,) = struct.unpack("<I", fh.read(4))
        if size == 84 + 50 * count:
            return
    text = _text_head(path)
    if text is None or not text.lstrip().lower().startswith("solid"):
        raise AutobonesError(f"{path}: not a valid STL file (neither a binary STL whose size matches its "
                             "triangle count nor ASCII text starting with 'solid')")


def _sniff_off(path, size):
    """AutobonesError unless ``path`` is text whose first word (after comments) is OFF or a
    variant (COFF, NOFF, STOFF...)."""
    text = _text_head(path)
    words = None if text is None else _off_words(text)
    if not words or not words[0].upper().endswith("OFF"):
        raise AutobonesError(f"{path}: not a valid OFF file (not text starting with an OFF header)")


_SNIFF = {".stl": _sniff_stl, ".off": _sniff_off}


def _off_words(text):
    """The words of an OFF file's ``text``, its ``#`` comments left out."""
    return " ".join(line.split("#", 1)[0] for line in text.splitlines()).split()


def _declared(path, ext):
    """(vertices, faces) a PLY or OFF header declares, or None (binary headers read as latin-1 text)."""
    with open(path, "rb") as fh:
        text = fh.read(4096).decode("latin-1")
    if ext == ".ply":
        head = text.split("end_header", 1)[0]
        found = dict(re.findall(r"^element\s+(vertex|face)\s+(\d+)", head, flags=re.M))
        return (int(found["vertex"]), int(found["face"])) if len(found) == 2 else None
    words = _off_words(text)
    if ext == ".off" and len(words) >= 3 and words[0].upper().endswith("OFF") and words[1].isdigit() \
            and words[2].isdigit():
        return int(words[1]), int(words[2])
    return None


def _check_declared(path, ext, V, F):
    """AutobonesError when an ASCII PLY or OFF holds fewer vertices or faces than its header declares: cut
    short between rows, trimesh reads what is there (241 of an icosphere's 320 faces, with exit 0)."""
    if ext not in (".ply", ".off"):
        return
    declared = _declared(path, ext)
    # a polygon fans into two or more triangles: fewer triangles than declared faces is always short
    if declared is not None and (len(V) < declared[0] or len(F) < declared[1]):
        raise AutobonesError(f"{path}: holds {counted(len(V), 'vertex', 'vertices')} and {counted(len(F), 'face')} "
                             f"of the {declared[0]} and {declared[1]} its header declares: the file is cut short "
                             "or corrupt")


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
        raise AutobonesError(f"{path}: {counted(n, 'point')} but no faces; a point cloud cannot be rigged")
    return np.asarray(loaded.vertices), np.asarray(loaded.faces)


def wound_outward(V, F, source=None):
    """``(F_out, note)``: the triangles ``F`` (m, 3), each once, wound outward for the pipeline's normals,
    winding numbers and views (:func:`autobones.geometry.winding.outward_faces`), and the sidecar's line
    saying how many were repeated or turned (None when none were; logged once). The rig keeps the
    input's own ``F``.

    A triangle written twice (a double-sided export's back faces, a face repeated) is taken once
    (:func:`autobones.geometry.topology.distinct_faces`): its twin wound the other way made every
    triangle read as turned, and the repeats weighed twice in the frame's sample, the depth groups and
    the bone heat (the assimp man double-sided: joints 0.5 head sizes apart, weights up to 1)."""
    from ..geometry.topology import distinct_faces
    from ..geometry.winding import outward_faces

    F_once = distinct_faces(F)
    F_out, turned = outward_faces(V, F_once)
    parts = []
    if len(F_once) < len(F):
        parts.append(f"{len(F) - len(F_once)} of {len(F)} triangles repeat others (a double-sided export?): "
                     "the head was rigged with each once; its triangles are written as given")
    if turned:
        parts.append(f"{turned} of {len(F_once)} triangles wound inward (normals into the head): the head was "
                     "rigged with them turned outward; its triangles are written as given")
    if not parts:
        return F_out, None
    note = "; ".join(parts)
    log.warning("%s: %s", source or "mesh", note)
    return F_out, note
