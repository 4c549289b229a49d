"""Tests for autobones.io.gltf through clients that are not our writer.

The ``.glb`` written by ``Rig.save`` is read back by pygltflib (a second glTF library;
accessors decoded here with numpy), by trimesh, checked by the Khronos glTF validator
(node, ``tools/gltf-validator``) and imported into Blender 3.4 (``tests/blender_check.py``),
on real heads from ``tests/data``: LeePerrySmith (one welded surface), the ICT
neutral head (56 parts: eyes, teeth, ...) and the unwelded low-poly robot head.

Node and Blender are required: when either is missing the tests fail with the command
that installs it, they do not skip.
"""
import json
import math
import os
import shutil
import struct
import subprocess
import warnings
from pathlib import Path

import numpy as np
import pygltflib
import pytest
import trimesh

import autobones
from autobones.io.gltf import (FLOAT, UBYTE, UINT, USHORT, GlbBuffer, glb_bytes, joint_nodes, pack_glb,
                               read_glb, skin_for, top_influences)
from autobones.io.gltf import read_accessor as read_glb_accessor
from autobones.io.posed import write_posed_mesh
from autobones.skeleton import Skeleton

from shared_data import data, run_blender_check

REPO = Path(__file__).resolve().parents[1]
MESHES = {
    "lps": data("misc/LeePerrySmith.obj"),
    "ict": data("ict/generic_neutral_mesh.obj"),
    "robot": data("misc/robot_head_neutral.obj"),
}
DENSITY = 4  # facial bones: enough to exercise face_XX joints, small enough to stay fast
VALIDATOR_DIR = REPO / "tools" / "gltf-validator"
VALIDATE_JS = VALIDATOR_DIR / "validate.js"
ROTATION_DEG = 30.0  # what blender_check.py rotates each bone by


@pytest.fixture(scope="module")
def rigged(tmp_path_factory):
    """name -> (rig, glb path), each mesh rigged and saved once per module."""
    cache = {}
    folder = tmp_path_factory.mktemp("gltf_clients")

    def get(name):
        if name not in cache:
            assert MESHES[name].exists(), f"missing test mesh {MESHES[name]}: shared data must sit beside the checkout"
            rig = autobones.place(str(MESHES[name]), density=DENSITY)
            path = folder / f"{name}.glb"
            rig.save(path)
            cache[name] = rig, path
        return cache[name]

    return get


# --------------------------------------------------------------------------- pygltflib

COMPONENT = {5121: "<u1", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


def read_accessor(gltf, index):
    """An accessor's elements as a numpy array ((count,) or (count, width))."""
    acc = gltf.accessors[index]
    view = gltf.bufferViews[acc.bufferView]
    dtype = np.dtype(COMPONENT[acc.componentType])
    width = WIDTH[acc.type]
    assert view.byteStride in (None, dtype.itemsize * width), "interleaved views are not expected"
    data = np.frombuffer(gltf.binary_blob(), dtype=dtype, count=acc.count * width,
                         offset=(view.byteOffset or 0) + (acc.byteOffset or 0))
    return data.reshape(acc.count, width) if width > 1 else data


def node_matrix(node):
    """4x4 local transform of a glTF node (matrix, or T * R * S)."""
    if node.matrix is not None:
        return np.array(node.matrix, dtype=np.float64).reshape(4, 4).T  # column-major
    x, y, z, w = node.rotation if node.rotation is not None else (0.0, 0.0, 0.0, 1.0)
    R = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    M = np.eye(4)
    M[:3, :3] = R * np.asarray(node.scale if node.scale is not None else (1.0, 1.0, 1.0))
    M[:3, 3] = node.translation if node.translation is not None else (0.0, 0.0, 0.0)
    return M


def node_parents(gltf):
    """node index -> parent node index (-1 for scene roots), from ``children`` lists."""
    parent = [-1] * len(gltf.nodes)
    for i, node in enumerate(gltf.nodes):
        for c in node.children or []:
            assert parent[c] == -1, f"node {c} has two parents"
            parent[c] = i
    return parent


def global_matrices(gltf):
    """(nodes, 4, 4) world transforms composed down the node hierarchy."""
    parent = node_parents(gltf)
    G = [None] * len(gltf.nodes)

    def world(i):
        if G[i] is None:
            G[i] = node_matrix(gltf.nodes[i]) if parent[i] < 0 else world(parent[i]) @ node_matrix(gltf.nodes[i])
        return G[i]

    return np.array([world(i) for i in range(len(gltf.nodes))])


@pytest.fixture(scope="module")
def read_back(rigged):
    """name -> (rig, pygltflib document, skinned mesh node index)."""
    cache = {}

    def get(name):
        if name not in cache:
            rig, path = rigged(name)
            gltf = pygltflib.GLTF2().load_binary(str(path))
            skinned = [i for i, n in enumerate(gltf.nodes) if n.mesh is not None]
            assert len(skinned) == 1 and gltf.nodes[skinned[0]].skin == 0
            cache[name] = rig, gltf, skinned[0]
        return cache[name]

    return get


@pytest.mark.parametrize("name", ["lps", "ict", "robot"])
def test_pygltflib_mesh_arrays_equal_the_rig(read_back, name):
    rig, gltf, mesh_node = read_back(name)
    prim = gltf.meshes[gltf.nodes[mesh_node].mesh].primitives[0]
    assert prim.mode in (None, 4)  # triangles
    P = read_accessor(gltf, prim.attributes.POSITION)
    assert P.dtype == np.float32
    np.testing.assert_array_equal(P, np.asarray(rig.vertices).astype(np.float32))
    np.testing.assert_array_equal(read_accessor(gltf, prim.indices).reshape(-1, 3), rig.faces)
    joints, weights = top_influences(rig.weights, 4)
    np.testing.assert_array_equal(read_accessor(gltf, prim.attributes.JOINTS_0), joints)
    W = read_accessor(gltf, prim.attributes.WEIGHTS_0)
    np.testing.assert_array_equal(W, weights)
    assert np.all(W >= 0)
    np.testing.assert_allclose(W.sum(axis=1, dtype=np.float64), 1.0, atol=1e-6)


@pytest.mark.parametrize("name", ["lps", "ict", "robot"])
def test_pygltflib_joint_names_and_hierarchy_reproduce_the_skeleton(read_back, name):
    rig, gltf, mesh_node = read_back(name)
    skin = gltf.skins[0]
    skel = rig.skeleton
    assert [gltf.nodes[j].name for j in skin.joints] == list(skel.names)
    parent = node_parents(gltf)
    joint_of = {node: i for i, node in enumerate(skin.joints)}
    parents = [joint_of[parent[j]] if parent[j] >= 0 else -1 for j in skin.joints]
    assert parents == skel.parents.tolist()
    roots = gltf.scenes[gltf.scene].nodes
    assert skin.skeleton in roots and parent[skin.skeleton] == -1
    assert mesh_node in roots  # a skinned mesh's own transform is ignored: keep it at the root


@pytest.mark.parametrize("name", ["lps", "ict", "robot"])
def test_pygltflib_bind_pose_reproduces_the_vertices(read_back, name):
    """IBMs invert the joints' TRS-chain transforms; bind-pose skinning is the identity."""
    rig, gltf, mesh_node = read_back(name)
    size = rig.frame.size
    skin = gltf.skins[0]
    G = global_matrices(gltf)
    J = G[skin.joints]
    IBM = read_accessor(gltf, skin.inverseBindMatrices).reshape(-1, 4, 4).transpose(0, 2, 1).astype(np.float64)
    assert len(IBM) == len(skin.joints)
    np.testing.assert_allclose(IBM[:, 3], np.tile([0.0, 0.0, 0.0, 1.0], (len(IBM), 1)), atol=0)
    # the joint matrices of the bind pose: global joint transform x inverse bind matrix = identity
    bind = J @ IBM
    np.testing.assert_allclose(bind[:, :3, :3], np.broadcast_to(np.eye(3), bind[:, :3, :3].shape), atol=1e-5)
    np.testing.assert_allclose(bind[:, :3, 3], 0.0, atol=1e-5 * size)
    np.testing.assert_allclose(IBM[:, :3, :3], np.linalg.inv(J)[:, :3, :3], atol=1e-5)
    np.testing.assert_allclose(IBM[:, :3, 3], np.linalg.inv(J)[:, :3, 3], atol=1e-5 * size)
    # joints sit on the bone heads, +Y pointing head -> tail (the writer's stated convention)
    np.testing.assert_allclose(J[:, :3, 3], rig.skeleton.heads, atol=1e-5 * size)
    d = rig.skeleton.tails - rig.skeleton.heads
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    np.testing.assert_allclose(J[:, :3, 1], d, atol=1e-5)
    # linear blend skinning in the bind pose gives back the input vertices
    prim = gltf.meshes[gltf.nodes[mesh_node].mesh].primitives[0]
    P = read_accessor(gltf, prim.attributes.POSITION).astype(np.float64)
    joints = read_accessor(gltf, prim.attributes.JOINTS_0).astype(np.int64)
    weights = read_accessor(gltf, prim.attributes.WEIGHTS_0).astype(np.float64)
    skin_mats = np.linalg.inv(G[mesh_node]) @ J @ IBM  # glTF: the mesh node's transform is undone
    Ph = np.column_stack([P, np.ones(len(P))])
    per_influence = np.einsum("nkij,nj->nki", skin_mats[joints], Ph)[..., :3]
    skinned = np.einsum("nk,nki->ni", weights, per_influence)
    np.testing.assert_allclose(skinned, rig.vertices, atol=1e-5 * size)


# --------------------------------------------------------------------------- trimesh

@pytest.mark.parametrize("name", ["lps", "ict", "robot"])
def test_trimesh_reads_the_same_vertices_and_faces(rigged, name):
    rig, path = rigged(name)
    mesh = trimesh.load(path, force="mesh", process=False)
    np.testing.assert_array_equal(mesh.vertices, np.asarray(rig.vertices).astype(np.float32))
    np.testing.assert_array_equal(mesh.faces, rig.faces)


# --------------------------------------------------------------------------- Khronos validator

SEVERITY = {0: "error", 1: "warning", 2: "info", 3: "hint"}
VALIDATOR_INSTALL = ("install Node.js (apt-get install nodejs npm) and the validator: "
                     f"npm install --prefix {VALIDATOR_DIR.relative_to(REPO)}")


def run_validator(path):
    node = shutil.which("node")
    if node is None:
        pytest.fail(f"node is not on PATH; {VALIDATOR_INSTALL}")
    if not (VALIDATOR_DIR / "node_modules" / "gltf-validator").is_dir():
        pytest.fail(f"the npm package gltf-validator is not installed; {VALIDATOR_INSTALL}")
    out = subprocess.run([node, str(VALIDATE_JS), str(path)], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, f"{VALIDATE_JS} failed ({out.returncode}): {out.stderr.strip()}"
    return json.loads(out.stdout)


@pytest.mark.parametrize("name", ["lps", "ict", "robot"])
def test_khronos_validator_reports_no_errors(rigged, name):
    rig, path = rigged(name)
    report = run_validator(path)
    issues = report["issues"]
    messages = issues["messages"]
    listing = "\n".join(f"  {SEVERITY[m['severity']]} {m['code']} {m.get('pointer', '')}: {m['message']}"
                        for m in messages[:20])
    if len(messages) > 20:
        listing += f"\n  ... {len(messages) - 20} more"
    summary = (f"{name}: validator {report.get('validatorVersion')}: {issues['numErrors']} errors, "
               f"{issues['numWarnings']} warnings, {issues['numInfos']} infos, {issues['numHints']} hints"
               + (f"\n{listing}" if listing else ""))
    assert issues["numErrors"] == 0, summary
    if issues["numWarnings"] or issues["numInfos"]:
        warnings.warn(summary)  # shown in pytest's warnings summary, not a failure
    info = report["info"]
    assert info["hasSkins"] and info["maxInfluences"] == 4, summary
    assert info["totalVertexCount"] == len(rig.vertices) and info["totalTriangleCount"] == len(rig.faces)


# --------------------------------------------------------------------------- Blender



@pytest.fixture(scope="module")
def blender_report(rigged, tmp_path_factory):
    """name -> (rig, report of tests/blender_check.py run in headless Blender)."""
    cache = {}
    folder = tmp_path_factory.mktemp("blender")

    def get(name):
        if name not in cache:
            rig, path = rigged(name)
            cache[name] = rig, run_blender_check(path, folder / f"{name}.json")
        return cache[name]

    return get


@pytest.mark.slow
@pytest.mark.parametrize("name", ["lps", "ict", "robot"])
def test_blender_imports_armature_with_one_vertex_group_per_bone(blender_report, name):
    rig, rep = blender_report(name)
    skel = rig.skeleton
    assert rep["armature"] and rep["mesh_objects"] == 1 and rep["armature_modifier"], rep.get("objects")
    assert rep["bones"] == list(skel.names)
    assert [rep["bone_parents"][n] for n in skel.names] == [skel.names[p] if p >= 0 else None for p in skel.parents]
    # Blender bones start at the joints and, imported with the "BLENDER" bone heuristic, point
    # the way the rig's bones do (their length is the importer's choice)
    heads = np.array([rep["bone_heads"][n] for n in skel.names])
    np.testing.assert_allclose(heads, skel.heads, atol=1e-5 * rig.frame.size)
    tails = np.array([rep["bone_tails"][n] for n in skel.names])
    d_bl, d_rig = tails - heads, skel.tails - skel.heads
    cos = (d_bl * d_rig).sum(1) / np.linalg.norm(d_bl, axis=1) / np.linalg.norm(d_rig, axis=1)
    assert cos.min() > 0.9999, cos
    groups = rep["vertex_groups"]
    assert all(groups[n]["exists"] for n in skel.names) and rep["extra_vertex_groups"] == []
    # a bone with no weighted vertex would be written but useless; the rig never makes one
    joints, weights = top_influences(rig.weights, 4)
    for b, n in enumerate(skel.names):
        assert (groups[n]["vertices"] > 0) == bool(((joints == b) & (weights > 0)).any()), n
    assert rep["unweighted_vertices"] == 0, f"{rep['unweighted_vertices']} of {rep['vertex_count']} vertices"


@pytest.mark.slow
@pytest.mark.parametrize("name", ["lps", "ict", "robot"])
def test_blender_rest_pose_equals_the_input(blender_report, name):
    """The evaluated (armature-deformed) rest mesh sits on the input vertices.

    Blender's importer may drop unused vertices and split or merge others, so its
    vertices are matched to the file's by nearest position (both ways), never by index.
    """
    rig, rep = blender_report(name)
    tol = 1e-5 * rig.frame.size
    rest = rep["rest"]
    assert rest["max_blender_to_file"] <= tol, rest
    assert rest["max_file_to_blender"] <= tol, rest
    assert rep["rest_restored_max_error"] <= tol  # posing and un-posing returns to rest


@pytest.mark.slow
@pytest.mark.parametrize("name", ["lps", "ict", "robot"])
def test_blender_rotating_head_and_neck_moves_the_skin(blender_report, name):
    rig, rep = blender_report(name)
    size = rig.frame.size
    top = np.array(rep["top_vertex"]["position"])
    for bone in ("head", "neck"):
        pose = rep["poses"][bone]
        msg = f"{bone}: {pose}"
        assert pose["max_displacement"] > 0.05 * size, msg
        # vertices no bone of the rotated chain weighs do not move
        assert pose["max_displacement_outside_chain"] <= 1e-5 * size, msg
        # Blender's deformation is linear blend skinning with the imported groups
        assert pose["max_error_vs_lbs"] <= 1e-5 * size, msg
        # the top of the head moves by its chain weight times the rigid rotation about the pivot,
        # which is at most the chord of a 30 degree arc at its distance from the pivot
        chord = 2 * math.sin(math.radians(ROTATION_DEG) / 2) * np.linalg.norm(top - pose["pivot"])
        assert pose["top_chain_weight"] > 0.9, msg
        assert pose["top_displacement"] == pytest.approx(pose["top_chain_weight"] * pose["top_rigid_displacement"],
                                                         rel=1e-4, abs=1e-5 * size), msg
        assert 0.05 * size < pose["top_displacement"] <= chord * (1 + 1e-4), msg


@pytest.mark.slow
@pytest.mark.parametrize("name", ["lps", "ict", "robot"])
def test_blender_rotating_a_facial_bone_moves_vertices_near_it(blender_report, name):
    rig, rep = blender_report(name)
    size = rig.frame.size
    faces = [b for b in rep["poses"] if b.startswith("face_")]
    assert len(faces) == 1, list(rep["poses"])
    pose = rep["poses"][faces[0]]
    msg = f"{faces[0]}: {pose}"
    pivot = np.array(pose["pivot"])
    assert pose["max_displacement"] > 0.01 * size, msg
    assert pose["max_displacement_outside_chain"] <= 1e-5 * size, msg
    assert pose["max_error_vs_lbs"] <= 1e-5 * size, msg
    # the motion is centred near the bone, the top of the head barely moves (the single largest
    # displacement can be a separate part, e.g. the robot's ear, riding its nearest bone rigidly)
    assert np.linalg.norm(np.array(pose["strongly_moved_centroid"]) - pivot) < 0.4 * size, msg
    assert pose["top_displacement"] < 0.25 * pose["max_displacement"], msg


# --------------------------------------------------------------------------- the container writer's parts

def _random_skeleton(rng, n_bones):
    """A random tree of bones (each parent before its children), heads and tails apart."""
    parents = np.array([-1] + [int(rng.integers(0, i)) for i in range(1, n_bones)])
    heads = rng.normal(size=(n_bones, 3))
    tails = heads + rng.normal(size=(n_bones, 3))
    tails[0] = heads[0] + [1.0, 0.0, 0.0]  # a bone along +-X takes its roll from the front in bone_rotations
    return Skeleton([f"b{i}" for i in range(n_bones)], parents, heads, tails)


def test_pack_glb_round_trips_through_read_glb():
    rng = np.random.default_rng(0)
    for n in (0, 4, 8, 400):
        doc = {"asset": {"version": "2.0"}, "x": "é" * int(rng.integers(0, 7))}  # JSON of any length
        body = rng.integers(0, 256, n, dtype=np.uint8).tobytes()
        data = pack_glb(doc, body)
        assert len(data) % 4 == 0 and struct.unpack_from("<I", data, 8)[0] == len(data)
        assert struct.unpack_from("<I", data, 12)[0] % 4 == 0  # the JSON chunk keeps BIN aligned
        assert read_glb_bytes(data) == (doc, body)


def read_glb_bytes(data):
    """read_glb of bytes (through a temporary file)."""
    import tempfile

    with tempfile.NamedTemporaryFile(suffix=".glb", delete=False) as fh:
        fh.write(data)
    try:
        return read_glb(fh.name)
    finally:
        Path(fh.name).unlink()


def test_glb_buffer_aligns_views_and_round_trips_accessors():
    rng = np.random.default_rng(1)
    buf = GlbBuffer()
    arrays = [(rng.integers(0, 255, (5, 4)).astype(np.uint8), UBYTE, "VEC4"),  # 20 bytes
              (rng.integers(0, 9, 3).astype(np.uint32), UINT, "SCALAR"),
              (rng.integers(0, 999, (3, 4)).astype(np.uint16), USHORT, "VEC4"),  # 24 bytes
              (rng.integers(0, 255, (3, 4)).astype(np.uint8), UBYTE, "VEC4"),  # 12 bytes
              (rng.normal(size=(7, 3)).astype(np.float32), FLOAT, "VEC3")]
    indices = [buf.add(a, c, t, minmax=(t == "VEC3")) for a, c, t in arrays]
    assert indices == list(range(len(arrays)))
    body = buf.body()
    assert len(body) == buf.byte_length() and len(body) % 4 == 0
    doc = {"accessors": buf.accessors, "bufferViews": buf.views}
    for i, (a, _, _) in enumerate(arrays):
        assert buf.views[i]["byteOffset"] % 4 == 0
        got = read_glb_accessor(doc, body, i)
        np.testing.assert_array_equal(got.reshape(a.shape), a)
    assert buf.accessors[4]["min"] == arrays[4][0].min(axis=0).tolist()
    assert buf.accessors[4]["max"] == arrays[4][0].max(axis=0).tolist()


def test_joint_nodes_compose_to_the_inverse_bind_matrices_and_place_markers():
    rng = np.random.default_rng(2)
    skel = _random_skeleton(rng, 9)
    markers = [("m0", "b3", rng.normal(size=3)), ("m1", "b0", rng.normal(size=3))]
    nodes, ibm = joint_nodes(skel, markers)
    assert len(nodes) == len(skel) + len(markers) and ibm.shape == (len(skel), 16) and ibm.dtype == np.float32
    gltf = pygltflib.GLTF2(nodes=[pygltflib.Node(**n) for n in nodes])
    G = global_matrices(gltf)
    for b in range(len(skel)):
        inv_bind = ibm[b].reshape(4, 4).T.astype(np.float64)  # column-major
        np.testing.assert_allclose(G[b] @ inv_bind, np.eye(4), atol=1e-5)
        np.testing.assert_allclose(G[b][:3, 1], (skel.tails[b] - skel.heads[b])
                                   / np.linalg.norm(skel.tails[b] - skel.heads[b]), atol=1e-12)  # +Y head -> tail
    for k, (_, bone, position) in enumerate(markers):
        i = len(skel) + k
        assert node_parents(gltf)[i] == skel.index(bone)
        np.testing.assert_allclose(G[i][:3, 3], position, atol=1e-12)


def test_skin_for_joint_index_type_follows_the_bone_count():
    rng = np.random.default_rng(3)
    for n_bones, dtype in ((3, np.uint8), (256, np.uint8), (257, np.uint16)):
        skel = _random_skeleton(rng, n_bones)
        W = rng.random((20, n_bones))
        skin = skin_for(skel, W / W.sum(1, keepdims=True), 4)
        assert skin.joints.dtype == dtype and skin.joints.shape == (20, 4) and skin.roots == [0]
        assert skin.joints.max() < n_bones and np.allclose(skin.weights.sum(1), 1, atol=1e-6)


def test_static_glb_is_the_skinned_file_minus_the_skin():
    rng = np.random.default_rng(4)
    V, F = rng.normal(size=(6, 3)), np.array([[0, 1, 2], [2, 3, 4], [4, 5, 0]])
    skel = _random_skeleton(rng, 2)
    static = read_glb_bytes(glb_bytes(V, F))[0]
    skinned = read_glb_bytes(glb_bytes(V, F, skin=skin_for(skel, np.full((6, 2), 0.5))))[0]
    assert "skins" not in static and static["nodes"] == [{"name": "head_mesh", "mesh": 0}]
    assert static["scenes"] == [{"nodes": [0]}]
    assert static["accessors"] == skinned["accessors"][:2]  # POSITION and indices, the same
    assert static["meshes"][0]["primitives"][0]["attributes"] == {"POSITION": 0}
    assert skinned["nodes"][-1] == {"name": "head_mesh", "mesh": 0, "skin": 0}


# --------------------------------------------------------------------------- the posed (static) .glb

@pytest.fixture(scope="module")
def posed_glb(tmp_path_factory):
    """(V, F, path): the robot head bent like a pose, written as ``autobones pose -o X.glb`` does."""
    V, F = autobones.load_mesh(MESHES["robot"])
    V = V + 0.05 * np.sin(V[:, [1, 2, 0]] / np.ptp(V, axis=0).max() * 7)
    path = tmp_path_factory.mktemp("posed") / "posed.glb"
    write_posed_mesh(path, V, F)
    return V, F, path


def test_posed_glb_arrays_equal_trimesh_export(posed_glb, tmp_path):
    """The posed mesh was written by trimesh before the one container writer: the same arrays."""
    V, F, path = posed_glb
    other = tmp_path / "trimesh.glb"
    other.write_bytes(trimesh.Trimesh(V, F, process=False, validate=False).export(file_type="glb"))
    ours, theirs = (pygltflib.GLTF2().load_binary(str(p)) for p in (path, other))
    pa, pb = ours.meshes[0].primitives[0], theirs.meshes[0].primitives[0]
    np.testing.assert_array_equal(read_accessor(ours, pa.attributes.POSITION),
                                  read_accessor(theirs, pb.attributes.POSITION))
    np.testing.assert_array_equal(read_accessor(ours, pa.indices), read_accessor(theirs, pb.indices))
    np.testing.assert_array_equal(read_accessor(ours, pa.attributes.POSITION), V.astype(np.float32))
    mesh = trimesh.load(path, force="mesh", process=False)
    np.testing.assert_array_equal(mesh.vertices, V.astype(np.float32))
    np.testing.assert_array_equal(mesh.faces, F)
    assert ours.skins == [] and all(n.skin is None for n in ours.nodes)


def test_posed_glb_khronos_validator_reports_no_issues(posed_glb):
    V, F, path = posed_glb
    report = run_validator(path)
    issues = report["issues"]
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"][:5]
    info = report["info"]
    assert not info["hasSkins"] and info["totalVertexCount"] == len(V) and info["totalTriangleCount"] == len(F)


BLENDER_STATIC = """
import json, sys
import bpy
import numpy as np
if "bool" not in vars(np):  # Blender 3.4's importer still uses np.bool, removed in numpy 1.24
    np.bool = bool
glb, out = sys.argv[sys.argv.index("--") + 1:]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=glb)
objs = bpy.context.scene.objects
meshes = [o for o in objs if o.type == "MESH"]
rep = {"meshes": len(meshes), "armatures": sum(o.type == "ARMATURE" for o in objs)}
if meshes:
    o = meshes[0]
    # Blender is Z-up: glTF (x, y, z) comes in as (x, -z, y)
    rep["vertices"] = [[w.x, w.z, -w.y] for w in (o.matrix_world @ v.co for v in o.data.vertices)]
    rep["polygon_sizes"] = [len(p.vertices) for p in o.data.polygons]
with open(out, "w") as fh:
    json.dump(rep, fh)
"""


@pytest.mark.slow
def test_blender_imports_the_posed_glb(posed_glb, tmp_path):
    V, F, path = posed_glb
    blender = shutil.which("blender")
    if blender is None:
        pytest.fail("blender is not on PATH; install it with: apt-get install blender python3-numpy")
    script, out = tmp_path / "static.py", tmp_path / "static.json"
    script.write_text(BLENDER_STATIC)
    # as tests/shared_data.run_blender_check: Blender's own Python, not the one running pytest
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONHOME", "PYTHONPATH")}
    env["PATH"] = str(Path(blender).resolve().parent) + ":" + env.get("PATH", "")
    run = subprocess.run([blender, "-b", "--factory-startup", "--python-exit-code", "1", "-P", str(script),
                          "--", str(path), str(out)], capture_output=True, text=True, timeout=300, env=env)
    assert run.returncode == 0, (run.stdout + run.stderr)[-3000:]
    rep = json.loads(out.read_text())
    assert rep["meshes"] == 1 and rep["armatures"] == 0
    assert rep["polygon_sizes"] == [3] * len(F)
    from scipy.spatial import cKDTree

    B = np.array(rep["vertices"])
    tol = 1e-6 * np.ptp(V, axis=0).max()
    assert cKDTree(B).query(V)[0].max() <= tol and cKDTree(V).query(B)[0].max() <= tol
