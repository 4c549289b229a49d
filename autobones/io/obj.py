"""The one Wavefront OBJ reader and writer: ``v`` and ``f`` lines, vertex order kept.

Other OBJ content (normals, texture coordinates, groups, materials) is ignored on
reading and never written.
"""
from __future__ import annotations

import io
import re
import warnings

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
        vertices, a token that is not a number, or no ``v`` line at all.
    """
    with open(path, "rb") as fh:
        # a tab separates tokens as a space does (exporters write ``v\t1\t2\t3``): read as one, no line is
        # skipped for its whitespace
        data = fh.read().removeprefix(b"\xef\xbb\xbf").replace(b"\t", b" ")  # a UTF-8 mark before the first line
    if b"\\" in data:
        data = re.sub(rb"\\ *\r?\n", b" ", data)  # a backslash at a line's end continues it
    try:
        return _read_blocks(data)
    except Exception:  # noqa: BLE001
        # anything the block reader does not cover, and every error message, comes from the line reader
        return _read_lines(path, data)


class _Unusual(Exception):
    """The block reader does not handle this file; the line reader will."""


MAX_BLOCKS = 64


def _read_blocks(data):
    """The common case in numpy: ``v`` and ``f`` lines in a few runs of consecutive lines, positive
    indices. Each run is parsed as one block (C loops, not one Python call per line: a million
    vertices in about a second). Same float64 bits as ``float()`` of each token."""
    buf = np.frombuffer(data, dtype=np.uint8)
    newline = np.flatnonzero(buf == ord("\n"))
    starts = np.r_[0, newline + 1]
    ends = np.r_[newline, len(buf)]
    keep = ends - starts >= 2
    starts, ends = starts[keep], ends[keep]
    c0, c1 = buf[starts], buf[starts + 1]
    if (c0 == ord(" ")).any():
        raise _Unusual  # indented lines: the line reader takes each line's first token
    kind = np.where(c1 != ord(" "), 0, np.where(c0 == ord("v"), 1, np.where(c0 == ord("f"), 2, 0)))
    if not (kind == 1).any():
        raise _Unusual
    # runs of consecutive lines of one kind; other lines (comments, vt, vn, g...) end a run
    change = np.flatnonzero(np.diff(kind) != 0) + 1
    first, last = np.r_[0, change], np.r_[change, len(kind)] - 1
    runs = [(int(kind[a]), data[starts[a]:ends[b]]) for a, b in zip(first, last) if kind[a]]
    if len(runs) > MAX_BLOCKS or any(k == 2 for k, _ in runs[:next(i for i, r in enumerate(runs) if r[0] == 1)]):
        raise _Unusual  # interleaved, or faces before the first vertex
    verts = [_vertex_block(block) for k, block in runs if k == 1]
    faces = [_face_block(block) for k, block in runs if k == 2]
    V = np.concatenate(verts)
    F = np.concatenate(faces) if faces else np.zeros((0, 3), dtype=np.int64)
    return V, F


def _vertex_block(block):
    """Vertices (k, 3) float64 of a run of ``v`` lines: one ``fromstring`` pass when every line has
    exactly three numbers (twice as fast as ``loadtxt``), else ``loadtxt``'s first three columns."""
    lines = block.count(b"\n") + 1
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a token it cannot parse ends the pass: the count shows it
        vals = np.fromstring(block.replace(b"v", b" ").decode("ascii", "replace"), sep=" ", dtype=np.float64)
    if len(vals) == 3 * lines:
        return vals.reshape(lines, 3)
    return np.loadtxt(io.BytesIO(block), usecols=(1, 2, 3), dtype=np.float64, ndmin=2, comments=None)


def _face_block(block):
    """Triangles (k, 3) int64, 0-based, of a run of ``f`` lines with positive indices."""
    if b"/" in block:
        block = re.sub(rb"/\S*", b"", block)  # f v/vt/vn keeps v
    # each line's "f" becomes a 0 marker: indices are positive here, so the zeros split the lines
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy warns, and stops, at a token it cannot parse
        idx = np.fromstring(block.replace(b"f", b"0").decode("ascii"), sep=" ", dtype=np.int64)
    marker = np.flatnonzero(idx == 0)
    if len(marker) != block.count(b"\n") + 1 or (idx < 0).any():
        raise _Unusual  # an index 0 or negative, or stray text: the line reader decides
    counts = np.diff(np.r_[marker, len(idx)]) - 1
    if (counts < 3).any():
        raise _Unusual
    idx = idx[idx != 0]
    idx -= 1
    if (counts == 3).all():
        return idx.reshape(-1, 3)
    # fan each polygon (0, k, k+1)
    offset = np.r_[0, np.cumsum(counts)[:-1]]
    tri = counts - 2
    base = np.repeat(offset, tri)
    k = np.arange(tri.sum()) - np.repeat(np.cumsum(tri) - tri, tri) + 1
    return np.stack([idx[base], idx[base + k], idx[base + k + 1]], axis=1)


def _read_lines(path, data):
    """One Python step per line: the reference behaviour, with line numbers in its errors."""
    verts, faces = [], []
    for lineno, raw in enumerate(data.split(b"\n"), 1):
        parts = raw.split()
        key = parts[0] if parts else b""
        if key == b"v":
            if len(parts) < 4:
                raise AutobonesError(f"{path}:{lineno}: vertex line needs 3 coordinates")
            verts.append(tuple(_number(float, t, path, lineno) for t in parts[1:4]))
        elif key == b"f":
            idx = []
            for tok in parts[1:]:
                i = _number(int, tok.split(b"/")[0], path, lineno)
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


def _number(kind, token, path, lineno):
    try:
        return kind(token)
    except ValueError:
        what = "a coordinate" if kind is float else "a vertex index"
        raise AutobonesError(f"{path}:{lineno}: {token.decode('latin-1')!r} is not {what}") from None


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
    from ..arguments import finite_output

    finite_output(path, "the OBJ", ("vertices", np.asarray(V, dtype=np.float64)))
    with open(path, "w", encoding="ascii") as fh:
        if comment is not None:
            fh.write(f"# {comment}\n")
        fh.write("".join(f"v {float(a)!r} {float(b)!r} {float(c)!r}\n" for a, b, c in np.asarray(V).tolist()))
        np.savetxt(fh, np.asarray(F) + 1, fmt="f %d %d %d")
