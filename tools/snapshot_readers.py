"""Readers of the files a rig snapshot holds: binary glTF (parsed by hand), OBJ numbers, mesh vertices.

Used by ``snapshot_compare.py`` (``python tools/rig_snapshot.py compare``); why by hand rather
than through ``autobones.io``: see ``read_glb``.

Dependencies: numpy only.
"""
from __future__ import annotations

import json
import os
import struct

import numpy as np

GLTF_COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
GLTF_TYPES = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}


def read_glb(path):
    """``(gltf_json, [accessor arrays])`` of a binary glTF file (container parsed by hand).

    Deliberately not ``autobones.io.gltf.read_glb``: the checker must not share code with the
    writer it checks, and must read files written by any version of autobones."""
    with open(path, "rb") as fh:
        b = fh.read()
    magic, version, length = struct.unpack_from("<III", b, 0)
    if magic != 0x46546C67:
        raise ValueError(f"{path}: not a GLB file")
    pos, doc, bin_chunk = 12, None, b""
    while pos + 8 <= min(length, len(b)):
        clen, ctype = struct.unpack_from("<II", b, pos)
        chunk = b[pos + 8:pos + 8 + clen]
        if ctype == 0x4E4F534A:
            doc = json.loads(chunk.decode("utf-8"))
        elif ctype == 0x004E4942:
            bin_chunk = chunk
        pos += 8 + clen
    arrays = []
    for acc in doc.get("accessors", []):
        dt = np.dtype(GLTF_COMPONENTS[acc["componentType"]]).newbyteorder("<")
        k, n = GLTF_TYPES[acc["type"]], acc["count"]
        a = np.zeros((n, k), dtype=dt)
        if "bufferView" in acc:
            bv = doc["bufferViews"][acc["bufferView"]]
            if bv.get("buffer", 0) != 0:
                raise ValueError(f"{path}: external buffers are not supported")
            start = bv.get("byteOffset", 0) + acc.get("byteOffset", 0)
            stride = bv.get("byteStride") or k * dt.itemsize
            if stride == k * dt.itemsize:
                a = np.frombuffer(bin_chunk, dtype=dt, count=n * k, offset=start).reshape(n, k).copy()
            else:
                rows = [np.frombuffer(bin_chunk, dtype=dt, count=k, offset=start + i * stride) for i in range(n)]
                a = np.array(rows, dtype=dt).reshape(n, k)
        if "sparse" in acc:
            sp = acc["sparse"]
            ibv, vbv = doc["bufferViews"][sp["indices"]["bufferView"]], doc["bufferViews"][sp["values"]["bufferView"]]
            idt = np.dtype(GLTF_COMPONENTS[sp["indices"]["componentType"]]).newbyteorder("<")
            idx = np.frombuffer(bin_chunk, dtype=idt, count=sp["count"],
                                offset=ibv.get("byteOffset", 0) + sp["indices"].get("byteOffset", 0))
            val = np.frombuffer(bin_chunk, dtype=dt, count=sp["count"] * k,
                                offset=vbv.get("byteOffset", 0) + sp["values"].get("byteOffset", 0))
            a[idx.astype(np.int64)] = val.reshape(-1, k)
        arrays.append(a)
    return doc, arrays


def glb_positions(path):
    doc, arrays = read_glb(path)
    for mesh in doc.get("meshes", []):
        for prim in mesh.get("primitives", []):
            if "POSITION" in prim.get("attributes", {}):
                return arrays[prim["attributes"]["POSITION"]].astype(np.float64)
    return None


def read_obj(path):
    """``(v (n, 3) float64, f list of int tuples)``: numbers only, comments and other lines ignored."""
    V, F = [], []
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            if line.startswith("v "):
                V.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                F.append(tuple(int(t.split("/")[0]) for t in line.split()[1:]))
    return np.array(V, dtype=np.float64).reshape(-1, 3), F


def mesh_vertices(path):
    ext = os.path.splitext(path)[1].lower()
    if ext == ".obj":
        return read_obj(path)[0]
    if ext == ".glb":
        return glb_positions(path)
    if ext == ".npz":
        with np.load(path, allow_pickle=False) as z:
            return z["vertices"].astype(np.float64) if "vertices" in z.files else None
    return None


def bbox_diagonal(V):
    if V is None or len(V) == 0:
        return None
    V = np.asarray(V, dtype=np.float64)
    return float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
