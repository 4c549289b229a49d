"""``autobones export``: a saved rig as USD (UsdSkel, usd-core) and FBX (Blender run headless).

USD: the stage passes USD's own validators (the validation framework that replaced
``UsdUtils.ComplianceChecker``), reads back with the rig's joints, every weight and the morph
targets, and USD's own skinning (``UsdSkel`` skinning query, ``BakeSkinning``) of posed joints
reproduces the project's linear blend skinning (``expressions.bones.blend_bones``) of the same
joint motions to 1e-5 of the head size. FBX: written by Blender and re-imported by Blender, the
bones, vertex groups (all influences) and shape keys match the rig.

Rigs: the built-in default head transferred (5 bones, one morph target per AU, muscles) and placed
(18 bones, up to 12 influences per vertex), both made in a few seconds. usd-core and Blender
are required: when either is missing the tests fail with what to install, they do not skip.
"""
import os
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import autobones
from autobones.errors import AutobonesError
from autobones.expressions.bones import blend_bones, bone_transforms
from autobones.expressions.definitions import load_expressions
from autobones.io.gltf import FLOAT, pack_glb, read_accessor, read_glb
from autobones.rig import sidecar_paths

try:
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdSkel
except ImportError as exc:  # never skip: the test extra installs usd-core
    raise ImportError(f"usd-core is missing ({exc}); install it with: pip install -e '.[test]'") from None

from autobones.export.source import read_rig_source
from autobones.export.usd import (all_influences, guess_meters_per_unit, joint_paths, unique_identifiers,
                                  write_animation, write_usd)
from autobones.export.usd_file import validate_stage

ROOT = Path(__file__).resolve().parents[1]
TOL = 1e-5  # of the head size
N_AUS = len(load_expressions()["action_units"])   # one morph target per AU


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """name -> glb path: ``transferred`` (default head, AU morph targets) and ``placed`` (default head,
    medium density: many influences per vertex), each saved once per module."""
    folder = tmp_path_factory.mktemp("export")
    cache = {}

    def get(name):
        if name not in cache:
            path = folder / f"{name}.glb"
            if name == "transferred":
                rig = autobones.transfer(None, ROOT / "generic_rig" / "default_head.landmarks.json")
                rig.save(path, expressions=True)
            else:
                autobones.place(None, density="medium").save(path)
            cache[name] = path
        return cache[name]

    return get


def _stage(path):
    stage = Usd.Stage.Open(str(path))
    assert stage, f"{path}: USD cannot open it"
    return stage


def _dense_weights(mesh_prim, b):
    binding = UsdSkel.BindingAPI(mesh_prim)
    ip, wp = binding.GetJointIndicesPrimvar(), binding.GetJointWeightsPrimvar()
    k = ip.GetElementSize()
    assert wp.GetElementSize() == k and ip.GetInterpolation() == UsdGeom.Tokens.vertex
    idx = np.array(ip.Get(), dtype=np.int64).reshape(-1, k)
    w = np.array(wp.Get(), dtype=np.float64).reshape(-1, k)
    W = np.zeros((len(idx), b))
    np.add.at(W, (np.repeat(np.arange(len(idx)), k), idx.ravel()), w.ravel())
    return W, k


def _posed_points(stage, time=0.0):
    """USD's own linear blend skinning of /Rig/Mesh at ``time`` (skinning query, no blend shapes)."""
    cache = UsdSkel.Cache()
    root = UsdSkel.Root(stage.GetPrimAtPath("/Rig"))
    cache.Populate(root, Usd.PrimDefaultPredicate)
    skel = UsdSkel.Skeleton(stage.GetPrimAtPath("/Rig/Skeleton"))
    xf = cache.GetSkelQuery(skel).ComputeSkinningTransforms(Usd.TimeCode(time))
    mesh = stage.GetPrimAtPath("/Rig/Mesh")
    skq = cache.GetSkinningQuery(mesh)
    pts = mesh.GetAttribute("points").Get()
    assert skq.ComputeSkinnedPoints(xf, pts, Usd.TimeCode(time))
    return np.array(pts, dtype=np.float64)


def _baked_points(stage, time=0.0):
    """The points ``UsdSkel.BakeSkinning`` writes at ``time`` (blend shapes, then skinning), baked on an
    anonymous copy of the stage (the bake turns the SkelRoot into an Xform)."""
    layer = Sdf.Layer.CreateAnonymous(".usda")
    layer.TransferContent(stage.GetRootLayer())
    copy = Usd.Stage.Open(layer)
    assert UsdSkel.BakeSkinning(UsdSkel.Root(copy.GetPrimAtPath("/Rig")), Gf.Interval(time, time))
    return np.array(copy.GetPrimAtPath("/Rig/Mesh").GetAttribute("points").Get(Usd.TimeCode(time)), dtype=np.float64)


def _pose_as_animation(stage, src, deform, shapes=None, weights=None):
    """Bind a one-frame SkelAnimation (time 0) in which every joint's world transform is its rest
    transform followed by ``deform`` (b, 4, 4) (column vectors, the rig's frame)."""
    posed = deform @ src.world
    local = posed.copy()
    for k, p in enumerate(src.parents):
        if p >= 0:
            local[k] = np.linalg.inv(posed[p]) @ posed[k]
    scale = np.linalg.norm(local[:, :3, :3], axis=1)
    rot = Rotation.from_matrix(local[:, :3, :3] / scale[:, None, :]).as_quat()
    skel = UsdSkel.Skeleton(stage.GetPrimAtPath("/Rig/Skeleton"))
    write_animation(stage, "/Rig/Pose", list(skel.GetJointsAttr().Get()), [0.0], local[None, :, :3, 3], rot[None],
                    scale[None], shapes, None if weights is None else np.asarray(weights)[None])
    UsdSkel.BindingAPI.Apply(skel.GetPrim()).CreateAnimationSourceRel().SetTargets(["/Rig/Pose"])


def _input_frame(frame, moves, b):
    """(b, 4, 4) world deformations in the rig's input frame from the canonical ``moves`` of
    :func:`bone_transforms` (bone -> (R, t) on canonical points; identity for bones not moved)."""
    Rf, o, s = frame.rotation, frame.origin, frame.size
    D = np.repeat(np.eye(4)[None], b, axis=0)
    for j, (Rc, tc) in moves.items():
        Ri = Rf.T @ Rc @ Rf
        D[j, :3, :3], D[j, :3, 3] = Ri, o - Ri @ o + s * Rf.T @ tc
    return D


def _rewrite_glb(src_glb, dst_glb, edit):
    """Copy a saved rig to ``dst_glb`` (sidecars too) with its glTF document changed by ``edit(doc, add)``,
    ``add(array, atype)`` appending a float32 accessor and returning its index."""
    doc, body = read_glb(src_glb)
    body = bytearray(body)

    def add(array, atype):
        a = np.ascontiguousarray(array, dtype=np.float32)
        body.extend(b"\0" * (-len(body) % 4))
        doc["bufferViews"].append({"buffer": 0, "byteOffset": len(body), "byteLength": a.nbytes})
        body.extend(a.tobytes())
        doc["accessors"].append({"bufferView": len(doc["bufferViews"]) - 1, "componentType": FLOAT,
                                 "count": int(len(a)), "type": atype,
                                 **({"min": [float(a.min())], "max": [float(a.max())]} if atype == "SCALAR" else {})})
        return len(doc["accessors"]) - 1

    edit(doc, add)
    body.extend(b"\0" * (-len(body) % 4))
    doc["buffers"][0]["byteLength"] = len(body)
    Path(dst_glb).write_bytes(pack_glb(doc, bytes(body)))
    for a, b in zip(sidecar_paths(src_glb), sidecar_paths(dst_glb)):
        shutil.copyfile(a, b)
    return dst_glb


# --------------------------------------------------------------------------- USD: what the stage holds

@pytest.mark.parametrize("name", ["transferred", "placed"])
def test_usd_passes_usd_validation_and_reads_back_the_rig(saved, name, tmp_path):
    glb = saved(name)
    out = tmp_path / f"{name}.usda"
    result = write_usd(glb, out)
    assert out.is_file() and result["path"] == str(out)
    findings = validate_stage(str(out))
    assert not [f for f in findings if f[0] == "Error"], findings
    assert findings == result["validation"]
    rig = autobones.load_rig(glb)
    src = read_rig_source(glb)
    stage = _stage(out)
    assert UsdGeom.GetStageUpAxis(stage) == "Y" and UsdGeom.GetStageMetersPerUnit(stage) == 1.0  # +y, metres
    assert stage.GetDefaultPrim().GetPath() == "/Rig" and stage.GetDefaultPrim().IsA(UsdSkel.Root)

    skel = UsdSkel.Skeleton(stage.GetPrimAtPath("/Rig/Skeleton"))
    joints = list(skel.GetJointsAttr().Get())
    assert list(skel.GetJointNamesAttr().Get()) == rig.skeleton.names
    assert [j.rsplit("/", 1)[-1] for j in joints] == rig.skeleton.names  # the bone names are identifiers already
    for j, p in zip(joints, rig.skeleton.parents):  # the path is the hierarchy
        assert (j.rsplit("/", 1)[0] if "/" in j else None) == (joints[p] if p >= 0 else None)
    assert not any("muscle" in j for j in joints) and len(joints) == len(rig.skeleton)  # markers are no joints
    # bind = the glb's bind pose: USD's row-vector matrices are the inverses of glTF's inverseBindMatrices
    doc, body = read_glb(glb)
    ibm = read_accessor(doc, body, doc["skins"][0]["inverseBindMatrices"]).reshape(-1, 4, 4)
    bind = np.array([np.array(m) for m in skel.GetBindTransformsAttr().Get()])
    assert np.abs(np.linalg.inv(bind) - ibm).max() < 1e-5
    assert np.allclose(bind[:, 3, :3], rig.skeleton.heads, atol=1e-9)  # joint origins at the bone heads
    topo = UsdSkel.Topology(skel.GetJointsAttr().Get())
    rest = [np.array(m) for m in skel.GetRestTransformsAttr().Get()]
    for k, p in enumerate(topo.GetParentIndices()):  # rest composed = bind
        world = rest[k] if p < 0 else rest[k] @ bind[p]
        assert np.abs(world - bind[k]).max() < 1e-9

    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Rig/Mesh"))
    assert np.array_equal(np.array(mesh.GetPointsAttr().Get()), rig.vertices.astype(np.float32))
    assert np.array_equal(np.array(mesh.GetFaceVertexIndicesAttr().Get()).reshape(-1, 3), rig.faces)
    assert mesh.GetSubdivisionSchemeAttr().Get() == "none"
    W, k = _dense_weights(mesh.GetPrim(), len(rig.skeleton))
    assert k == int((rig.weights > 0).sum(axis=1).max())  # every influence, not four
    assert np.abs(W.sum(axis=1) - 1.0).max() < 1e-6
    assert np.abs(W - rig.weights).max() < 1e-6
    binding = UsdSkel.BindingAPI(mesh.GetPrim())
    assert binding.GetGeomBindTransformAttr().Get() == Gf.Matrix4d(1.0)
    assert [str(t) for t in binding.GetSkeletonRel().GetTargets()] == ["/Rig/Skeleton"]
    labels = np.array(UsdGeom.PrimvarsAPI(mesh).GetPrimvar("autobones:label").Get())
    assert np.array_equal(labels, rig.labels)

    # blend shapes: every morph target, its name and its offsets
    names = list(binding.GetBlendShapesAttr().Get() or [])
    targets = binding.GetBlendShapeTargetsRel().GetTargets()
    assert len(names) == len(targets) == len(src.morph_targets) == (N_AUS if name == "transferred" else 0)
    for shape, path, (orig, delta) in zip(names, targets, src.morph_targets):
        bs = UsdSkel.BlendShape(stage.GetPrimAtPath(path))
        assert shape == path.name == orig and bs.GetPrim().GetCustomDataByKey("autobones:name") == orig
        dense = np.zeros_like(delta)
        dense[np.array(bs.GetPointIndicesAttr().Get(), dtype=np.int64)] = np.array(bs.GetOffsetsAttr().Get())
        assert np.array_equal(dense, delta)

    data = stage.GetDefaultPrim().GetCustomDataByKey("autobones")
    assert data["frame"]["head_size"] == rig.frame.size and data["source"] == glb.name
    if name == "transferred":
        assert set(data["landmarks"]) == set(rig.landmarks)
        for lm, p in rig.landmarks.items():
            assert np.allclose(np.array(data["landmarks"][lm]), p, atol=0)
        assert set(data["muscles"]) == {m["name"] for m in rig.muscles}
        m0 = rig.muscles[0]
        assert np.allclose(np.array(data["muscles"][m0["name"]]["origin"]), m0["origin"], atol=0)
        assert set(data["muscle_markers"]) == {f"muscle/{m['name']}/{e}" for m in rig.muscles
                                               for e in ("origin", "insertion")}


def test_every_influence_is_kept_where_the_glb_keeps_four(saved, tmp_path):
    glb = saved("placed")
    rig = autobones.load_rig(glb)
    n_max = int((rig.weights > 0).sum(axis=1).max())
    assert n_max > 4, "the test needs a rig with more than four influences on some vertex"
    idx, w = all_influences(rig.weights)
    assert idx.shape == (len(rig.vertices), n_max) and w.dtype == np.float32
    assert np.all(np.diff(w, axis=1) <= 0)  # largest first, zeros padded at the end
    assert np.all(idx[w == 0] == 0)


@pytest.mark.parametrize("suffix", [".usdc", ".usd", ".usdz"])
def test_binary_and_package_files_hold_the_same_stage(saved, suffix, tmp_path):
    glb = saved("transferred")
    out = tmp_path / f"rig{suffix}"
    result = write_usd(glb, out)
    assert not [f for f in result["validation"] if f[0] == "Error"], result["validation"]
    stage = _stage(out)
    ref = _stage(write_usd(glb, tmp_path / "ref.usda")["path"])
    for path in ("/Rig/Skeleton", "/Rig/Mesh"):
        for attr in ref.GetPrimAtPath(path).GetAttributes():
            assert stage.GetPrimAtPath(path).GetAttribute(attr.GetName()).Get() == attr.Get(), (path, attr.GetName())
    if suffix != ".usda":
        assert out.read_bytes()[:8] != b"#usda 1."
    assert sorted(os.listdir(tmp_path)) == sorted(["ref.usda", f"rig{suffix}"])  # no temporaries left


# --------------------------------------------------------------------------- USD: skinning

@pytest.mark.parametrize("name", ["transferred", "placed"])
def test_usd_skinning_reproduces_the_projects_posed_vertices(saved, name, tmp_path):
    """Head turned, neck turned, jaw open, eyes aimed (transferred) or every joint turned (placed), posed
    by the project's joint code (bone_transforms / blend_bones, linear blend skinning with the rig's
    weights) and by USD's own skinning of the same joint motions in a one-frame SkelAnimation."""
    glb = saved(name)
    out = write_usd(glb, tmp_path / "pose.usda")["path"]
    src = read_rig_source(glb)
    rig, frame = src.rig, src.rig.frame
    names = rig.skeleton.names
    pivots = frame.to_canonical(rig.skeleton.heads)
    if name == "transferred":
        moves = bone_transforms(names, pivots, 20.0, (15.0, 5.0), None, (10.0, 25.0, -5.0), (5.0, -10.0, 0.0))
    else:  # every joint turned about its own pivot, 5..30 degrees, random axes
        rng = np.random.default_rng(0)
        moves = {}
        for j in range(len(names)):
            R = Rotation.from_rotvec(rng.normal(size=3) / 3.0 * np.radians(rng.uniform(5, 30))).as_matrix()
            moves[j] = (R, pivots[j] - R @ pivots[j])
    Vc = frame.to_canonical(rig.vertices)
    d = blend_bones(np.zeros_like(Vc), Vc, rig.weights, moves)
    expected = rig.vertices + (d * frame.size) @ frame.rotation
    moved = np.linalg.norm(expected - rig.vertices, axis=1).max() / frame.size
    assert moved > 0.05  # a real pose, not the rest pose

    stage = _stage(out)
    _pose_as_animation(stage, src, _input_frame(frame, moves, len(names)))
    err_query = np.linalg.norm(_posed_points(stage) - expected, axis=1).max() / frame.size
    err_bake = np.linalg.norm(_baked_points(stage) - expected, axis=1).max() / frame.size
    assert err_query <= TOL, f"USD skinning query vs the project's pose: {err_query:.3g} head sizes"
    assert err_bake <= TOL, f"UsdSkel.BakeSkinning vs the project's pose: {err_bake:.3g} head sizes"


def test_baked_blend_shapes_apply_before_skinning_as_in_gltf(saved, tmp_path):
    glb = saved("transferred")
    out = write_usd(glb, tmp_path / "shapes.usda")["path"]
    src = read_rig_source(glb)
    rig, frame = src.rig, src.rig.frame
    shapes = {"AU12": 0.8, "AU26": 1.0, "AU6": 0.4}
    names = [n for n, _ in src.morph_targets]
    weights = [shapes.get(n, 0.0) for n in names]
    delta = sum(w * d.astype(np.float64) for w, (_, d) in zip(weights, src.morph_targets))
    moves = bone_transforms(rig.skeleton.names, frame.to_canonical(rig.skeleton.heads), 15.0, None, None,
                            (0.0, 20.0, 0.0), None)
    Vc = frame.to_canonical(rig.vertices)
    d = blend_bones((delta @ frame.rotation.T) / frame.size, Vc, rig.weights, moves)  # LBS of V + delta
    expected = rig.vertices + (d * frame.size) @ frame.rotation
    stage = _stage(out)
    _pose_as_animation(stage, src, _input_frame(frame, moves, len(rig.skeleton)), names, weights)
    err = np.linalg.norm(_baked_points(stage) - expected, axis=1).max() / frame.size
    assert np.linalg.norm(delta, axis=1).max() / frame.size > 0.01
    assert err <= TOL, f"{err:.3g} head sizes"


def test_a_glb_animation_becomes_a_bound_skel_animation(saved, tmp_path):
    """A glb with an animation (jaw turning 0 -> 20 -> 0 degrees about its own X axis over 1 s, linear,
    and the AU26 morph weight 0 -> 1 -> 0): the SkelAnimation's skinning at each key and half-way between
    is the rig's linear blend skinning of the glTF-sampled joint transforms."""
    base = saved("transferred")
    src0 = read_rig_source(base)
    j = src0.joint_names.index("jaw")
    doc0, _ = read_glb(base)
    q0 = Rotation.from_quat(doc0["nodes"][j]["rotation"])
    keys = np.array([0.0, 0.5, 1.0])
    angles = np.array([0.0, 20.0, 0.0])
    quats = np.array([(q0 * Rotation.from_euler("x", a, degrees=True)).as_quat() for a in angles])
    au = [n for n, _ in src0.morph_targets].index("AU26")
    k = len(src0.morph_targets)
    mw = np.zeros((3, k))
    mw[1, au] = 1.0

    def edit(doc, add):
        t = add(keys, "SCALAR")
        mesh_node = next(i for i, nd in enumerate(doc["nodes"]) if "mesh" in nd)
        doc["animations"] = [{"name": "jaw open", "samplers": [
            {"input": t, "output": add(quats, "VEC4"), "interpolation": "LINEAR"},
            {"input": t, "output": add(mw.reshape(-1), "SCALAR"), "interpolation": "LINEAR"}],
            "channels": [{"sampler": 0, "target": {"node": j, "path": "rotation"}},
                         {"sampler": 1, "target": {"node": mesh_node, "path": "weights"}}]}]

    glb = _rewrite_glb(base, tmp_path / "animated.glb", edit)
    result = write_usd(glb, tmp_path / "animated.usda")
    assert result["animations"] == 1 and not [f for f in result["validation"] if f[0] == "Error"]
    stage = _stage(result["path"])
    skel = UsdSkel.Skeleton(stage.GetPrimAtPath("/Rig/Skeleton"))
    source = UsdSkel.BindingAPI(skel.GetPrim()).GetAnimationSourceRel().GetTargets()
    assert [str(p) for p in source] == ["/Rig/Animations/jaw_open"]
    anim = UsdSkel.Animation(stage.GetPrimAtPath(source[0]))
    assert anim.GetPrim().GetCustomDataByKey("autobones:name") == "jaw open"
    assert stage.GetTimeCodesPerSecond() == 24 and (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (0, 24)
    src = read_rig_source(glb)
    rig, frame = src.rig, src.rig.frame
    for tc, angle, w in ((12.0, 20.0, 1.0), (6.0, 10.0, 0.5), (24.0, 0.0, 0.0)):
        local = src.local.copy()
        R = Rotation.from_euler("x", angle, degrees=True).as_matrix()
        local[j, :3, :3] = local[j, :3, :3] @ R
        world = local.copy()
        for b, p in enumerate(src.parents):
            if p >= 0:
                world[b] = world[p] @ local[b]
        D = world @ np.linalg.inv(src.world)
        moves = {b: (D[b, :3, :3], D[b, :3, 3]) for b in range(len(D))}
        delta = w * src.morph_targets[au][1].astype(np.float64)
        expected = blend_bones(delta.copy(), rig.vertices, rig.weights, moves) + rig.vertices
        # the bake writes points at the animation's samples only (0, 12, 24); between them, USD's
        # interpolated joint transforms through the skinning query (which applies no blend shapes)
        if tc == 6.0:
            expected = blend_bones(np.zeros_like(rig.vertices), rig.vertices, rig.weights, moves) + rig.vertices
            err = np.linalg.norm(_posed_points(stage, tc) - expected, axis=1).max() / frame.size
        else:
            err = np.linalg.norm(_baked_points(stage, tc) - expected, axis=1).max() / frame.size
        assert err <= TOL, f"time code {tc}: {err:.3g} head sizes"
        weights = dict(zip(anim.GetBlendShapesAttr().Get(), anim.GetBlendShapeWeightsAttr().Get(tc)))
        assert abs(weights["AU26"] - w) < 1e-6


def test_names_that_are_not_usd_identifiers_are_made_valid_and_kept(saved, tmp_path):
    base = saved("transferred")

    def edit(doc, add):
        names = doc["meshes"][0]["extras"]["targetNames"]
        names[0], names[1] = "mouth open-1", "9 lives"

    glb = _rewrite_glb(base, tmp_path / "odd.glb", edit)
    result = write_usd(glb, tmp_path / "odd.usda")
    assert not [f for f in result["validation"] if f[0] == "Error"]
    stage = _stage(result["path"])
    binding = UsdSkel.BindingAPI(stage.GetPrimAtPath("/Rig/Mesh"))
    targets = binding.GetBlendShapeTargetsRel().GetTargets()
    assert [t.name for t in targets[:2]] == ["mouth_open_1", "_9_lives"]
    kept = [stage.GetPrimAtPath(t).GetCustomDataByKey("autobones:name") for t in targets[:2]]
    assert kept == ["mouth open-1", "9 lives"]
    assert list(binding.GetBlendShapesAttr().Get())[:2] == ["mouth_open_1", "_9_lives"]
    # joints: the same rule, siblings kept distinct, the originals in jointNames
    assert joint_paths(["root", "a b", "a-b", "c"], [-1, 0, 0, 1]) == ["root", "root/a_b", "root/a_b_1", "root/a_b/c"]
    assert unique_identifiers(["x", "x", ""]) == ["x", "x_1", "_"]


def test_up_axis_and_units_follow_the_rigs_frame(tmp_path):
    """A head in centimetres with +Z up: upAxis Z, metersPerUnit 0.01; upside down (-y up): upAxis Y
    and a rotation on /Rig that stands the head up. The points stay as the rig has them."""
    V, F = autobones.load_mesh(str(ROOT / "generic_rig" / "default_head.obj"))
    assert guess_meters_per_unit(0.31) == 1.0 and guess_meters_per_unit(31.0) == 0.01
    assert guess_meters_per_unit(310.0) == 0.001 and guess_meters_per_unit(float("nan")) == 1.0
    cases = {"zup_cm": (np.c_[V[:, 0], -V[:, 2], V[:, 1]] * 100.0, "Z", 0.01),
             "upside_down": (np.c_[-V[:, 0], -V[:, 1], V[:, 2]], "Y", 1.0)}
    for name, (W, up, mpu) in cases.items():
        rig = autobones.place((W, F), density="sparse")
        rig.save(tmp_path / f"{name}.glb")
        result = write_usd(tmp_path / f"{name}.glb", tmp_path / f"{name}.usda")
        assert not [f for f in result["validation"] if f[0] == "Error"], result["validation"]
        stage = _stage(result["path"])
        assert UsdGeom.GetStageUpAxis(stage) == up and UsdGeom.GetStageMetersPerUnit(stage) == mpu, name
        mesh = stage.GetPrimAtPath("/Rig/Mesh")
        assert np.array_equal(np.array(mesh.GetAttribute("points").Get()), rig.vertices.astype(np.float32))
        M = np.array(UsdGeom.Xformable(mesh).ComputeLocalToWorldTransform(Usd.TimeCode.Default()))
        up_world = rig.frame.rotation[1] @ M[:3, :3]  # the head's up direction, as the stage shows it
        axis = np.eye(3)[1 if up == "Y" else 2]
        assert up_world @ axis > 0.9, (name, up_world)
    explicit = write_usd(tmp_path / "zup_cm.glb", tmp_path / "explicit.usda", meters_per_unit=0.0254)
    assert explicit["meters_per_unit"] == 0.0254
    with pytest.raises(AutobonesError, match="meters per unit"):
        write_usd(tmp_path / "zup_cm.glb", tmp_path / "bad.usda", meters_per_unit=-1.0)
    assert not (tmp_path / "bad.usda").exists()


# --------------------------------------------------------------------------- FBX through Blender

@pytest.mark.slow
@pytest.mark.parametrize("name", ["transferred", "placed"])
def test_fbx_round_trip_through_blender_keeps_bones_groups_and_shape_keys(saved, name, tmp_path):
    from autobones.export.fbx import check_fbx, write_fbx

    if shutil.which("blender") is None:
        pytest.fail("blender is not on PATH; install it with: apt-get install blender python3-numpy "
                    "(or bash tools/test-setup.sh)")
    glb = saved(name)
    rig = autobones.load_rig(glb)
    out = tmp_path / f"{name}.fbx"
    result = write_fbx(glb, out)
    assert out.is_file() and out.read_bytes()[:18] == b"Kaydara FBX Binary"
    assert result["weights_matched_by"] == "index"
    assert result["influences"] == int((rig.weights > 0).sum(axis=1).max())
    rep = check_fbx(out, glb)
    assert rep["bones_match"] and rep["bones"] == len(rig.skeleton), rep
    assert rep["bone_head_error"] <= TOL, rep
    assert rep["vertex_count_match"] and rep["vertex_error"] <= TOL, rep
    assert rep["weight_error"] <= 1e-6, rep  # every influence, not the glb's four
    assert rep["shape_keys_match"] and rep["shape_keys"] == (N_AUS if name == "transferred" else 0), rep
    if name == "transferred":
        assert rep["shape_key_error"] <= TOL, rep
    assert rep["markers_match"], rep
    assert sorted(os.listdir(tmp_path)) == [out.name]  # no temporaries left


# --------------------------------------------------------------------------- the command line

class _Run:
    def __init__(self, returncode, stdout, stderr):
        self.returncode, self.stdout, self.stderr = returncode, stdout, stderr


@pytest.fixture
def cli(capsys, monkeypatch):
    """Run ``autobones ARGS`` in this process from folder ``cwd``: (exit code, stdout, stderr)."""
    from autobones.cli.main import main

    def run(args, cwd):
        monkeypatch.chdir(cwd)
        capsys.readouterr()
        code = main([str(a) for a in args])
        out = capsys.readouterr()
        return _Run(code, out.out, out.err)

    return run


def test_cli_export_writes_usd_and_says_what_it_wrote(saved, tmp_path, cli):
    out = cli(["export", saved("transferred"), "-o", "head.usdc"], tmp_path)
    assert out.returncode == 0, out.stderr
    line = out.stdout.strip()
    assert "\n" not in line and line.startswith("head.usdc: UsdSkel, 5 joints") and "0 errors" in line
    assert f"{N_AUS} blend shapes" in line and (tmp_path / "head.usdc").is_file()


def test_cli_export_refuses_bad_input_in_one_line_and_writes_nothing(saved, tmp_path, cli):
    import trimesh

    good = saved("transferred")
    lone = tmp_path / "lone.glb"
    shutil.copyfile(good, lone)  # no sidecars beside it
    foreign = tmp_path / "foreign.glb"
    trimesh.creation.box().export(foreign)
    rig_copy = _rewrite_glb(good, tmp_path / "copy.glb", lambda doc, add: None)
    json_side = sidecar_paths(rig_copy)[0]
    link = tmp_path / "same.usda"
    link.symlink_to(rig_copy)
    cases = [
        (["export", good, "-o", "x.obj"], "cannot tell the format"),
        (["export", good, "-o", "x"], "cannot tell the format"),
        (["export", tmp_path / "missing.glb", "-o", "x.usda"], "no such file"),
        (["export", lone, "-o", "x.usda"], "sidecar"),
        (["export", lone, "-o", "x.fbx"], "sidecar"),
        (["export", foreign, "-o", "x.usda"], "not a rig written by autobones"),
        (["export", rig_copy, "-o", rig_copy], "is the input file"),   # said before the suffix (issue #36)
        (["export", rig_copy, "-o", link], "is the input file"),
        (["export", good, "-o", tmp_path / "no_such_folder" / "x.usda"], "does not exist"),
        (["export", good, "-o", "x.fbx", "--meters-per-unit", "0.01"], "USD output only"),
    ]
    before = sorted(os.listdir(tmp_path))
    for args, needle in cases:
        out = cli(args, tmp_path)
        assert out.returncode == 2, (args, out.stdout, out.stderr)
        err = out.stderr.strip()
        assert "\n" not in err and needle in err and err.startswith("autobones export: error:"), (args, err)
        assert out.stdout == ""
        assert sorted(os.listdir(tmp_path)) == before, args  # nothing written, no temporaries
    assert link.is_symlink() and os.path.samefile(link, rig_copy) and Path(json_side).is_file()


def test_cli_without_usd_core_or_blender_says_what_to_install(saved, tmp_path, cli, monkeypatch):
    glb = saved("transferred")
    with monkeypatch.context() as m:
        m.setitem(sys.modules, "pxr", None)  # as if usd-core were not installed
        out = cli(["export", glb, "-o", "x.usda"], tmp_path)
    assert out.returncode == 2 and not (tmp_path / "x.usda").exists()
    assert out.stderr.strip() == ("autobones export: error: USD export needs usd-core: pip install 'autobones[usd]' "
                                  "(or pip install usd-core)")
    monkeypatch.setenv("PATH", str(tmp_path))  # no blender on PATH
    out = cli(["export", glb, "-o", "x.fbx"], tmp_path)
    assert out.returncode == 2 and not (tmp_path / "x.fbx").exists()
    assert out.stderr.strip() == "autobones export: error: FBX export needs Blender (Debian: apt-get install blender)"


def test_library_refuses_an_output_that_is_the_input(saved, tmp_path):
    glb = _rewrite_glb(saved("transferred"), tmp_path / "r.glb", lambda doc, add: None)
    with pytest.raises(AutobonesError, match="USD file ends in"):
        write_usd(glb, glb)
    npz = sidecar_paths(glb)[1]
    before = Path(npz).read_bytes()
    from autobones.export.fbx import write_fbx

    with pytest.raises(AutobonesError, match="ends in .fbx"):
        write_fbx(glb, npz)
    assert Path(npz).read_bytes() == before
