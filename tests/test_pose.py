"""Posing saved rigs: autobones.load_rig, AU morph targets in the glb (Rig.save(expressions=...)),
and ``autobones pose`` / ``autobones transfer --expressions`` on the command line.

The morph targets are read back by pygltflib, checked by the Khronos validator and imported
into Blender as shape keys (tests/blender_check.py); the rigs are the built-in default head
transferred (fast) and the ICT identity002 head (a real 27k-vertex head with eyes and teeth).
"""
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pygltflib
import pytest
import trimesh

import autobones
from autobones.errors import AutobonesError
from autobones.expressions.model import load_expressions
from autobones.io.gltf import read_accessor, read_glb
from autobones.expressions.morph_targets import definitions_digest
from autobones.rig import sidecar_paths

from shared_data import ROOT, data, run_blender_check
from test_gltf_clients import read_accessor as pyg_accessor
from test_gltf_clients import run_validator

HEADS = {
    "default": (None, ROOT / "generic_rig" / "default_head.landmarks.json"),
    "ict": (data("ict/identity002.obj"), data("ict/identity002.landmarks.json")),
}
DOC = load_expressions()
AUS = sorted(DOC["action_units"], key=int)
MIXES = ({"au": {12: 0.8, 6: 0.4}, "jaw_deg": 10}, {"expression": "happiness"}, {"expression": "anger"},
         {"au": {26: 1.0}}, {"au": {43: 1.0}}, {"au": {"12L": 1.0}, "gaze": (20, 5)},
         {"expression": {"surprise": 0.5, "fear": 0.5}, "head_deg": (10, 20, 0)})


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """name -> (in-memory rig, glb path saved with one morph target per AU)."""
    folder = tmp_path_factory.mktemp("pose")
    cache = {}

    def get(name):
        if name not in cache:
            rig = autobones.transfer(*HEADS[name])
            glb = folder / f"{name}.glb"
            rig.save(glb, expressions=True)
            cache[name] = rig, glb
        return cache[name]

    return get


def _targets(glb):
    """name -> (n, 3) float32 delta, and the mesh's default weights, read with pygltflib."""
    g = pygltflib.GLTF2().load(str(glb))
    mesh = g.meshes[0]
    names = mesh.extras["targetNames"]
    deltas = {n: pyg_accessor(g, t["POSITION"] if isinstance(t, dict) else t.POSITION)
              for n, t in zip(names, mesh.primitives[0].targets)}
    return deltas, mesh.weights, g


# ------------------------------------------------------------------------------ load_rig


@pytest.mark.parametrize("name", ["default", "ict"])
def test_load_rig_poses_like_the_rig_that_was_saved(saved, name):
    rig, glb = saved(name)
    again = autobones.load_rig(glb)
    assert np.array_equal(again.vertices, rig.vertices) and again.vertices.dtype == np.float64
    assert np.array_equal(again.faces, rig.faces)
    assert again.skeleton.names == rig.skeleton.names
    assert np.allclose(again.skeleton.heads, rig.skeleton.heads, rtol=0, atol=1e-12 * rig.frame.size)
    assert np.abs(again.weights - rig.weights).max() < 1e-6  # saved as float32
    assert np.array_equal(again.labels, rig.labels) and np.array_equal(again.facial_mask, rig.facial_mask)
    assert np.allclose(again.frame.rotation, rig.frame.rotation) and again.frame.size == rig.frame.size
    assert sorted(again.fields) == sorted(rig.fields)
    assert again.extra["muscles"] == json.loads(json.dumps(rig.extra["muscles"]))
    # every AU at 0 is the neutral mesh, exactly
    assert np.array_equal(again.pose(au={a: 0.0 for a in AUS}), again.vertices)
    assert np.array_equal(again.pose(), rig.vertices)
    for kw in MIXES:
        d = np.abs(again.pose(**kw) - rig.pose(**kw)).max()
        moved = np.abs(rig.pose(**kw) - rig.vertices).max()
        assert moved > 1e-3 * rig.frame.size, kw  # the mix does move the face
        assert d < 1e-6 * rig.frame.size, (kw, d)


def test_load_rig_of_a_file_without_float64_vertices_uses_the_glb_positions(saved, tmp_path):
    """A weights.npz without ``vertices`` (written before they were kept): the glb's float32
    positions, and poses that agree with the saved rig to float32 precision."""
    rig, glb = saved("default")
    for src in [glb, *sidecar_paths(glb)]:
        shutil.copy(src, tmp_path / os.path.basename(src))
    npz = tmp_path / os.path.basename(sidecar_paths(glb)[1])
    with np.load(npz) as z:
        arrays = {k: z[k] for k in z.files if k != "vertices"}
    np.savez_compressed(npz, **arrays)
    again = autobones.load_rig(tmp_path / glb.name)
    assert np.array_equal(again.vertices, rig.vertices.astype(np.float32).astype(np.float64))
    assert np.array_equal(again.pose(au={12: 0}), again.vertices)
    for kw in MIXES[:3]:
        assert np.abs(again.pose(**kw) - rig.pose(**kw)).max() < 1e-5 * rig.frame.size, kw


def test_the_sidecar_keeps_the_definitions_the_loaded_rig_poses_with(saved, tmp_path):
    rig, glb = saved("default")
    side = json.loads(open(sidecar_paths(glb)[0]).read())["expressions"]
    assert side["format"] == DOC["format"] == "autobones-expressions/1"
    assert side["definitions"] == DOC and side["sha256"] == definitions_digest(DOC)
    # change AU12 in the copy's sidecar: the loaded rig follows its sidecar, not the package file
    for src in [glb, *sidecar_paths(glb)]:
        shutil.copy(src, tmp_path / os.path.basename(src))
    js = tmp_path / os.path.basename(sidecar_paths(glb)[0])
    doc = json.loads(js.read_text())
    doc["expressions"]["definitions"]["action_units"]["12"]["muscles"] = {
        k: 2 * v for k, v in DOC["action_units"]["12"]["muscles"].items()}
    js.write_text(json.dumps(doc))
    again = autobones.load_rig(tmp_path / glb.name)
    assert np.allclose(again.pose(au={12: 0.5}), rig.pose(au={12: 1.0}), rtol=0, atol=1e-9 * rig.frame.size)
    assert not np.allclose(again.pose(au={12: 1.0}), rig.pose(au={12: 1.0}))
    # and saving the loaded rig keeps those definitions
    again.save(tmp_path / "resaved.glb")
    kept = json.loads((tmp_path / "resaved.rig.json").read_text())["expressions"]
    assert kept["definitions"]["action_units"]["12"] == doc["expressions"]["definitions"]["action_units"]["12"]
    assert kept["sha256"] != side["sha256"]


def _copy_rig(glb, folder, stem="copy"):
    js, npz = sidecar_paths(glb)
    out = folder / f"{stem}.glb"
    shutil.copy(glb, out)
    shutil.copy(js, folder / f"{stem}.rig.json")
    shutil.copy(npz, folder / f"{stem}.weights.npz")
    return out


def test_load_rig_refuses_what_it_cannot_pose(saved, tmp_path):
    rig, glb = saved("default")
    cases = {}
    f = _copy_rig(glb, tmp_path, "nojson")
    os.remove(tmp_path / "nojson.rig.json")
    cases[f] = "nojson.rig.json is missing"
    f = _copy_rig(glb, tmp_path, "nonpz")
    os.remove(tmp_path / "nonpz.weights.npz")
    cases[f] = "nonpz.weights.npz is missing"
    f = _copy_rig(glb, tmp_path, "badjson")
    (tmp_path / "badjson.rig.json").write_text('{"format": "autobones-rig/1", "bones": [')
    cases[f] = "not a readable autobones sidecar"
    f = _copy_rig(glb, tmp_path, "badnpz")
    (tmp_path / "badnpz.weights.npz").write_bytes(b"PK\x03\x04 not really a zip")
    cases[f] = "not a readable autobones weights file"
    f = _copy_rig(glb, tmp_path, "truncated")
    f.write_bytes(f.read_bytes()[:5000])
    cases[f] = "cannot read it as a glb"
    obj = tmp_path / "mesh.glb"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    cases[obj] = "cannot read it as a glb"
    other = tmp_path / "other.glb"
    trimesh.Trimesh(rig.vertices, rig.faces, process=False).export(other)
    cases[other] = "not a rig written by autobones"
    # sidecars of another rig (ICT) beside this glb
    f = _copy_rig(glb, tmp_path, "mixed")
    _, ict_glb = saved("ict")
    shutil.copy(sidecar_paths(ict_glb)[1], tmp_path / "mixed.weights.npz")
    cases[f] = "do not belong together"
    cases[tmp_path / "absent.glb"] = "no such file"
    f = _copy_rig(glb, tmp_path, "baddefs")
    side = json.loads((tmp_path / "baddefs.rig.json").read_text())
    del side["expressions"]["definitions"]["action_units"]
    (tmp_path / "baddefs.rig.json").write_text(json.dumps(side))
    cases[f] = "expressions.definitions has no 'action_units'"
    for path, expect in cases.items():
        with pytest.raises(AutobonesError) as err:
            autobones.load_rig(path)
        msg = str(err.value)
        assert expect in msg and "\n" not in msg, (path, msg)


def test_a_placed_rig_loads_but_has_no_muscles_to_pose(rigs, tmp_path):
    rig = rigs(None, density="sparse")
    with pytest.raises(AutobonesError, match="no muscles"):
        rig.save(tmp_path / "p.glb", expressions=True)
    assert os.listdir(tmp_path) == []  # nothing written
    rig.save(tmp_path / "p.glb")
    again = autobones.load_rig(tmp_path / "p.glb")
    assert np.array_equal(again.vertices, rig.vertices) and "expressions" not in again.extra
    with pytest.raises(AutobonesError, match="no muscles"):
        again.pose(au={12: 1})


# ------------------------------------------------------------------------------ morph targets


@pytest.mark.parametrize("name", ["default", "ict"])
def test_morph_targets_are_the_aus_at_intensity_1(saved, name):
    rig, glb = saved(name)
    deltas, weights, g = _targets(glb)
    side = json.loads(open(sidecar_paths(glb)[0]).read())["expressions"]
    assert list(deltas) == [t["name"] for t in side["morph_targets"]]
    assert sorted(list(deltas) + side["morph_targets_skipped"]) == sorted(f"AU{a}" for a in AUS)
    assert "AU12" in deltas and "AU26" in deltas and "AU43" in deltas
    assert weights == [0.0] * len(deltas)
    # the rest positions are still the input (float32), the skin still there
    prim = g.meshes[0].primitives[0]
    assert np.array_equal(pyg_accessor(g, prim.attributes.POSITION), rig.vertices.astype(np.float32))
    assert prim.attributes.JOINTS_0 is not None and g.skins
    neutral = rig.vertices
    for n, d in deltas.items():
        want = rig.pose(au={n[2:]: 1.0}) - neutral
        assert d.dtype == np.float32 and d.shape == neutral.shape
        assert np.abs(d - want).max() <= 1e-6 * np.abs(want).max() + 1e-7 * rig.frame.size, n
        assert np.abs(d).max() > 1e-4 * rig.frame.size, n  # every written target moves the face
        rec = side["morph_targets"][list(deltas).index(n)]
        assert np.isclose(rec["max_displacement"], np.linalg.norm(want, axis=1).max())
        assert rec["label"] == DOC["action_units"][n[2:]]["name"]
    # accessor min/max are the data's (the validator checks them too)
    for t, d in zip(prim.targets, deltas.values()):
        acc = g.accessors[t["POSITION"] if isinstance(t, dict) else t.POSITION]
        assert np.array_equal(acc.min, d.min(axis=0).tolist()) and np.array_equal(acc.max, d.max(axis=0).tolist())


def test_morph_targets_by_side_and_by_list(saved, tmp_path):
    rig, _ = saved("default")
    rig.save(tmp_path / "sides.glb", expressions="sides")
    deltas, _, _ = _targets(tmp_path / "sides.glb")
    assert list(deltas)[:6] == ["AU1", "AU1L", "AU1R", "AU2", "AU2L", "AU2R"] and len(deltas) == 3 * len(AUS)
    x = rig.frame.to_canonical(rig.vertices)[:, 0]  # +x: the subject's left
    d = np.linalg.norm(deltas["AU12L"], axis=1)
    assert d[x > 0.05].max() > 1e-3 * rig.frame.size and d[x < -0.05].max() < 0.05 * d[x > 0.05].max()
    rig.save(tmp_path / "some.glb", expressions=["AU12", 6, "12R"])
    assert list(_targets(tmp_path / "some.glb")[0]) == ["AU12", "AU6", "AU12R"]
    with pytest.raises(AutobonesError, match="unknown action unit"):
        rig.save(tmp_path / "bad.glb", expressions=[12, 13])
    assert not (tmp_path / "bad.glb").exists() and not (tmp_path / "bad.rig.json").exists()


def test_without_targets_the_glb_is_unchanged_and_targets_only_append(saved, tmp_path):
    rig, glb = saved("default")
    plain = tmp_path / "plain.glb"
    rig.save(plain)
    doc0, body0 = read_glb(plain)
    doc1, body1 = read_glb(glb)
    assert "targets" not in doc0["meshes"][0]["primitives"][0] and "extras" not in doc0["meshes"][0]
    assert body1[:len(body0)] == body0  # the skinned mesh's data first, as before; targets after it
    assert doc1["accessors"][:len(doc0["accessors"])] == doc0["accessors"]
    assert doc1["nodes"] == doc0["nodes"] and doc1["skins"] == doc0["skins"]
    # trimesh reads the same rest mesh from both
    for f in (plain, glb):
        m = trimesh.load(str(f), force="mesh", process=False)
        assert len(m.vertices) == len(rig.vertices) and len(m.faces) == len(rig.faces)


@pytest.mark.parametrize("name", ["default", "ict"])
def test_khronos_validator_accepts_the_morph_targets(saved, name):
    rig, glb = saved(name)
    report = run_validator(glb)
    issues = report["issues"]
    bad = [m for m in issues["messages"] if m["severity"] <= 1]
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, bad[:10]
    # the only infos are the muscle marker nodes (nodes without a mesh), as in every transferred glb
    assert {m["code"] for m in issues["messages"]} <= {"NODE_EMPTY"}
    info = report["info"]
    assert info["hasMorphTargets"] and info["hasSkins"] and info["totalVertexCount"] == len(rig.vertices)


@pytest.mark.parametrize("name", ["default", "ict"])
def test_blender_imports_the_targets_as_shape_keys_that_move_the_skin_as_written(saved, tmp_path, name):
    rig, glb = saved(name)
    rep = run_blender_check(glb, tmp_path / "blender.json")
    keys = rep["shape_keys"]
    deltas, _, _ = _targets(glb)
    assert keys["names"] == list(deltas) == keys["file_target_names"]
    assert keys["reference"] == "Basis" and all(v == 0 for k, v in keys["values"].items())
    diag = rep["rest"]["bbox_diagonal"]
    for n, k in keys["keys"].items():
        # float32 positions: the shape key moves every vertex by the file's delta
        assert k["max_error"] < 1e-6 * diag, (n, k)
        assert abs(k["max_blender_displacement"] - np.linalg.norm(deltas[n], axis=1).max()) < 1e-6 * diag
        assert k["vertices_moved"] > 0
    assert len(keys["keys"]) == len(deltas)
    assert keys["rest_restored_max_error"] < 1e-6 * diag
    assert rep["rest"]["max_blender_to_file"] < 1e-6 * diag  # the rest pose is still the input


# ------------------------------------------------------------------------------ command line


def _cli(args, cwd, capsys):
    from autobones.cli.main import main

    old = os.getcwd()
    os.chdir(cwd)
    try:
        code = main([str(a) for a in args])
    finally:
        os.chdir(old)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_cli_user_story(tmp_path, capsys):
    """The issue's three commands: transfer --expressions, pose an emotion, pose AUs with the jaw."""
    code, out, err = _cli(["transfer", ROOT / "generic_rig" / "default_head.obj", "--landmarks",
                           HEADS["default"][1], "--expressions", "-o", "head.glb"], tmp_path, capsys)
    assert code == 0, err
    assert f"{len(AUS)} morph targets" in out and len(out.strip().splitlines()) == 1
    assert len(_targets(tmp_path / "head.glb")[0]) == len(AUS)
    rig = autobones.load_rig(tmp_path / "head.glb")
    for args, kw in ((["--expression", "happiness", "-o", "happy.obj"], {"expression": "happiness"}),
                     (["--au", "12=0.8", "--au", "6=0.4", "--jaw", "10", "-o", "smile.obj"],
                      {"au": {12: 0.8, 6: 0.4}, "jaw_deg": 10}),
                     (["--au", "AU12L", "--gaze", "20,5", "--eyelids", "upper=0.5", "--head", "0,15,0", "-o", "x.glb"],
                      {"au": {"12L": 1}, "gaze": (20, 5), "eyelids": {"upper": 0.5}, "head_deg": (0, 15, 0)}),
                     (["--expression", "sadness=0.5", "--head", "-10,0,0", "--gaze", "-20,-5", "-o", "neg.obj"],
                      {"expression": {"sadness": 0.5}, "head_deg": (-10, 0, 0), "gaze": (-20, -5)})):
        code, out, err = _cli(["pose", "head.glb", *args], tmp_path, capsys)
        assert code == 0 and not err, err
        assert len(out.strip().splitlines()) == 1 and out.startswith(args[-1] + ":")
        want = rig.pose(**kw)
        V, F = autobones.load_mesh(tmp_path / args[-1])
        assert len(V) == len(rig.vertices) and np.array_equal(F, rig.faces)
        tol = 1e-6 * rig.frame.size if args[-1].endswith(".glb") else 1e-8 * rig.frame.size
        assert np.abs(V - want).max() < tol, args
    assert sorted(os.listdir(tmp_path)) == ["happy.obj", "head.glb", "head.rig.json", "head.weights.npz",
                                            "neg.obj", "smile.obj", "x.glb"]
    issues = run_validator(tmp_path / "x.glb")["issues"]  # the posed static mesh is valid glTF too
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"][:5]


def test_cli_pose_bad_input_is_one_line_exit_2_nothing_written(saved, rigs, tmp_path, capsys):
    _, glb = saved("default")
    _copy_rig(glb, tmp_path, "head")
    shutil.copy(glb, tmp_path / "lonely.glb")
    rigs(None, density="sparse").save(tmp_path / "placed.glb")
    before = sorted(os.listdir(tmp_path))
    cases = [(["pose", "head.glb", "--au", "13=1", "-o", "o.obj"], "unknown action unit '13'"),
             (["pose", "head.glb", "--au", "12=lots", "-o", "o.obj"], "'lots' is not a number"),
             (["pose", "head.glb", "--au", "12=nan", "-o", "o.obj"], "not a finite number"),
             (["pose", "head.glb", "--expression", "joy", "-o", "o.obj"], "unknown expression 'joy'"),
             (["pose", "head.glb", "--jaw", "wide", "-o", "o.obj"], "--jaw"),
             (["pose", "head.glb", "--gaze", "20", "-o", "o.obj"], "expected 2 comma-separated numbers"),
             (["pose", "head.glb", "--eyelids", "middle=1", "-o", "o.obj"], "unknown eyelid"),
             (["pose", "head.glb", "--au", "12", "-o", "o.stl"], ".obj or .glb"),
             (["pose", "lonely.glb", "-o", "o.obj"], "lonely.rig.json is missing"),
             (["pose", "placed.glb", "-o", "o.obj"], "no muscles"),
             (["pose", "absent.glb", "-o", "o.obj"], "no such file"),
             (["place", "--expressions", "-o", "p.glb"], "place does not make")]
    for args, expect in cases:
        code, out, err = _cli(args, tmp_path, capsys)
        assert code == 2, (args, out, err)
        lines = err.strip().splitlines()
        assert len(lines) == 1 and expect in lines[0] and lines[0].startswith("autobones "), (args, err)
        assert sorted(os.listdir(tmp_path)) == before, args


def test_cli_pose_help_teaches_the_aus_emotions_and_units(tmp_path):
    exe = shutil.which("autobones")
    assert exe, "the 'autobones' command is not on PATH: pip install -e ."
    r = subprocess.run([exe, "pose", "--help"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0
    for a in AUS:
        assert f"AU{a} " in r.stdout, a
    for name, d in DOC["expressions"].items():
        assert name in r.stdout
    assert "degrees" in r.stdout and "subject's left" in r.stdout and "--expression" in r.stdout
    r = subprocess.run([exe, "transfer", "--help"], capture_output=True, text=True, timeout=120)
    assert "--expressions" in r.stdout and "morph target" in r.stdout


def test_a_rig_with_its_own_definitions_saves_and_loads_with_them(tmp_path):
    import copy

    from autobones.expressions.model import ExpressionModel

    doc = copy.deepcopy(DOC)
    doc["action_units"]["12"]["muscles"] = {"zygomaticus_major": 0.5}
    doc["expressions"]["grin"] = {"au": {"12": 1.0, "25": 0.5}}
    rig = autobones.transfer(*HEADS["default"])
    model = rig.expression_model(doc)
    assert rig.expression_model() is model  # pose and save use the model built last
    rig.save(tmp_path / "own.glb", expressions=["12"])
    deltas, _, _ = _targets(tmp_path / "own.glb")
    want = ExpressionModel(doc).fit(rig).pose(au={12: 1}) - rig.vertices
    assert np.abs(deltas["AU12"] - want).max() < 1e-6 * rig.frame.size
    assert not np.allclose(want, ExpressionModel().fit(rig).pose(au={12: 1}) - rig.vertices)
    side = json.loads((tmp_path / "own.rig.json").read_text())["expressions"]
    assert side["definitions"] == doc and side["sha256"] == definitions_digest(doc) != definitions_digest(DOC)
    again = autobones.load_rig(tmp_path / "own.glb")
    assert np.abs(again.pose(expression="grin") - rig.pose(expression="grin")).max() < 1e-9 * rig.frame.size


def test_batch_transfer_with_expressions_and_its_options_hash(tmp_path, capsys):
    src = tmp_path / "in"
    src.mkdir()
    shutil.copy(ROOT / "generic_rig" / "default_head.obj", src / "a.obj")
    shutil.copy(HEADS["default"][1], src / "a.landmarks.json")
    out = tmp_path / "out"
    code, _, err = _cli(["batch", src, "-o", out, "--transfer", "--expressions", "-q"], tmp_path, capsys)
    assert code == 0, err
    assert len(_targets(out / "a.rig.glb")[0]) == len(AUS)
    report = json.loads((out / "batch_report.json").read_text())
    assert report["options"]["expressions"] is True
    code, _, err = _cli(["batch", src, "-o", out, "--transfer", "--expressions", "-q"], tmp_path, capsys)
    assert code == 0 and json.loads((out / "batch_report.json").read_text())["counts"]["skipped"] == 1
    # the same batch without morph targets is other options: refused without --force, done with it
    code, _, err = _cli(["batch", src, "-o", out, "--transfer", "-q"], tmp_path, capsys)
    assert code == 1 and "a.obj" in err
    code, _, err = _cli(["batch", src, "-o", out, "--transfer", "--force", "-q"], tmp_path, capsys)
    assert code == 0, err
    assert "targets" not in read_glb(out / "a.rig.glb")[0]["meshes"][0]["primitives"][0]
    code, _, err = _cli(["batch", src, "-o", tmp_path / "p", "--expressions"], tmp_path, capsys)
    assert code == 2 and "add --transfer" in err and not (tmp_path / "p").exists()


def test_cli_pose_with_other_definitions(saved, tmp_path, capsys):
    import copy

    rig, glb = saved("default")
    _copy_rig(glb, tmp_path, "head")
    doc = copy.deepcopy(DOC)
    doc["action_units"]["12"]["muscles"] = {k: 2 * v for k, v in DOC["action_units"]["12"]["muscles"].items()}
    (tmp_path / "mine.json").write_text(json.dumps(doc))
    code, out, err = _cli(["pose", "head.glb", "--au", "12=0.5", "--definitions", "mine.json", "-o", "a.obj"],
                          tmp_path, capsys)
    assert code == 0, err
    V, _ = autobones.load_mesh(tmp_path / "a.obj")
    assert np.abs(V - rig.pose(au={12: 1})).max() < 1e-8 * rig.frame.size
    (tmp_path / "broken.json").write_text("{")
    code, out, err = _cli(["pose", "head.glb", "--definitions", "broken.json", "-o", "b.obj"], tmp_path, capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "broken.json" in err
    assert not (tmp_path / "b.obj").exists()


def test_cli_pose_with_the_tissue_pass(saved, tmp_path, capsys):
    rig, glb = saved("default")
    _copy_rig(glb, tmp_path, "head")
    code, out, err = _cli(["pose", "head.glb", "--au", "12", "--tissue", "-o", "t.obj"], tmp_path, capsys)
    assert code == 0 and "tissue" in out, err
    V, _ = autobones.load_mesh(tmp_path / "t.obj")
    expected = rig.pose(au={12: 1}, tissue=True)
    assert np.abs(V - expected).max() < 1e-6 * rig.frame.size
    assert np.abs(V - rig.pose(au={12: 1})).max() > 1e-3 * rig.frame.size   # the tissue did move the skin
    # transfer refuses --tissue without the morph targets it refines, before writing anything
    code, out, err = _cli(["transfer", str(ROOT / "generic_rig" / "default_head.obj"), "--landmarks",
                           str(ROOT / "generic_rig" / "default_head.landmarks.json"), "--tissue", "-o", "x.glb"],
                          tmp_path, capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--expressions" in err
    assert not (tmp_path / "x.glb").exists()
