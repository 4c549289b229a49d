"""Tests for autobones.io.gltf through clients that are not our writer.

The ``.glb`` written by ``Rig.save`` is read back by pygltflib (a second glTF library;
accessors decoded here with numpy), by trimesh, checked by the Khronos glTF validator
(node, ``tools/gltf-validator``) and imported into Blender 3.4 (``tests/blender_check.py``),
on real heads from ``../shared/data``: LeePerrySmith (one welded surface), the ICT
neutral head (56 parts: eyes, teeth, ...) and the unwelded low-poly robot head.

Node and Blender are required: when either is missing the tests fail with the command
that installs it, they do not skip.
"""
import json
import math
import shutil
import subprocess
import warnings
from pathlib import Path

import numpy as np
import pygltflib
import pytest
import trimesh

import autobones
from autobones.io.gltf import top_influences

from shared_data import run_blender_check

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
MESHES = {
    "lps": DATA / "misc" / "LeePerrySmith.obj",
    "ict": DATA / "ict" / "generic_neutral_mesh.obj",
    "robot": DATA / "misc" / "robot_head_neutral.obj",
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
