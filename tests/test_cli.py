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


def test_place_density_output_and_verbose(tmp_path):
    r = run(["place", str(data("misc/goathead.obj")), "--density", "12", "-o", "goat.glb", "-v"], tmp_path)
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
])
def test_bad_options_one_line_exit_2(tmp_path, args, needle):
    r = run(args, tmp_path)
    assert r.returncode == 2 and needle in r.stderr and "Traceback" not in r.stderr, r.stderr
    assert [p for p in os.listdir(tmp_path)] == []


def test_debug_shows_the_traceback(tmp_path):
    (tmp_path / "e.obj").write_bytes(b"")
    r = run(["place", str(tmp_path / "e.obj"), "--debug"], tmp_path)
    assert r.returncode != 0 and "Traceback" in r.stderr
