"""Hostile file arguments and one-line errors (issue #33): every case of ``bad_inputs.command_cases``
through the CLI as a subprocess, and the bounded reader of ``autobones.io.files`` on its own."""
import json
import os
import stat
import subprocess
import sys
import warnings

import pytest

import bad_inputs
from shared_data import ROOT, data

CLI = [sys.executable, "-m", "cli.main"]
CASES = bad_inputs.command_cases()


@pytest.fixture(scope="module")
def placed_rig(tmp_path_factory):
    """A saved place rig of the robot head (sparse: ~2 s): the rig the cases pose and animate."""
    import autobones

    folder = tmp_path_factory.mktemp("rig")
    autobones.place(data(bad_inputs.ROBOT), density="sparse").save(folder / "robot.glb")
    return folder / "robot.glb"


@pytest.fixture(scope="module")
def transferred_rig(tmp_path_factory):
    """A saved transfer rig of the robot head with its ARKit shapes (~3 s): muscles, landmarks and the
    definitions in its sidecar, for the tampered-sidecar, pose and animate cases."""
    import autobones

    folder = tmp_path_factory.mktemp("trig")
    autobones.transfer(data(bad_inputs.ROBOT), landmarks=str(bad_inputs.ROBOT_LANDMARKS), arkit=True).save(
        folder / "robot.glb")
    return folder / "robot.glb"


@pytest.mark.parametrize("name", sorted(CASES))
def test_command_case_is_one_line_exit_2_nothing_written(tmp_path, placed_rig, transferred_rig, name):
    args = bad_inputs.write_command_case(tmp_path, name, placed_rig, transferred_rig)
    case = CASES[name][2]
    before = bad_inputs.snapshot(tmp_path)
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env.pop("AUTOBONES_MAX_FILE_MB", None)
    # a FIFO must be refused, not waited on: 60 s is far beyond any case's own time (~1-3 s)
    try:
        r = subprocess.run(CLI + args, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=60)
        after = bad_inputs.snapshot(tmp_path)
    finally:
        for p in tmp_path.iterdir():  # the 126 MB capture is not kept in pytest's last three temp folders
            if p.is_file() and os.stat(p).st_blocks * 512 > 8 * 1024**2:
                p.unlink()
    lines = r.stderr.splitlines()
    assert r.returncode == 2, (name, r.returncode, r.stderr)
    assert len(lines) == 1 and r.stderr.endswith("\n"), (name, r.stderr)
    assert lines[0].startswith("autobones") and "error:" in lines[0], r.stderr
    assert case.needle.lower() in lines[0].lower(), (name, lines[0], case.needle)
    assert "Traceback" not in r.stderr and "Warning" not in r.stderr and r.stdout == "", (r.stdout, r.stderr)
    assert after == before, f"{name}: a file was written or changed"


def test_help_is_still_the_full_help_on_stdout():
    r = subprocess.run(CLI + ["--help"], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stderr == ""
    assert "usage: autobones" in r.stdout and all(c in r.stdout for c in ("place", "transfer", "animate"))


def test_the_corpus_covers_the_issue():
    """Each case the issue names is in the corpus, refused, with a reason for the README."""
    for name in ("definitions_dev_zero", "capture_dev_zero", "definitions_fifo", "capture_fifo",
                 "capture_1m_frames", "definitions_deep", "sidecar_deep", "mesh_newline_name", "mesh_1e200_warnings",
                 "no_command", "argparse_missing_value"):
        assert CASES[name][2].expect == "refused" and CASES[name][2].why, name


# --------------------------------------------------------------------------------------------------
# autobones.io.files on its own

def test_the_reader_never_takes_more_than_the_limit(tmp_path, monkeypatch):
    """A file that says it is empty (/proc) or grows after the size check is cut at limit + 1 bytes."""
    from autobones.errors import AutobonesError
    from autobones.io import files

    monkeypatch.setenv(files.LIMIT_ENV, str(4096 / files.MB))  # 4 kB
    read = []
    real = os.read
    monkeypatch.setattr(files.os, "read", lambda fd, n: read.append(n) or real(fd, n))
    p = tmp_path / "grows.json"
    p.write_bytes(b"[" + b"0," * 100_000 + b"0]")
    monkeypatch.setattr(files.os, "stat", lambda path: os.stat_result((stat.S_IFREG | 0o644,) + (0,) * 9))
    with pytest.raises(AutobonesError, match=r"over the 0.00390625 MB limit .*AUTOBONES_MAX_FILE_MB"):
        files.read_bytes(p, "definitions")
    assert sum(read) == 4097
    monkeypatch.undo()
    assert os.stat("/proc/self/status").st_size == 0  # the kernel's files report no size
    monkeypatch.setenv(files.LIMIT_ENV, str(64 / files.MB))
    with pytest.raises(AutobonesError, match="more than that"):
        files.read_bytes("/proc/self/status", "definitions")


def test_the_limit_env_must_be_a_size(monkeypatch, tmp_path):
    from autobones.errors import AutobonesError
    from autobones.io import files

    (tmp_path / "a.json").write_text("[]")
    for bad in ("lots", "-1", "inf", "nan", "0"):
        monkeypatch.setenv(files.LIMIT_ENV, bad)
        with pytest.raises(AutobonesError, match=files.LIMIT_ENV):
            files.read_json(tmp_path / "a.json", "definitions")
    monkeypatch.setenv(files.LIMIT_ENV, "0.5")
    assert files.read_json(tmp_path / "a.json", "definitions") == []


def test_json_depth_skips_strings():
    from autobones.io.files import json_depth

    assert json_depth(b"1") == 0 and json_depth(b"[]") == 1 and json_depth(b'{"a": [[1], {"b": []}]}') == 4
    assert json_depth(b"[[1], [2], [[3]]]") == 3  # siblings do not add up
    assert json_depth(b'["[[[[", "\\"[[[", {"{": "]]]]]"}]') == 2  # brackets and escaped quotes in strings
    assert json_depth(b"[" * 100_000 + b"]" * 100_000) == 100_000


def test_every_json_autobones_writes_or_ships_is_well_inside_the_limits(placed_rig):
    """The built-in definitions, rig folder and a saved sidecar: far under 64 levels and 64 MB, so the
    limits refuse only damaged files."""
    from autobones.generic_rig import default_rig_path, expressions_path
    from autobones.io.files import MAX_JSON_DEPTH, json_depth, read_json

    paths = [expressions_path(), placed_rig.with_name("robot.rig.json")]
    paths += [os.path.join(default_rig_path(), f) for f in os.listdir(default_rig_path()) if f.endswith(".json")]
    for p in paths:
        raw = open(p, "rb").read()
        assert json_depth(raw) <= 8 < MAX_JSON_DEPTH and len(raw) < 8 * 1024**2, p
        assert read_json(p, "sidecar") == json.loads(raw)


def test_a_capture_at_the_frame_limit_is_read(tmp_path, monkeypatch):
    """A take of exactly the frame limit is read; one frame more is refused (the limit lowered to 1000
    here: 200k frames take ~5 s to parse)."""
    from autobones.arkit import capture
    from autobones.arkit.capture import read_capture
    from autobones.errors import AutobonesError

    assert capture.MAX_FRAMES == 200_000
    monkeypatch.setattr(capture, "MAX_FRAMES", 1000)
    MAX_FRAMES = 1000
    text = bad_inputs._capture(MAX_FRAMES).decode()
    (tmp_path / "a.csv").write_text(text)
    assert len(read_capture(tmp_path / "a.csv").times) == MAX_FRAMES
    (tmp_path / "b.csv").write_text(text + f"{MAX_FRAMES}" + text.splitlines()[-1][len(str(MAX_FRAMES - 1)):] + "\n")
    with pytest.raises(AutobonesError, match="more than 1000 frames"):
        read_capture(tmp_path / "b.csv")


def _main(monkeypatch, capsys, command):
    from cli import main as cli_main

    monkeypatch.setitem(cli_main.COMMANDS, "place", command)
    code = cli_main.main(["place"])
    return code, capsys.readouterr()


def test_warnings_before_an_error_are_dropped_after_a_result_shown(monkeypatch, capsys):
    from autobones.errors import AutobonesError

    def fails(args):
        warnings.warn("overflow encountered in multiply", RuntimeWarning)
        raise AutobonesError("x.obj: an outlier")

    def works(args):
        warnings.warn("overflow encountered in multiply", RuntimeWarning)
        print("x.glb: done")
        return 0

    code, out = _main(monkeypatch, capsys, fails)
    assert code == 2 and out.err == "autobones place: error: x.obj: an outlier\n" and out.out == ""
    with pytest.warns(RuntimeWarning, match="overflow"):
        code, out = _main(monkeypatch, capsys, works)
    assert code == 0 and out.out == "x.glb: done\n"


def test_control_characters_in_a_message_are_escaped(monkeypatch, capsys):
    from autobones.errors import AutobonesError

    def fails(args):
        raise AutobonesError("a\nb\r\x1b[2J.obj: no faces")

    code, out = _main(monkeypatch, capsys, fails)
    assert code == 2 and out.err == "autobones place: error: a\\nb\\r\\x1b[2J.obj: no faces\n"


def test_debug_still_raises(monkeypatch, capsys):
    from autobones.errors import AutobonesError
    from cli import main as cli_main

    def fails(args):
        raise AutobonesError("x")

    monkeypatch.setitem(cli_main.COMMANDS, "place", fails)
    with pytest.raises(AutobonesError):
        cli_main.main(["place", "--debug"])


def test_view_folder_lists_past_a_deep_sidecar_and_a_deep_glb(tmp_path, placed_rig):
    """One rig nested 100k deep in its sidecar, another in its glb's JSON chunk: `view FOLDER` still lists
    the good rig; the first is shown unviewable, the second is not a rig (was: RecursionError, no page)."""
    import shutil
    import struct

    from autobones.view.site import batch_listing, open_site

    for stem in ("good", "deep_sidecar"):
        for suffix in (".glb", ".rig.json", ".weights.npz"):
            shutil.copy(placed_rig.with_name("robot" + suffix), tmp_path / (stem + suffix))
    (tmp_path / "deep_sidecar.rig.json").write_bytes(b"[" * 100_000 + b"]" * 100_000)
    chunk = b"[" * 100_000 + b"]" * 100_000
    (tmp_path / "deep_glb.glb").write_bytes(b"glTF" + struct.pack("<II", 2, 20 + len(chunk))
                                            + struct.pack("<I4s", len(chunk), b"JSON") + chunk)
    listing = {f["output"]: f for f in batch_listing(open_site(tmp_path))["files"]}
    assert sorted(listing) == ["deep_sidecar.glb", "good.glb"]
    assert listing["good.glb"]["viewable"] and not listing["deep_sidecar.glb"]["viewable"]


def test_the_corpus_covers_items_5_and_6():
    """Each tampered rig and bad value issue #33 items 5 and 6 name is a refused case with a reason."""
    for name in ("sidecar_labels_out_of_int8", "sidecar_vertex_count_infinity", "sidecar_vertex_count_1e12",
                 "sidecar_landmarks_list", "sidecar_muscles_string", "sidecar_frame_2x2", "sidecar_head_size_0",
                 "definitions_au_lots", "sidecar_definitions_au_lots", "export_proc", "glb_json_deep",
                 "mesh_scale_1e150", "mesh_scale_1e-40", "pose_au_1e308", "capture_weight_1e308",
                 "definitions_nan_smoothing", "build_rig_centimetres"):
        assert CASES[name][2].expect == "refused" and CASES[name][2].why, name


# --------------------------------------------------------------------------------------------------
# a full disk during a USD export; the writers' finiteness guard

def _tiny_tmpfs(folder):
    """``folder`` mounted as a 64 kB tmpfs (root only); False where mounting is not allowed."""
    folder.mkdir()
    try:
        r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(folder)], capture_output=True,
                           timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return r.returncode == 0


def test_a_full_disk_during_a_usd_export_is_one_line_and_leaves_nothing(tmp_path, transferred_rig, monkeypatch,
                                                                       capsys):
    """On a 64 kB tmpfs (where it can be mounted; else the writer made to fail with ENOSPC, as a full disk
    does): one line, exit 2, no partial file (was: a traceback and 11,061 lines from the USD library)."""
    import errno

    full = tmp_path / "full"
    mounted = _tiny_tmpfs(full)
    try:
        if mounted:
            env = dict(os.environ, PYTHONPATH=str(ROOT))
            for ext in (".usdc", ".usda"):
                r = subprocess.run(CLI + ["export", str(transferred_rig), "-o", str(full / ("x" + ext))],
                                   env=env, capture_output=True, text=True, timeout=120)
                assert r.returncode == 2 and r.stdout == "", (r.returncode, r.stdout)
                assert r.stderr.count("\n") == 1 and "no space left on device" in r.stderr, r.stderr
                assert os.listdir(full) == []
        else:
            from autobones.export import usd
            from cli import main as cli_main

            full.mkdir(exist_ok=True)

            def disk_full(stage, tmp, out_path, ext):
                with open(tmp, "wb") as fh:
                    fh.write(b"PXR-USDC" + b"\0" * 100)  # a partial file, then the disk is full
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

            monkeypatch.setattr(usd, "_export", disk_full)
            code = cli_main.main(["export", str(transferred_rig), "-o", str(full / "x.usdc")])
            err = capsys.readouterr().err
            assert code == 2 and err.count("\n") == 1 and "no space left on device" in err.lower(), err
            assert os.listdir(full) == []
    finally:
        if mounted:
            subprocess.run(["umount", str(full)], timeout=30)


def test_the_writers_never_write_a_non_finite_value(tmp_path):
    """glb (rig, posed mesh, animation keys), OBJ and USD refuse NaN and infinity (a finite 1e300 is
    infinite in float32) and write nothing: the last line of defence behind every input check."""
    import numpy as np

    from autobones.errors import AutobonesError
    from autobones.io.gltf import add_animation, glb_bytes
    from autobones.io.obj import write_obj
    from autobones.io.posed import write_posed_mesh

    V, F = bad_inputs.robot()
    for bad in (np.nan, np.inf, 1e300):
        W = V.copy()
        W[7, 1] = bad
        for name in ("x.obj", "x.glb") if bad != 1e300 else ("x.glb",):  # an OBJ keeps float64's 1e300
            with pytest.raises(AutobonesError, match=r"not written: 1 NaN or infinite value in"):
                write_posed_mesh(tmp_path / name, W, F)
        with pytest.raises(AutobonesError, match="positions"):
            glb_bytes(W, F)
        with pytest.raises(AutobonesError, match="morph target smile"):
            glb_bytes(V, F, morph_targets=[("smile", W - V)])
    with pytest.raises(AutobonesError, match="vertices"):
        W = V.copy()
        W[0, 0] = np.nan
        write_obj(tmp_path / "y.obj", W, F)
    assert os.listdir(tmp_path) == []
    with pytest.raises(AutobonesError, match="weights keys"):
        add_animation({}, b"", "a", [0.0, 1.0], [(0, "weights", [[0.0], [1e300]])])


def test_usd_stage_refuses_non_finite_points(transferred_rig):
    import numpy as np

    from autobones.errors import AutobonesError
    from autobones.export import usd

    src = usd.read_rig_source(transferred_rig)
    src.rig.vertices = np.array(src.rig.vertices)
    src.rig.vertices[3, 2] = 1e300  # finite in float64, infinite in USD's float32 points
    with pytest.raises(AutobonesError, match="points"):
        usd.build_stage(src)


def test_schema_refuses_what_autobones_never_writes(placed_rig):
    """rig_schema on its own: the sidecar autobones wrote passes; each edit is named by its key."""
    from autobones.io.rig_schema import SchemaError, check_definitions, check_sidecar
    from autobones.expressions.definitions import MODEL_DEFAULTS
    from autobones.generic_rig import expressions_path

    meta = json.loads(placed_rig.with_name("robot.rig.json").read_text())
    assert check_sidecar(meta, MODEL_DEFAULTS) == meta["vertex_count"]
    for path, value, needle in ((("bones", 0, "head"), [0, 0], r"bones\[0\].head is a list of 2"),
                                (("bones", 1, "parent"), "nobody", "not a bone listed before it"),
                                (("labels", 0), -1, "labels holds -1"),
                                (("labels", 0), 1.5, "labels holds 1.5"),
                                (("frame", "rotation", 0, 0), -1.0, "not a rotation"),
                                (("frame", "origin"), "here", "frame.origin is the string"),
                                (("vertex_count",), True, "vertex_count is true"),
                                (("reliable_fraction",), 2.0, r"reliable_fraction is 2, expected a number in \[0, 1\]")):
        edited = json.loads(json.dumps(meta))
        node = edited
        for k in path[:-1]:
            node = node[k]
        node[path[-1]] = value
        with pytest.raises(SchemaError, match=needle):
            check_sidecar(edited, MODEL_DEFAULTS)
    defs = json.loads(open(expressions_path()).read())
    check_definitions(defs, MODEL_DEFAULTS)
    defs["model"]["smoothing"] = float("nan")  # a dict through the API never passed the JSON reader
    with pytest.raises(SchemaError, match="definitions.model.smoothing is nan"):
        check_definitions(defs, MODEL_DEFAULTS)


def test_schema_refuses_a_whole_number_past_float_range():
    """JSON's whole numbers have no bound: 10**400 in definitions or a sidecar is one SchemaError naming
    its key (float() raised OverflowError, a traceback, where 1e400 was refused)."""
    from autobones.io.rig_schema import SchemaError, check_finite_tree, number

    with pytest.raises(SchemaError, match=r"defs\.a\[1\] is a whole number too large"):
        check_finite_tree({"a": [1, 10 ** 400]}, "defs")
    with pytest.raises(SchemaError, match="head_size is a whole number too large"):
        number(10 ** 400, "head_size")
    assert number(3, "n") == 3.0
