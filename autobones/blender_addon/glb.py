"""Read what the add-on needs from a glb written by autobones: joints, their rest frames, morph targets.

Beyond the papers: Blender's glTF importer would make a second object (and re-aim the bones unless
told not to), while the result must land on the user's own mesh, so the add-on reads the few parts
it needs itself. The layout is the one :func:`autobones.io.gltf.glb_bytes` writes (and
:mod:`autobones.export.source` reads): one joint node per bone in ``skins[0].joints``, inverse bind
matrices, morph targets as POSITION deltas named in ``meshes[0].extras.targetNames``. Everything is
in the rig's input frame and units, which is the Blender mesh's own (local) frame here.

Only numpy and the standard library: this runs inside Blender's Python.
"""
import json
import struct

import numpy as np

_DTYPES = {5121: "<u1", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


class GlbError(ValueError):
    """The file is not a glb this add-on can read (the message says why)."""


def read_glb(path):
    """(JSON document, BIN chunk bytes) of a binary glTF file.

    Raises GlbError when the file is not a binary glTF.
    """
    with open(path, "rb") as fh:
        data = fh.read()
    if len(data) < 12 or data[:4] != b"glTF":
        raise GlbError(f"{path}: not a binary glTF file")
    off, doc, body = 12, None, b""
    while off + 8 <= len(data):
        length, kind = struct.unpack_from("<I4s", data, off)
        chunk = data[off + 8:off + 8 + length]
        if kind == b"JSON":
            doc = json.loads(chunk)
        elif kind == b"BIN\0":
            body = chunk
        off += 8 + length
    if doc is None:
        raise GlbError(f"{path}: the glb has no JSON chunk")
    return doc, body


def accessor(doc, body, index):
    """Accessor ``index`` as an (count, width) or (count,) numpy array (dense accessors only)."""
    acc = doc["accessors"][index]
    if "sparse" in acc or "bufferView" not in acc:
        raise GlbError("sparse or view-less accessors are not read by the add-on")
    view = doc["bufferViews"][acc["bufferView"]]
    dtype = np.dtype(_DTYPES[acc["componentType"]])
    width = _WIDTH[acc["type"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    stride = view.get("byteStride", 0) or dtype.itemsize * width
    count = acc["count"]
    rows = np.ndarray((count, width), dtype=dtype, buffer=body, offset=start, strides=(stride, dtype.itemsize))
    rows = np.array(rows)  # own the memory: the BIN chunk is dropped after reading
    return rows if width > 1 else rows[:, 0]


def read_rig_glb(path):
    """The joints and morph targets of an autobones glb.

    Parameters
    ----------
    path : str
        A ``.glb`` written by autobones (``place``, ``transfer``).

    Returns
    -------
    dict
        ``joint_names`` (list of str, skin order = the rig's bone order), ``parents`` (list of int,
        -1 for a root), ``world`` ((b, 4, 4) float64: each joint's rest frame in the rig's input frame
        and units, column vectors; its +Y runs along the bone, +X across the head),
        ``vertex_count`` (int), ``morph_names`` (list of str) and ``morph_deltas`` ((k, n, 3) float32
        POSITION deltas, input units).

    Raises GlbError when the file has no skin or mesh.
    """
    doc, body = read_glb(path)
    try:
        skin = doc["skins"][0]
        prim = doc["meshes"][0]["primitives"][0]
    except (KeyError, IndexError):
        raise GlbError(f"{path}: no skin or mesh in the glb") from None
    joints = list(skin["joints"])
    nodes = doc["nodes"]
    parent_of = {c: i for i, n in enumerate(nodes) for c in n.get("children", [])}
    parents = [joints.index(parent_of[j]) if parent_of.get(j) in joints else -1 for j in joints]
    # the joint's rest frame in mesh space is the inverse of its inverse bind matrix (column-major)
    ibm = accessor(doc, body, skin["inverseBindMatrices"]).astype(np.float64).reshape(-1, 4, 4)
    world = np.linalg.inv(np.transpose(ibm, (0, 2, 1)))
    names = (doc["meshes"][0].get("extras") or {}).get("targetNames") or []
    targets = prim.get("targets") or []
    n = int(doc["accessors"][prim["attributes"]["POSITION"]]["count"])
    deltas = np.zeros((len(targets), n, 3), np.float32)
    for k, target in enumerate(targets):
        deltas[k] = accessor(doc, body, target["POSITION"])
    morph_names = [str(names[k]) if k < len(names) else f"target_{k}" for k in range(len(targets))]
    return {"joint_names": [str(nodes[j].get("name", f"joint_{j}")) for j in joints], "parents": parents,
            "world": world, "vertex_count": n, "morph_names": morph_names, "morph_deltas": deltas}
