"""Write a skinned mesh as binary glTF 2.0 (.glb).

One mesh, one skin, one joint node per bone. Each joint's local +Y axis points
from its head to its tail (Blender's bone convention), so an importer rebuilds
the bones as placed. The bind pose is the rest pose: with no joint moved, the
skinned mesh is the input mesh exactly (float32 positions as given, in the
input's own frame and units).

The container is small enough to write directly with numpy, struct and json;
tests read it back with two independent libraries (pygltflib, trimesh), the
Khronos validator and Blender.
"""
from __future__ import annotations

import json
import struct

import numpy as np

FLOAT, UBYTE, USHORT, UINT = 5126, 5121, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963


def top_influences(W, k=4):
    """Keep each vertex's ``k`` largest weights, renormalised in float32.

    Parameters
    ----------
    W : (n, b) float
        Full weights, rows summing to 1.

    Returns
    -------
    joints : (n, k) int
        Bone indices, largest weight first; 0 in unused slots.
    weights : (n, k) float32
        Weights summing to 1 in float32 arithmetic; 0 in unused slots.
    """
    W = np.asarray(W, dtype=np.float64)
    n, b = W.shape
    kk = min(k, b)
    idx = np.argsort(-W, axis=1, kind="stable")[:, :kk]
    w = np.take_along_axis(W, idx, axis=1)
    w = w / np.maximum(w.sum(axis=1, keepdims=True), 1e-300)
    w[w < 1e-6] = 0.0  # negligible influences would only cost skinning time
    w = (w / w.sum(axis=1, keepdims=True)).astype(np.float32)
    # put the float32 rounding residue on the largest weight so sums are exact
    w[:, 0] += np.float32(1.0) - w.sum(axis=1, dtype=np.float32)
    idx = np.where(w > 0, idx, 0)
    joints = np.zeros((n, k), dtype=np.int64)
    weights = np.zeros((n, k), dtype=np.float32)
    joints[:, :kk], weights[:, :kk] = idx, w
    return joints, weights


def _bone_rotations(skeleton):
    """(b, 3, 3) world rotations whose +Y column points head -> tail."""
    out = []
    for h, t in zip(skeleton.heads, skeleton.tails):
        y = t - h
        y = y / np.linalg.norm(y) if np.linalg.norm(y) > 0 else np.array([0.0, 1.0, 0.0])
        ref = np.array([0.0, 0.0, 1.0]) if abs(y[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
        x = np.cross(y, ref)
        x /= np.linalg.norm(x)
        z = np.cross(x, y)
        out.append(np.column_stack([x, y, z]))
    return np.array(out)


def _quaternion(R):
    from scipy.spatial.transform import Rotation

    q = Rotation.from_matrix(R).as_quat()  # x, y, z, w as glTF wants
    return (q * np.sign(q[3] or 1.0)).tolist()


def write_glb(path, V, F, skeleton, W, max_influences=4, extras=None, markers=(), morph_targets=()):
    """Write the skinned mesh to ``path``.

    Parameters
    ----------
    path : str
        Output ``.glb``.
    V : (n, 3) float
        Vertices in the mesh's own frame and units (written as float32).
    F : (m, 3) int
        Triangles.
    skeleton : Skeleton
        Bones in the same frame as ``V``.
    W : (n, b) float
        Weights; the ``max_influences`` largest per vertex are written.
    extras : dict or None
        JSON-serialisable data stored in the asset's ``extras``.
    markers : sequence of (name, bone name, (3,) position)
        Extra named nodes (no mesh, not joints) parented to a bone, so they
        follow it when posed: e.g. muscle origins and insertions.
    morph_targets : sequence of (name, (n, 3) float)
        Optional morph targets (blend shapes): per-vertex POSITION displacements in
        the frame and units of ``V`` (written as float32 with their min/max), named
        in ``meshes[0].extras.targetNames`` (the names Blender, three.js and Babylon
        give the shape keys), default weights 0 so the rest pose is unchanged. glTF
        applies them before skinning. None given: the file is exactly as without them.
    """
    V = np.asarray(V, dtype=np.float32)
    F = np.asarray(F, dtype=np.uint32)
    joints, weights = top_influences(W, max_influences)
    jtype, jdtype = (UBYTE, np.uint8) if len(skeleton) <= 256 else (USHORT, np.uint16)

    R = _bone_rotations(skeleton)
    nodes, ibm = [], []
    for i, name in enumerate(skeleton.names):
        p = skeleton.parents[i]
        if p < 0:
            local_R, local_t = R[i], skeleton.heads[i]
        else:
            local_R = R[p].T @ R[i]
            local_t = R[p].T @ (skeleton.heads[i] - skeleton.heads[p])
        nodes.append({"name": name, "translation": [float(v) for v in local_t], "rotation": _quaternion(local_R)})
        G = np.eye(4)
        G[:3, :3], G[:3, 3] = R[i], skeleton.heads[i]
        ibm.append(np.linalg.inv(G).T.ravel())  # column-major
    for i, p in enumerate(skeleton.parents):
        if p >= 0:
            nodes[p].setdefault("children", []).append(i)
    ibm = np.array(ibm, dtype=np.float32)
    for name, bone, position in markers:
        b = skeleton.index(bone)
        local = R[b].T @ (np.asarray(position, dtype=np.float64) - skeleton.heads[b])
        nodes[b].setdefault("children", []).append(len(nodes))
        nodes.append({"name": name, "translation": [float(v) for v in local]})

    blobs, views, accessors = [], [], []

    def add(array, ctype, atype, target=None, minmax=False):
        data = np.ascontiguousarray(array).tobytes()
        offset = sum(len(b) for b in blobs)
        blobs.append(data + b"\0" * (-len(data) % 4))
        view = {"buffer": 0, "byteOffset": offset, "byteLength": len(data)}
        if target:
            view["target"] = target
        views.append(view)
        acc = {"bufferView": len(views) - 1, "componentType": ctype, "count": int(len(array)), "type": atype}
        if minmax:
            acc["min"] = array.min(axis=0).tolist()
            acc["max"] = array.max(axis=0).tolist()
        accessors.append(acc)
        return len(accessors) - 1

    pos = add(V, FLOAT, "VEC3", ARRAY_BUFFER, minmax=True)
    ind = add(F.ravel(), UINT, "SCALAR", ELEMENT_ARRAY_BUFFER)
    jnt = add(joints.astype(jdtype), jtype, "VEC4", ARRAY_BUFFER)
    wgt = add(weights, FLOAT, "VEC4", ARRAY_BUFFER)
    inv = add(ibm, FLOAT, "MAT4")
    targets, target_names = [], []
    for name, delta in morph_targets:
        delta = np.asarray(delta, dtype=np.float32)
        if delta.shape != V.shape:
            raise ValueError(f"morph target {name!r}: shape {delta.shape}, expected {V.shape}")
        targets.append({"POSITION": add(delta, FLOAT, "VEC3", ARRAY_BUFFER, minmax=True)})
        target_names.append(str(name))

    mesh_node = len(nodes)
    n_joints = len(skeleton)
    roots = [i for i, p in enumerate(skeleton.parents) if p < 0]
    primitive = {"attributes": {"POSITION": pos, "JOINTS_0": jnt, "WEIGHTS_0": wgt}, "indices": ind, "mode": 4}
    mesh = {"name": "head_mesh", "primitives": [primitive]}
    if targets:
        primitive["targets"] = targets
        mesh["weights"] = [0.0] * len(targets)
        mesh["extras"] = {"targetNames": target_names}
    doc = {
        "asset": {"version": "2.0", "generator": "autobones", **({"extras": extras} if extras else {})},
        "scene": 0,
        "scenes": [{"nodes": roots + [mesh_node]}],
        "nodes": nodes + [{"name": "head_mesh", "mesh": 0, "skin": 0}],
        "meshes": [mesh],
        "skins": [{"name": "rig", "joints": list(range(n_joints)), "skeleton": roots[0],
                   "inverseBindMatrices": inv}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": sum(len(b) for b in blobs)}],
    }
    body = b"".join(blobs)
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    total = 12 + 8 + len(js) + 8 + len(body)
    with open(path, "wb") as fh:
        fh.write(struct.pack("<4sII", b"glTF", 2, total))
        fh.write(struct.pack("<I4s", len(js), b"JSON") + js)
        fh.write(struct.pack("<I4s", len(body), b"BIN\0") + body)


def read_glb(path):
    """The JSON document and BIN chunk of a binary glTF file.

    Parameters
    ----------
    path : str
        A ``.glb`` file.

    Returns
    -------
    doc : dict
        The JSON chunk.
    body : bytes
        The binary chunk (empty when there is none).

    Raises ``ValueError`` (with what is wrong) when the file is not a readable binary glTF 2.0.
    """
    with open(path, "rb") as fh:
        data = fh.read()
    if len(data) < 20 or data[:4] != b"glTF":
        raise ValueError("not a binary glTF file (no 'glTF' header)")
    _, version, total = struct.unpack_from("<4sII", data, 0)
    if version != 2:
        raise ValueError(f"glTF version {version}, expected 2")
    off, doc, body = 12, None, b""
    while off + 8 <= min(total, len(data)):
        length, kind = struct.unpack_from("<I4s", data, off)
        chunk = data[off + 8:off + 8 + length]
        if len(chunk) != length:
            raise ValueError("the file is truncated")
        if kind == b"JSON":
            doc = json.loads(chunk)
        elif kind == b"BIN\0":
            body = chunk
        off += 8 + length
    if not isinstance(doc, dict):
        raise ValueError("no JSON chunk")
    return doc, body


def read_accessor(doc, body, index):
    """Accessor ``index`` as a numpy array, (count,) or (count, width): the tightly packed,
    non-sparse accessors :func:`write_glb` writes."""
    acc = doc["accessors"][index]
    view = doc["bufferViews"][acc["bufferView"]]
    dtype = np.dtype({UBYTE: "<u1", USHORT: "<u2", UINT: "<u4", FLOAT: "<f4"}[acc["componentType"]])
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}[acc["type"]]
    if view.get("byteStride") not in (None, dtype.itemsize * width) or "sparse" in acc:
        raise ValueError(f"accessor {index}: interleaved or sparse data is not supported")
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    count = acc["count"] * width
    if start + count * dtype.itemsize > len(body):
        raise ValueError(f"accessor {index} runs past the end of the binary chunk")
    a = np.frombuffer(body, dtype=dtype, count=count, offset=start)
    return a.reshape(acc["count"], width) if width > 1 else a
