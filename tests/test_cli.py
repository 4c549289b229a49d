"""The command line as a user meets it: defaults, outputs, one-line errors, exit code 2, nothing written."""
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from shared_data import ROOT, data

CLI = [sys.executable, "-m", "cli.main"]


def run(args, cwd):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run(CLI + args, cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


def test_installed_entry_point():
    exe = shutil.which("autobones")
    assert exe, "the 'autobones' command is not on PATH: pip install ."
    out = subprocess.run([exe, "--version"], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.startswith("autobones ")


def test_place_with_no_argument_rigs_the_default_head(tmp_path):
    r = run(["place"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert sorted(os.listdir(tmp_path)) == ["default_head.rig.glb", "default_head.rig.json", "default_head.weights.npz"]
    side = json.loads((tmp_path / "default_head.rig.json").read_text())
    names = [b["name"] for b in side["bones"]]
    assert names[:2] == ["neck", "head"] and len(names) == 2 + 16
    assert side["options"]["density"] == "medium"
    assert side["frame"]["up"] == "+y" and side["frame"]["front"] == "+z"
    W = np.load(tmp_path / "default_head.weights.npz")["weights"]
    assert W.shape == (side["vertex_count"], len(names))
    assert len(side["labels"]) == side["vertex_count"] and set(side["labels"]) <= {0, 1, 2}
    np.testing.assert_allclose(W.sum(axis=1), 1.0, atol=1e-5)


def test_place_says_when_the_head_is_a_face_mask(tmp_path):
    mask = run(["place", data("misc/fran_cut.obj"), "-o", str(tmp_path / "mask.glb")], tmp_path)
    assert mask.returncode == 0, mask.stderr
    lines = mask.stdout.strip().splitlines()
    assert len(lines) == 2 and lines[1].startswith("joints: a face mask"), mask.stdout
    head = run(["place", data("misc/LeePerrySmith.obj"), "-o", str(tmp_path / "head.glb")], tmp_path)
    assert head.returncode == 0 and "face mask" not in head.stdout, head.stdout


def test_place_says_when_the_head_has_no_neck(tmp_path):
    from pathlib import Path

    suzanne = Path(__file__).parent / "data" / "blender" / "suzanne.obj"
    r = run(["place", str(suzanne), "-o", str(tmp_path / "suzanne.glb"), "--density", "sparse"], tmp_path)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.strip().splitlines()
    assert len(lines) == 2 and lines[1].startswith("joints: no neck"), r.stdout
    assert "up +y, front +z" in lines[0]


def test_place_density_output_and_verbose(tmp_path):
    # the goat's frame as the user gives it (found from its shape alone it is the same: test_orient's
    # closed bust), so --up/--front, the documented recourse, is exercised
    r = run(["place", str(data("misc/goathead.obj")), "--density", "12", "-o", "goat.glb", "-v",
             "--up", "+y", "--front", "-x"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert sorted(os.listdir(tmp_path)) == ["goat.glb", "goat.rig.json", "goat.weights.npz"]
    assert "up +y" in r.stdout and "front -x" in r.stdout
    assert "weights" in r.stderr  # -v reports stages
    side = json.loads((tmp_path / "goat.rig.json").read_text())
    assert len(side["bones"]) == 14 and side["options"]["facial_bones"] == 12


def test_help_teaches():
    r = run(["place", "--help"], ROOT)
    assert r.returncode == 0
    for word in ("--density", "sparse", "dense", "--up", "--front", "rig.json", "weights.npz", "examples"):
        assert word in r.stdout


BAD = {
    "empty.obj": b"",
    "garbage.obj": os.urandom(4096),
    "nan.obj": b"v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n",
    "cloud.ply": b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                 b"end_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n",
    "triangle.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_input_one_line_exit_2_nothing_written(tmp_path, name):
    src = tmp_path / "in"
    src.mkdir()
    (src / name).write_bytes(BAD[name])
    out = tmp_path / "out"
    out.mkdir()
    r = run(["place", str(src / name), "-o", str(out / "x.glb")], tmp_path)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "error" in lines[0] and name in lines[0], r.stderr
    assert "Traceback" not in r.stderr
    assert os.listdir(out) == []


@pytest.mark.parametrize("args,needle", [
    (["place", "--density", "lots"], "density"),
    (["place", "--up", "+w"], "--up"),
    (["place", "--up", "+y", "--front", "-y"], "different axes"),
    (["place", "nothere.obj"], "no such file"),
    (["place", "-o", "x.fbx"], ".glb"),
    (["place", "-o", "/nonexistent/dir/x.glb"], "does not exist"),
    (["place", "."], "a folder, not a mesh file"),
    (["pose", ".", "-o", "x.obj"], "a folder, not a rig"),
])
def test_bad_options_one_line_exit_2(tmp_path, args, needle):
    r = run(args, tmp_path)
    assert r.returncode == 2 and needle in r.stderr and "Traceback" not in r.stderr, r.stderr
    assert [p for p in os.listdir(tmp_path)] == []


def test_debug_shows_the_traceback(tmp_path):
    (tmp_path / "e.obj").write_bytes(b"")
    r = run(["place", str(tmp_path / "e.obj"), "--debug"], tmp_path)
    assert r.returncode != 0 and "Traceback" in r.stderr


# ---------------------------------------------------------------------------------------------
# issue 13, bad input that got through: each one line naming the file, exit 2, nothing written

def _one_line_error(r, *needles):
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert "error" in lines[0] and all(n in lines[0] for n in needles), r.stderr
    return lines[0]


@pytest.mark.parametrize("seed", ["-5", "1.5", "abc"])
def test_bad_seed_one_line_exit_2(tmp_path, seed):
    r = run(["place", str(data("misc/robot_head_neutral.obj")), "--seed", seed, "-o", "x.glb"], tmp_path)
    _one_line_error(r, "--seed", "whole number")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("seed", [-5, 1.5, "3", None, True])
def test_library_refuses_a_bad_seed_with_its_error_type(seed):
    import autobones

    with pytest.raises(autobones.AutobonesError, match="random_state"):
        autobones.place(data("misc/robot_head_neutral.obj"), random_state=seed)


NEW_BAD = ["stray_triangle_1e9.obj", "stray_triangle_1e7.obj", "spike_1e3.obj", "spike_1e5.obj",
           "collinear_strip.obj", "random_stl.stl", "random_off.off", "too_far_from_origin.obj"]


@pytest.mark.parametrize("name", NEW_BAD)
def test_bad_mesh_named_in_one_line(tmp_path, name):
    import bad_inputs

    content, case = bad_inputs.mesh_cases()[name]
    (tmp_path / name).write_bytes(content)
    out = tmp_path / "out"
    out.mkdir()
    r = run(["place", name, "-o", str(out / "x.glb")], tmp_path)
    line = _one_line_error(r, name)
    assert case.needle in line.lower(), line
    assert os.listdir(out) == [] and (tmp_path / name).read_bytes() == content


@pytest.mark.parametrize("sidecar", ["x.rig.json", "x.weights.npz"])
def test_a_folder_in_the_way_of_a_sidecar_leaves_nothing(tmp_path, sidecar):
    """All or nothing: the folder is named, and neither the glb nor the other sidecar appears."""
    (tmp_path / sidecar).mkdir()
    r = run(["place", str(data("misc/robot_head_neutral.obj")), "-o", "x.glb", "--density", "sparse"], tmp_path)
    _one_line_error(r, sidecar, "folder")
    assert os.listdir(tmp_path) == [sidecar] and os.listdir(tmp_path / sidecar) == []


@pytest.mark.parametrize("command", ["place", "transfer"])
@pytest.mark.parametrize("out, needle", [("nope/x.glb", "does not exist"), ("x.fbx", "must be a .glb"),
                                         ("dir.glb", "folder of that name"), ("x.rig.json", "must be a .glb"),
                                         ("d.glb", "d.rig.json: a folder"), ("/proc/x.glb", "cannot write in")])
def test_an_output_that_cannot_be_written_is_refused_before_any_work(tmp_path, monkeypatch, capsys, command,
                                                                     out, needle):
    """A mistyped -o used to be found by the save, after the rig (100 s for a 213k scan with --arkit)."""
    import autobones
    from cli.main import main

    def no_work(*args, **kwargs):
        raise AssertionError("the head was read before the output was checked")

    for name in ("place", "transfer", "load_mesh"):
        monkeypatch.setattr(autobones, name, no_work)
    (tmp_path / "dir.glb").mkdir()
    (tmp_path / "d.rig.json").mkdir()
    monkeypatch.chdir(tmp_path)
    head = str(data("misc/robot_head_neutral.obj"))
    lm = str(ROOT / "tests" / "landmarks" / "robot_head_neutral.landmarks.json")
    args = [command, head, "-o", out] + (["--landmarks", lm] if command == "transfer" else [])
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0], err
    assert sorted(os.listdir(tmp_path)) == ["d.rig.json", "dir.glb"]


def test_build_rig_output_refused_before_the_build(tmp_path, monkeypatch, capsys):
    import autobones
    from cli.main import main

    monkeypatch.setattr(autobones, "build_rig", lambda *a, **k: pytest.fail("built before the output was checked"))
    (tmp_path / "afile").write_text("")
    lm = str(ROOT / "tests" / "landmarks" / "robot_head_neutral.landmarks.json")
    for out, needle in (("nope/rig", "does not exist"), ("afile", "is not a folder")):
        assert main(["build-rig", str(data("misc/robot_head_neutral.obj")), "--landmarks", lm, "-o",
                     str(tmp_path / out)]) == 2
        assert needle in capsys.readouterr().err


@pytest.fixture(scope="module")
def robot_glb(tmp_path_factory):
    """The robot head as a plain glb mesh, its landmarks beside it, and a transferred rig of it."""
    import trimesh

    import autobones

    folder = tmp_path_factory.mktemp("same")
    V, F = autobones.load_mesh(data("misc/robot_head_neutral.obj"))
    trimesh.Trimesh(V, F, process=False).export(folder / "a.glb")
    shutil.copy(ROOT / "tests" / "landmarks" / "robot_head_neutral.landmarks.json", folder / "a.landmarks.json")
    autobones.transfer(folder / "a.glb", folder / "a.landmarks.json").save(folder / "r.glb")
    return folder


@pytest.mark.parametrize("args,victim", [
    (["place", "a.glb", "-o", "a.glb"], "a.glb"),
    (["place", "a.glb", "-o", "link.glb"], "a.glb"),  # a symbolic link to the input
    (["transfer", "a.glb", "--landmarks", "a.landmarks.json", "-o", "a.glb"], "a.glb"),
    (["landmarks", "a.glb", "--from", "a.landmarks.json", "-o", "a.landmarks.json"], "a.landmarks.json"),
    (["pose", "r.glb", "-o", "r.glb"], "r.glb"),
])
def test_output_never_replaces_the_input(tmp_path, robot_glb, args, victim):
    for f in os.listdir(robot_glb):
        shutil.copy(robot_glb / f, tmp_path / f)
    os.symlink("a.glb", tmp_path / "link.glb")
    before = {f: (tmp_path / f).read_bytes() for f in os.listdir(tmp_path)}
    r = run(args, tmp_path)
    _one_line_error(r, "is the input file", victim)
    assert {f: (tmp_path / f).read_bytes() for f in os.listdir(tmp_path)} == before


def _strict(text):
    def refuse(token):
        raise ValueError(f"not strict JSON: {token}")
    return json.loads(text, parse_constant=refuse)


def test_sidecars_are_strict_json(tmp_path, robot_glb):
    """place and transfer: the sidecar and the glb's JSON chunk parse with a strict reader (no NaN or
    Infinity tokens); an undefined value is null and reads back (a transferred frame has no symmetry error)."""
    import autobones
    from autobones.io.gltf import read_glb

    placed = autobones.place(robot_glb / "a.glb", density="sparse").save(tmp_path / "p.glb")
    transferred = autobones.transfer(robot_glb / "a.glb", robot_glb / "a.landmarks.json").save(tmp_path / "t.glb")
    for glb, side, _ in (placed, transferred):
        _strict((tmp_path / side).read_text())
        with open(glb, "rb") as fh:
            blob = fh.read()
        n = int.from_bytes(blob[12:16], "little")
        _strict(blob[20:20 + n].decode())
        read_glb(glb)
    sym = _strict((tmp_path / "t.rig.json").read_text())["frame"]["symmetry_error"]
    assert sym is None or np.isfinite(sym)
    rig = autobones.load_rig(tmp_path / "t.glb")
    assert rig.frame.symmetry_error == sym or (sym is None and np.isnan(rig.frame.symmetry_error))
