"""Write a triangle mesh as binary glTF 2.0 (.glb): skinned (a rig) or static (a posed mesh).

One container writer for both: :func:`glb_bytes` lays out one mesh, its accessors and
one binary buffer; a :class:`Skin` adds joint nodes, ``JOINTS_0``/``WEIGHTS_0`` and the
skin; a static mesh is the same file minus the skin. Each joint's local +Y axis points
from its head to its tail (Blender's bone convention), so an importer rebuilds the bones
as placed, and its +X lies on the head's left-right axis (:func:`bone_rotations`), so
turning a joint about its own axes pitches, twists and tilts it in the head's terms. The
bind pose is the rest pose: with no joint moved, the skinned mesh is the input mesh exactly
(float32 positions as given, in the input's own frame and units).

The container is small enough to write directly with numpy, struct and json;
tests read it back with two independent libraries (pygltflib, trimesh), the
Khronos validator and Blender.
"""
from __future__ import annotations

import json
import struct
from dataclasses import dataclass

import numpy as np

from .jsonable import strict_dumps

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


LATERAL_COS = 0.9  # a bone within ~26 deg of the left-right axis takes its roll from the front instead


def bone_rotations(skeleton, axes=None):
    """(b, 3, 3) rest world rotations of the bones: columns = each joint's local +X, +Y, +Z.

    The convention (Blender's armatures, which FBX and USD pipelines follow): local +Y runs along
    the bone from its head to its tail; the roll puts local +X on the head's left-right axis
    (canonical +X, the subject's left) with its along-the-bone part removed, and +Z = X x Y. So
    every bone that is not sideways has the same sense of "pitch" (about +X: nods the head, tips
    a facial bone), an upright bone twists about +Y (the head turns left/right) and tilts about
    +Z (toward the shoulder), and mirrored bones get mirrored motions from the same angles.
    Taken from the head's own frame, not the file's axes, so the roll is the same for a head
    stored Z-up, Y-up or turned. A bone within ~26 deg of the left-right axis (a cheek bone
    pointing sideways) has no usable left-right direction across it: its +Z is the head's
    front with the along-the-bone part removed and +X = Y x Z.

    Parameters
    ----------
    skeleton : Skeleton
        Heads and tails in the mesh's frame and units.
    axes : (3, 3) float or None
        Rows: the head's canonical +X (subject's left), +Y (up), +Z (front) as unit vectors in
        the mesh's frame (``Frame.turn_axes``); None takes the mesh's own x, y, z.
        A zero-length bone points along +Y of this frame.

    Returns
    -------
    (b, 3, 3) float64, proper rotations (det +1) in the mesh's frame.
    """
    A = np.eye(3) if axes is None else np.asarray(axes, dtype=np.float64)
    A = A / np.linalg.norm(A, axis=1, keepdims=True)
    left, up, front = A
    d = np.asarray(skeleton.tails, dtype=np.float64) - np.asarray(skeleton.heads, dtype=np.float64)
    n = np.linalg.norm(d, axis=1, keepdims=True)
    y = np.where(n > 0, d / np.where(n > 0, n, 1.0), up)
    x = left - (y @ left)[:, None] * y  # the left-right axis across the bone
    z = front - (y @ front)[:, None] * y
    sideways = np.abs(y @ left) > LATERAL_COS
    x = x / np.linalg.norm(x, axis=1, keepdims=True).clip(1e-300)
    z = z / np.linalg.norm(z, axis=1, keepdims=True).clip(1e-300)
    x, z = np.where(sideways[:, None], np.cross(y, z), x), np.where(sideways[:, None], z, np.cross(x, y))
    return np.stack([x, y, z], axis=2)


def _quaternion(R):
    from scipy.spatial.transform import Rotation

    q = Rotation.from_matrix(R).as_quat()  # x, y, z, w as glTF wants
    return (q * np.sign(q[3] or 1.0)).tolist()


@dataclass
class Skin:
    """What a skinned file adds to a static one (see :func:`skin_for`).

    nodes : list of dict
        glTF nodes: one per joint (index = bone index), then the markers.
    roots : list of int
        Joint nodes without a parent (scene roots; the first is the skin's ``skeleton``).
    joints : (n, k) uint8 or uint16
        Bone indices per vertex (``JOINTS_0``), uint16 when there are more than 256 bones.
    weights : (n, k) float32
        Their weights (``WEIGHTS_0``), rows summing to 1.
    inverse_binds : (b, 16) float32
        Inverse bind matrices, column-major.
    """

    nodes: list
    roots: list
    joints: np.ndarray
    weights: np.ndarray
    inverse_binds: np.ndarray


def joint_nodes(skeleton, markers=(), axes=None):
    """glTF nodes of the skeleton and its markers, and the inverse bind matrices.

    Parameters
    ----------
    skeleton : Skeleton
        Bones (heads, tails in the mesh's frame and units; parents before children not required).
    markers : sequence of (name, bone name, (3,) position)
        Extra named nodes parented to a bone, positions in the skeleton's frame.
    axes : (3, 3) float or None
        The head's canonical axes in the skeleton's frame (rows +X left, +Y up, +Z front), which
        set each bone's roll (:func:`bone_rotations`); None: the frame's own x, y, z.

    Returns
    -------
    nodes : list of dict
        One node per bone (local translation and rotation quaternion, ``children``), then
        one per marker (translation in its bone's frame).
    inverse_binds : (b, 16) float32
        Inverse of each bone's world transform (:func:`bone_rotations`: +Y head -> tail, +X the
        head's left-right axis across the bone; origin at the head), column-major as glTF stores MAT4.
    """
    R = bone_rotations(skeleton, axes)
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
    for name, bone, position in markers:
        b = skeleton.index(bone)
        local = R[b].T @ (np.asarray(position, dtype=np.float64) - skeleton.heads[b])
        nodes[b].setdefault("children", []).append(len(nodes))
        nodes.append({"name": name, "translation": [float(v) for v in local]})
    return nodes, np.array(ibm, dtype=np.float32)


def skin_for(skeleton, W, max_influences=4, markers=(), axes=None):
    """The :class:`Skin` binding a mesh to ``skeleton`` with weights ``W`` (n, b) float,
    keeping each vertex's ``max_influences`` largest weights (:func:`top_influences`);
    ``axes``: the head's canonical axes that set the bones' roll (:func:`joint_nodes`)."""
    joints, weights = top_influences(W, max_influences)
    nodes, ibm = joint_nodes(skeleton, markers, axes)
    jdtype = np.uint8 if len(skeleton) <= 256 else np.uint16
    roots = [i for i, p in enumerate(skeleton.parents) if p < 0]
    return Skin(nodes=nodes, roots=roots, joints=joints.astype(jdtype), weights=weights, inverse_binds=ibm)


class GlbBuffer:
    """The binary chunk of a .glb being laid out: one buffer, one view per accessor.

    Each array is appended tightly packed and padded to 4 bytes (glTF's alignment).
    """

    def __init__(self):
        self.blobs, self.views, self.accessors = [], [], []

    def add(self, array, ctype, atype, target=None, minmax=False):
        """Append ``array`` (its bytes as they are) as an accessor; returns the accessor index.

        ``ctype``: glTF component type (FLOAT, UBYTE, USHORT, UINT) matching the array's dtype;
        ``atype``: SCALAR, VEC3, VEC4 or MAT4; ``target``: the view's GPU target, if any;
        ``minmax``: record per-component min and max (required for POSITION).
        """
        data = np.ascontiguousarray(array).tobytes()
        offset = self.byte_length()
        self.blobs.append(data + b"\0" * (-len(data) % 4))
        view = {"buffer": 0, "byteOffset": offset, "byteLength": len(data)}
        if target:
            view["target"] = target
        self.views.append(view)
        acc = {"bufferView": len(self.views) - 1, "componentType": ctype, "count": int(len(array)), "type": atype}
        if minmax:
            acc["min"] = array.min(axis=0).tolist()
            acc["max"] = array.max(axis=0).tolist()
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def byte_length(self):
        """Bytes appended so far, padding included."""
        return sum(len(b) for b in self.blobs)

    def body(self):
        """The BIN chunk's contents."""
        return b"".join(self.blobs)


def pack_glb(doc, body):
    """A binary glTF 2.0 file: 12-byte header, JSON chunk (space-padded), BIN chunk."""
    js = strict_dumps(doc, separators=(",", ":")).encode()  # JSON.parse in a browser rejects NaN
    js += b" " * (-len(js) % 4)
    total = 12 + 8 + len(js) + 8 + len(body)
    return (struct.pack("<4sII", b"glTF", 2, total) + struct.pack("<I4s", len(js), b"JSON") + js
            + struct.pack("<I4s", len(body), b"BIN\0") + body)


def _add_morph_targets(buf, mesh, morph_targets, V):
    """Append the morph targets' POSITION deltas to ``buf`` and list them on ``mesh`` (in place)."""
    targets, target_names = [], []
    for name, delta in morph_targets:
        delta = np.asarray(delta, dtype=np.float32)
        if delta.shape != V.shape:
            raise ValueError(f"morph target {name!r}: shape {delta.shape}, expected {V.shape}")
        targets.append({"POSITION": buf.add(delta, FLOAT, "VEC3", ARRAY_BUFFER, minmax=True)})
        target_names.append(str(name))
    if targets:
        mesh["primitives"][0]["targets"] = targets
        mesh["weights"] = [0.0] * len(targets)
        mesh["extras"] = {"targetNames": target_names}


def glb_bytes(V, F, skin=None, extras=None, morph_targets=(), path=None):
    """The .glb file of one triangle mesh, skinned when ``skin`` is given, as bytes.

    Parameters
    ----------
    V : (n, 3) float
        Vertices in the mesh's own frame and units (written as float32).
    F : (m, 3) int
        Triangles, 0-based (written as uint32).
    skin : Skin or None
        From :func:`skin_for`; None writes a static mesh (one node, no skin).
    extras : dict or None
        JSON-serialisable data stored in the asset's ``extras``.
    morph_targets : sequence of (name, (n, 3) float)
        See :func:`write_glb`.
    path : str or None
        The file the bytes are for, named in the message when a value is not finite.

    AutobonesError when a position, a morph target or a bind matrix is NaN or infinite in float32
    (a finite 1e300 is infinite there): nothing non-finite is ever written.
    """
    from ..arguments import finite_output

    with np.errstate(over="ignore"):  # a value past float32's range is named by the check below, not warned of
        V = np.asarray(V, dtype=np.float32)
        finite_output(path, "the glb", ("positions (float32)", V),
                      *((f"morph target {n} (float32)", np.asarray(d, dtype=np.float32)) for n, d in morph_targets),
                      *(() if skin is None else (("inverse bind matrices", skin.inverse_binds),)))
    F = np.asarray(F, dtype=np.uint32)
    buf = GlbBuffer()
    attributes = {"POSITION": buf.add(V, FLOAT, "VEC3", ARRAY_BUFFER, minmax=True)}
    primitive = {"attributes": attributes, "indices": buf.add(F.ravel(), UINT, "SCALAR", ELEMENT_ARRAY_BUFFER),
                 "mode": 4}
    nodes, roots, skins, mesh_node = [], [], {}, {"name": "head_mesh", "mesh": 0}
    if skin is not None:
        jtype = UBYTE if skin.joints.dtype == np.uint8 else USHORT
        attributes["JOINTS_0"] = buf.add(skin.joints, jtype, "VEC4", ARRAY_BUFFER)
        attributes["WEIGHTS_0"] = buf.add(skin.weights, FLOAT, "VEC4", ARRAY_BUFFER)
        inv = buf.add(skin.inverse_binds, FLOAT, "MAT4")
        nodes, roots, mesh_node["skin"] = skin.nodes, skin.roots, 0
        skins = {"skins": [{"name": "rig", "joints": list(range(len(skin.inverse_binds))), "skeleton": roots[0],
                            "inverseBindMatrices": inv}]}
    mesh = {"name": "head_mesh", "primitives": [primitive]}
    _add_morph_targets(buf, mesh, morph_targets, V)
    doc = {
        "asset": {"version": "2.0", "generator": "autobones", **({"extras": extras} if extras else {})},
        "scene": 0,
        "scenes": [{"nodes": roots + [len(nodes)]}],
        "nodes": nodes + [mesh_node],
        "meshes": [mesh],
        **skins,
        "accessors": buf.accessors,
        "bufferViews": buf.views,
        "buffers": [{"byteLength": buf.byte_length()}],
    }
    return pack_glb(doc, buf.body())


def write_glb(path, V, F, skeleton, W, max_influences=4, extras=None, markers=(), morph_targets=(), axes=None):
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
    axes : (3, 3) float or None
        Rows: the head's canonical +X (subject's left), +Y (up), +Z (front) in the frame of ``V``
        (``Frame.turn_axes``); they set the joints' roll (:func:`bone_rotations`). None: the
        frame's own x, y, z (right for a head stored +Y up, facing +Z).
    """
    data = glb_bytes(V, F, skin=skin_for(skeleton, W, max_influences, markers, axes), extras=extras,
                     morph_targets=morph_targets, path=path)
    with open(path, "wb") as fh:
        fh.write(data)


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
            doc = _json_chunk(chunk)
        elif kind == b"BIN\0":
            body = chunk
        off += 8 + length
    if not isinstance(doc, dict):
        raise ValueError("no JSON chunk")
    return doc, body


def _json_chunk(chunk):
    """The glb's JSON chunk parsed, after the depth scan every other JSON autobones reads has
    (``io/files.py``): nested 100k deep, ``json.loads`` would end in a RecursionError."""
    from .files import MAX_JSON_DEPTH, json_depth

    depth = json_depth(chunk)
    if depth > MAX_JSON_DEPTH:
        raise ValueError(f"its JSON chunk is nested {depth} levels deep, more than the {MAX_JSON_DEPTH} autobones "
                         "reads: a damaged file")
    return json.loads(chunk)


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


def add_animation(doc, body, name, times, channels):
    """The glb ``(doc, body)`` with one more animation (LINEAR keys), as a new ``(doc, body)``.

    Parameters
    ----------
    doc, body
        A glb's JSON dict and BIN chunk (:func:`read_glb`); not modified.
    name : str
        The animation's name.
    times : (f,) float
        Key times in seconds, strictly increasing.
    channels : sequence of (node index, path, values)
        ``path`` "weights" with values (f, t) (one weight per morph target of the node's
        mesh), or "rotation" with (f, 4) unit quaternions ``x, y, z, w`` (the node's local
        rotation), or "translation" with (f, 3).

    Write the result with :func:`pack_glb`.
    """
    buf = GlbBuffer()
    buf.blobs = [bytes(body) + b"\0" * (-len(body) % 4)]
    buf.views, buf.accessors = list(doc.get("bufferViews", [])), list(doc.get("accessors", []))
    t = np.asarray(times, dtype=np.float32)
    inp = buf.add(t, FLOAT, "SCALAR")
    buf.accessors[inp]["min"], buf.accessors[inp]["max"] = [float(t.min())], [float(t.max())]
    samplers, chans = [], []
    from ..arguments import finite_output

    finite_output(None, "the animation", ("key times (float32)", t))
    for node, path, values in channels:
        with np.errstate(over="ignore"):  # named by the check below
            values = np.asarray(values, dtype=np.float32)
        finite_output(None, "the animation", (f"{path} keys of node {node} (float32)", values))
        if len(values) != len(t):
            raise ValueError(f"animation channel {path} of node {node}: {len(values)} keys for {len(t)} times")
        atype = {"weights": "SCALAR", "rotation": "VEC4", "translation": "VEC3"}[path]
        out = buf.add(values.reshape(-1) if path == "weights" else values, FLOAT, atype)
        samplers.append({"input": inp, "output": out, "interpolation": "LINEAR"})
        chans.append({"sampler": len(samplers) - 1, "target": {"node": int(node), "path": path}})
    doc = dict(doc, bufferViews=buf.views, accessors=buf.accessors, buffers=[{"byteLength": buf.byte_length()}])
    doc["animations"] = list(doc.get("animations", [])) + [{"name": name, "samplers": samplers, "channels": chans}]
    return doc, buf.body()
