"""The Blender add-on (issue #37): its zip installs in Blender 3.4 and its operators rig a head in the scene.

One headless Blender run (tests/blender_addon_check.py, ~25 s) installs the zip that
``autobones blender-addon`` writes, enables it, rigs the built-in default head with ``place`` and
then ``transfer`` (landmark file, ``--arkit``), then the same head in millimetres and +Z up, moved and
scaled in the scene, with landmarks placed as empties by the add-on's operator; every result is
compared here with the files autobones wrote (read by autobones' own readers, not the add-on's).
"""
import json
import os
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
HEAD = ROOT / "generic_rig" / "default_head.obj"
LANDMARKS = ROOT / "generic_rig" / "default_head.landmarks.json"
RUNS = {"a_place": "head", "a_transfer": "head", "b_place": "head_mm", "b_transfer": "head_mm", "c_auto": "head_auto"}
MORPH_TARGETS = {"a_transfer": 52, "b_transfer": 52}  # --arkit; none for place or a transfer without options
TO_B = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]]) * 1000.0  # the head as given -> millimetres, +Z up


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    """(out folder, report dict, Blender's log) of one Blender run of tests/blender_addon_check.py."""
    blender = shutil.which("blender")
    if blender is None:
        pytest.fail("blender is not on PATH; install it with: apt-get install blender python3-numpy "
                    "(or bash tools/test-setup.sh)")
    from autobones.blender_zip import write_addon_zip

    work = tmp_path_factory.mktemp("blender_addon")
    write_addon_zip(work / "autobones_blender.zip")  # what `autobones blender-addon` writes (tested below)
    out, scripts = work / "out", work / "user_scripts"
    out.mkdir()
    # Debian's Blender finds its Python's standard library through the first python3.X on PATH (see
    # autobones/export/fbx.py); the user's scripts folder is a temporary one: nothing installed for real
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(scripts),
               PATH=os.path.dirname(os.path.realpath(blender)) + os.pathsep + os.environ.get("PATH", ""))
    run = subprocess.run([blender, "-b", "--factory-startup", "--python-exit-code", "1", "-P",
                          str(ROOT / "tests" / "blender_addon_check.py"), "--", str(work / "autobones_blender.zip"),
                          sys.executable, str(HEAD), str(LANDMARKS), str(out)],
                         capture_output=True, text=True, timeout=600, env=env)
    log = run.stdout + run.stderr
    assert run.returncode == 0, log[-3000:]
    assert (scripts / "addons" / "autobones_blender" / "__init__.py").is_file()  # installed from the zip
    with open(out / "report.json") as fh:
        return out, json.load(fh), log


def _rig(out, run):
    """(what Blender made: npz dict, the files autobones wrote: RigSource)."""
    from autobones.export.source import read_rig_source

    with np.load(out / f"{run}.npz") as z:
        got = {k: z[k] for k in z.files}
    return got, read_rig_source(out / run / f"{RUNS[run]}.glb")


@pytest.mark.slow  # Blender
@pytest.mark.parametrize("run", list(RUNS))
def test_the_rig_in_blender_is_the_rig_autobones_wrote(scene, run):
    out, report, log = scene
    assert report["results"][run] == ["FINISHED"]
    got, src = _rig(out, run)
    rig, size = src.rig, float(src.rig.frame.size)
    names = [str(s) for s in got["bone_names"]]
    assert names == src.joint_names
    parents = [str(p) for p in got["parents"]]
    assert parents == [src.joint_names[p] if p >= 0 else "" for p in src.parents]
    # bones where autobones put them, in the mesh's own frame, with the glb joints' own axes
    assert np.abs(got["heads"] - rig.skeleton.heads).max() <= 1e-6 * size
    assert np.abs(got["tails"] - rig.skeleton.tails).max() <= 1e-6 * size
    assert np.abs(got["x_axes"] - src.world[:, :3, 0]).max() <= 1e-4
    assert np.abs(got["y_axes"] - src.world[:, :3, 1]).max() <= 1e-4
    # every weight of the sidecar (not the glb's four), one vertex group per bone
    assert got["weights"].shape == rig.weights.shape
    assert np.abs(got["weights"] - rig.weights).max() <= 1e-6
    assert (rig.weights > 0).sum(axis=1).max() > 4 or not run.endswith("place")
    assert set(names) <= {str(g) for g in got["group_names"]}
    # a shape key per morph target, under its name, with the glb's offsets
    assert [str(s) for s in got["shape_key_names"]] == [n for n, _ in src.morph_targets]
    assert len(src.morph_targets) == MORPH_TARGETS.get(run, 0)
    for delta, (name, want) in zip(got["shape_key_deltas"], src.morph_targets):
        assert np.linalg.norm(delta - want, axis=1).max() <= 1e-6 * size, name
    # on the same object, at rest, and the sidecar kept
    made = report["made"][run]
    assert made["armature_parent"] == made["mesh"] == RUNS[run] and made["armature_parent_type"] == "OBJECT"
    assert made["modifier_object"] == f"{RUNS[run]}_rig" and made["modifier_index"] == 0
    assert made["armatures_in_scene"] == " abc".index(run[0])  # rigging again replaced the rig
    assert made["sidecar_text"] == (out / run / f"{RUNS[run]}.rig.json").read_text()
    assert np.abs(got["rest"] - got["mesh"]).max() <= 1e-6 * size
    assert np.abs(got["mesh"] - rig.vertices).max() <= 1e-6 * size  # vertex order and values kept


@pytest.mark.slow  # Blender
@pytest.mark.parametrize("run", list(RUNS))
def test_turning_head_20_degrees_moves_the_head_and_not_the_neck_base(scene, run):
    out, report, _ = scene
    got, src = _rig(out, run)
    rig, size = src.rig, float(src.rig.frame.size)
    names = list(src.joint_names)
    up = rig.skeleton.heads[names.index("head")] - rig.skeleton.heads[names.index("neck")]
    height = got["mesh"] @ (up / np.linalg.norm(up))
    moved = np.linalg.norm(got["turned"] - got["rest"], axis=1)
    top = int(np.argmax(height))
    pivot = rig.skeleton.heads[names.index("head")]
    rigid = 2 * np.sin(np.radians(10)) * np.linalg.norm(got["mesh"][top] - pivot)  # a chord of 20 degrees
    assert moved[top] >= 0.95 * rigid * rig.weights[top, names.index("head"):].sum()
    assert moved[top] >= 0.1 * size
    base = height <= height.min() + 0.02 * (height.max() - height.min())  # the neck's cut, 2% of the height
    assert base.sum() >= 20
    assert moved[base].max() <= 1e-6 * size
    assert np.abs(got["after_reset"] - got["mesh"]).max() <= 1e-6 * size  # autobones.reset_pose


@pytest.mark.slow  # Blender
def test_the_millimetre_z_up_head_gets_the_same_rig_sitting_on_it(scene):
    out, _, _ = scene
    for kind in ("place", "transfer"):
        got_a, src_a = _rig(out, f"a_{kind}")
        got_b, src_b = _rig(out, f"b_{kind}")
        assert src_b.joint_names == src_a.joint_names
        size_a = float(src_a.rig.frame.size)
        # the same bones on the same head: b's mapped back to a's frame and unit
        back = got_b["heads"] @ np.linalg.inv(TO_B).T
        assert np.linalg.norm(back - got_a["heads"], axis=1).max() <= 1e-3 * size_a, kind  # measured 1e-7
        # and on the mesh in the scene: every joint inside the moved, scaled head's world bounding box
        M = got_b["matrix_world"]
        world = got_b["heads"] @ M[:3, :3].T + M[:3, 3]
        skin = got_b["mesh"] @ M[:3, :3].T + M[:3, 3]
        lo, hi = skin.min(axis=0), skin.max(axis=0)
        assert ((world >= lo) & (world <= hi)).all(), kind
        assert np.abs(M[:3, 3] - [0.4, 0.1, 0.0]).max() < 1e-6  # the object itself did not move


@pytest.mark.slow  # Blender
def test_landmark_empties_are_snapped_named_and_written_for_autobones(scene):
    from autobones.io.landmarks import NAMES, read_landmarks

    out, report, _ = scene
    assert report["written_landmarks"] == ["FINISHED"]
    got, src = _rig(out, "b_transfer")
    placed = dict(zip((str(s) for s in got["landmark_names"]), got["landmarks"]))
    assert list(placed) == list(NAMES)
    written = read_landmarks(out / "b.landmarks.json")  # autobones reads the file the operator wrote
    assert sorted(written) == sorted(placed)
    size = float(src.rig.frame.size)
    for name, p in placed.items():  # Blender keeps positions in float32
        assert np.abs(np.asarray(written[name]) - p).max() <= 1e-6 * size
    with open(LANDMARKS) as fh:
        given = json.load(fh)["landmarks"]
    for name, p in given.items():  # clicked at the given points (on the skin): snapping keeps them there
        assert np.linalg.norm(placed[name] - TO_B @ np.asarray(p)) <= 0.005 * size, name
    # the transfer used exactly those, and its landmarks came back as the same empties
    assert sorted(src.rig.landmarks) == sorted(placed)
    for name, p in src.rig.landmarks.items():
        assert np.linalg.norm(np.asarray(p) - placed[name]) <= 1e-6 * size


@pytest.mark.slow  # Blender
def test_automatic_landmarks_come_back_as_empties(scene):
    out, _, _ = scene
    got, src = _rig(out, "c_auto")
    assert src.rig.options["landmarks_source"] == "detected" and len(src.rig.landmarks) >= 20  # MediaPipe: 27
    placed = dict(zip((str(s) for s in got["landmark_names"]), got["landmarks"]))
    assert sorted(placed) == sorted(src.rig.landmarks)
    size = float(src.rig.frame.size)
    for name, p in src.rig.landmarks.items():
        assert np.linalg.norm(np.asarray(p) - placed[name]) <= 1e-6 * size


@pytest.mark.slow  # Blender
def test_bad_input_is_one_line_in_blenders_report_never_a_traceback(scene):
    _, report, log = scene
    errors = report["errors"]
    expected = {"no_active_mesh": "select a mesh object to rig",
                "autobones_not_found": "autobones not found: ",
                "autobones_not_on_path": "autobones not found on PATH",
                "autobones_exit_2": "autobones transfer: error: ",
                }
    assert sorted(errors) == sorted(expected)
    for key, words in expected.items():
        message = errors[key].strip()
        assert "\n" not in message and "Traceback" not in message, message
        assert message.startswith("Error: ") and words in message, message
    assert "at least 10" in errors["autobones_exit_2"]  # autobones' own one-line message
    assert "Traceback" not in log and "Dependency cycle" not in log


@pytest.mark.slow  # Blender
def test_the_rig_button_runs_in_the_background_with_progress_in_blenders_window(tmp_path):
    """Blender's own window (under Xvfb): the panels draw, Rig runs modal with its stages in the status bar."""
    from autobones.blender_zip import write_addon_zip

    blender, xvfb = shutil.which("blender"), shutil.which("xvfb-run")
    if blender is None or xvfb is None:
        pytest.fail("blender or xvfb-run is not on PATH; install them with: apt-get install blender python3-numpy "
                    "xvfb xauth (or bash tools/test-setup.sh)")
    write_addon_zip(tmp_path / "autobones_blender.zip")
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(tmp_path / "user_scripts"),
               PATH=os.path.dirname(os.path.realpath(blender)) + os.pathsep + os.environ.get("PATH", ""))
    empty = tmp_path / "empty.blend"  # opening a file skips the splash screen
    subprocess.run([blender, "-b", "--factory-startup", "--python-expr",
                    "import bpy; bpy.ops.wm.read_factory_settings(use_empty=True); "
                    f"bpy.ops.wm.save_as_mainfile(filepath={str(empty)!r})"], env=env, capture_output=True, timeout=120)
    script = ROOT / "gallery" / "blender_shots_scene.py"  # the gallery's window run, also a test of it
    run = subprocess.run([xvfb, "-a", "-s", "-screen 0 1600x1000x24", blender, "--factory-startup",
                          "--enable-event-simulate", str(empty), "--python", str(script), "--", "ui",
                          str(tmp_path / "autobones_blender.zip"), sys.executable, str(HEAD), str(LANDMARKS),
                          str(tmp_path)], capture_output=True, text=True, timeout=600, env=env)
    log = run.stdout + run.stderr
    assert run.returncode == 0 and "Traceback" not in log, log[-3000:]
    seen = json.loads((tmp_path / "ui.json").read_text())
    assert "failed" not in seen, seen
    assert all(seen["draws"].get(p, 0) >= 1 for p in ("AUTOBONES_PT_rig", "AUTOBONES_PT_landmarks",
                                                       "AUTOBONES_PT_pose")), seen  # drawn without an error
    # the status bar followed autobones' stages (-v): it shows the latest line at each 0.2 s tick, so a
    # quick stage can pass unseen (the ARKit stage's line is the latest only while the rig is written);
    # every line it showed is one the job read, and the job read every stage, ARKit's included
    assert len(seen["status"]) >= 3 and seen["status"][0] == "starting", seen
    from autobones.blender_addon.runner import one_line

    # the bar's one line: squeezed, and cut at 400 characters (the lids' warning is longer)
    stages = [one_line(line[len("autobones: "):]) for line in seen["lines"]]
    assert all(s in stages for s in seen["status"][1:]), seen
    assert any(s.startswith("arkit ") for s in stages) and any(s.startswith("write ") for s in stages), seen
    assert re.search(r"Info: autobones: rigged head: 5 bones, 5 vertex groups \(up to \d+ weights a vertex\), "
                     r"52 shape keys, 44 landmarks, \d+\.\d s", log), log[-3000:]
    assert (tmp_path / "pose.png").stat().st_size > 10000


@pytest.fixture
def cli(capsys, monkeypatch):
    """Run ``autobones ARGS`` in this process from folder ``cwd``: (exit code, stdout, stderr). The command
    line is this checkout's ``cli/`` (as tests/test_cli.py runs ``python -m cli.main``), whichever
    autobones is installed."""
    import importlib

    monkeypatch.syspath_prepend(str(ROOT))
    main = importlib.import_module("cli.main").main

    def run(args, cwd):
        monkeypatch.chdir(cwd)
        capsys.readouterr()
        code = main([str(a) for a in args])
        out = capsys.readouterr()
        return code, out.out, out.err

    return run


def test_cli_writes_the_same_zip_every_time_and_refuses_a_bad_output(tmp_path, cli):
    from autobones.io.landmark_names import NAMES

    code, out, _ = cli(["blender-addon", "-o", "a.zip"], tmp_path)
    assert code == 0 and out.startswith("a.zip: Blender add-on autobones_blender"), out
    assert cli(["blender-addon", "-o", "a.zip"], tmp_path)[0] == 0  # an existing zip is replaced
    data = (tmp_path / "a.zip").read_bytes()
    (tmp_path / "b").mkdir()
    assert cli(["blender-addon", "-o", "b/c.zip"], tmp_path)[0] == 0
    assert (tmp_path / "b" / "c.zip").read_bytes() == data  # deterministic
    with zipfile.ZipFile(tmp_path / "a.zip") as zf:
        files = zf.namelist()
        assert "autobones_blender/__init__.py" in files and "autobones_blender/operators.py" in files
        assert all(f.startswith("autobones_blender/") and "__pycache__" not in f for f in files)
        assert json.loads(zf.read("autobones_blender/landmark_names.json"))["names"] == list(NAMES)
        import ast

        from autobones import __version__

        init = zf.read("autobones_blender/__init__.py").decode()
        bl_info = ast.literal_eval(init[init.index("bl_info = ") + 10:init.index("}", init.index("bl_info")) + 1])
        assert bl_info["blender"] == (3, 4, 0) and bl_info["category"] == "Rigging"
        assert ".".join(map(str, bl_info["version"])) == __version__
    (tmp_path / "notes.zip").write_text("my notes")
    for target, words in (("notes.zip", "is not a zip file"), ("missing/a.zip", "does not exist"),
                          ("addon.txt", "written as a .zip"), ("b", "written as a .zip")):
        before = sorted(p.name for p in tmp_path.rglob("*"))
        code, out, err = cli(["blender-addon", "-o", target], tmp_path)
        assert code == 2 and out == "", (code, out, err)
        assert err.count("\n") == 1 and err.startswith("autobones blender-addon: error: "), err
        assert words in err, err
        assert sorted(p.name for p in tmp_path.rglob("*")) == before  # nothing written
    assert (tmp_path / "notes.zip").read_text() == "my notes"


# --------------------------------------------------------------------------- the add-on's subprocess side
# autobones/blender_addon/runner.py needs no Blender (standard library and numpy): its background job,
# which the Rig button's modal run polls for the status bar, is checked here directly.

def _finish(job, seconds=120):
    import time

    t = time.monotonic()
    while job.poll() is None:
        assert time.monotonic() - t < seconds
        time.sleep(0.05)


def test_the_background_job_reports_stages_and_autobones_one_line_error(tmp_path):
    from autobones.blender_addon import runner

    cmd = runner.autobones_command(sys.executable)
    assert cmd == [sys.executable, "-m", "autobones"]
    job = runner.Job(cmd + ["place", str(HEAD), "--density", "sparse", "-o", str(tmp_path / "h.glb"), "-v"])
    _finish(job)
    assert job.result().startswith(str(tmp_path / "h.glb")) and (tmp_path / "h.weights.npz").is_file()
    assert len(job.lines) >= 3 and not job.status().startswith("autobones: ")  # -v stages, shown bare
    bad = tmp_path / "few.json"
    bad.write_text(json.dumps({"format": "autobones-landmarks/1", "landmarks": {"pronasale": [0, 0.08, 0.1]}}))
    job = runner.Job(cmd + ["transfer", str(HEAD), "--landmarks", str(bad), "-o", str(tmp_path / "t.glb"), "-v"])
    _finish(job)
    with pytest.raises(runner.AddonError) as err:
        job.result()
    assert str(err.value).startswith("autobones transfer: error: ") and "\n" not in str(err.value)
    assert not (tmp_path / "t.glb").exists()


def test_the_background_job_stops_and_other_failures_are_one_line(tmp_path):
    from autobones.blender_addon import runner

    job = runner.Job([sys.executable, "-c", "import time; time.sleep(60)"])
    job.cancel()  # Esc
    _finish(job, seconds=10)
    crash = runner.Job([sys.executable, "-c", "import sys; sys.stderr.write('Traceback\\n  boom\\nValueError: x\\n'); "
                                              "sys.exit(1)"])
    _finish(crash)
    with pytest.raises(runner.AddonError, match=r"^autobones failed \(exit 1\): ValueError: x$"):
        crash.result()
    with pytest.raises(runner.AddonError, match="not an executable file"):
        runner.autobones_command(str(tmp_path / "python3"))
    with pytest.raises(runner.AddonError, match="did not run"):
        runner.Job([str(tmp_path)])  # a folder: the OS refuses to start it
