"""One set of CLI conventions (issue #36): -v prints stages on every command, a clock only on a terminal,
names checked before heavy work, and every error message one grammatical line."""
import ast
import os
import re
import subprocess
import sys
import time

import pytest

from shared_data import ROOT

CLI = [sys.executable, "-m", "cli.main"]
STAGE = re.compile(r"^autobones: [a-z][\w-]* +\d+\.\d\d s$", re.M)


def run(args, cwd, **kw):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run(CLI + args, cwd=cwd, env=env, capture_output=True, text=True, timeout=300, **kw)


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    """A folder with the samples (s/) and the robot transferred with its ARKit shapes (robot.glb)."""
    cwd = tmp_path_factory.mktemp("conventions")
    assert run(["samples", "s"], cwd).returncode == 0
    r = run(["transfer", "s/robot.obj", "--landmarks", "s/robot.landmarks.json", "--arkit", "-o", "robot.glb"], cwd)
    assert r.returncode == 0, r.stderr
    (cwd / "in").mkdir()
    (cwd / "in" / "robot.obj").write_bytes((cwd / "s" / "robot.obj").read_bytes())
    return cwd


# one case per command: each must print its stages with -v (a command added without one fails here)
VERBOSE = {
    "samples": ["samples", "s2"],
    "place": ["place", "s/robot.obj", "--density", "sparse", "-o", "p.glb"],
    "transfer": ["transfer", "s/goat.obj", "--landmarks", "s/goat.pp", "-o", "g.glb"],
    "pose": ["pose", "robot.glb", "--au", "12", "-o", "smile.obj"],
    "landmarks": ["landmarks", "s/goat.obj", "--from", "s/goat.pp", "-o", "goat2.landmarks.json"],
    "build-rig": ["build-rig", "s/default_head.obj", "--landmarks", "s/default_head.landmarks.json", "-o", "myrig"],
    "batch": ["batch", "in", "-o", "out", "--density", "sparse"],
    "export": ["export", "robot.glb", "-o", "robot.usda"],
    "animate": ["animate", "robot.glb", "--capture", "s/take.csv", "-o", "anim.glb"],
    "view": ["view", "robot.glb", "--no-browser"],
    "blender-addon": ["blender-addon", "-o", "addon.zip"],
}


def test_every_command_has_a_verbose_case():
    sys.path.insert(0, str(ROOT))
    from cli.commands import COMMANDS

    assert set(VERBOSE) == set(COMMANDS)


@pytest.mark.parametrize("command", sorted(VERBOSE))
def test_verbose_prints_stages_on_every_command(work, command):
    args = VERBOSE[command] + ["-v"]
    if command == "view":  # serves until stopped: read its first lines, then stop it
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        p = subprocess.Popen(CLI + args, cwd=work, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            url = p.stdout.readline()
            err = p.stderr.readline() + p.stderr.readline()
        finally:
            p.terminate()
            p.wait(10)
        assert url.startswith("http://127.0.0.1:")
    else:
        r = run(args, work)
        assert r.returncode == 0, r.stderr
        err = r.stderr
    assert STAGE.search(err), f"autobones {command} -v printed no stage line:\n{err}"


def test_without_verbose_a_pipe_gets_no_stages_and_no_clock(work):
    r = run(["pose", "robot.glb", "--expression", "happiness", "-o", "h.obj"], work)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    assert r.stdout.count("\n") == 1 and r.stdout.startswith("h.obj: happiness 1")


def test_a_terminal_sees_a_ticking_clock_which_then_goes(work):
    import pty

    master, slave = pty.openpty()
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.Popen(CLI + ["place", "s/scan.obj", "--density", "sparse", "-o", "tty.glb"], cwd=work, env=env,
                         stdout=subprocess.PIPE, stderr=slave, text=True)
    os.close(slave)
    seen = b""
    while True:
        try:
            chunk = os.read(master, 4096)
        except OSError:  # the child closed the terminal
            break
        if not chunk:
            break
        seen += chunk
    out, _ = p.communicate(timeout=120)
    os.close(master)
    assert p.returncode == 0 and out.startswith("tty.glb:")
    text = seen.decode(errors="replace")
    assert "autobones place: placing bones" in text and re.search(r"\d\d:\d\d", text), text
    assert "\r" in text  # redrawn in place (and cleared at the end: leave=False)


def _main(args, capsys):
    sys.path.insert(0, str(ROOT))
    from cli.main import main

    code = main(args)
    return code, capsys.readouterr()


@pytest.mark.parametrize("args, needle", [
    (["--expression", "hapiness"], "unknown expression 'hapiness'; known: surprise"),
    (["--au", "99"], "unknown action unit '99'"),
    (["--muscle", "zygomatic=1"], "unknown muscle 'zygomatic'"),
    (["--eyelids", "middle=1"], "unknown eyelid 'middle'"),
    (["--arkit", "jawopen"], "did you mean 'jawOpen'"),
])
def test_pose_checks_names_before_building_the_model(work, monkeypatch, capsys, args, needle):
    from autobones.rig import Rig

    def never(*a, **k):
        raise AssertionError("the skin/muscle model was built before the names were checked")

    monkeypatch.setattr(Rig, "expression_model", never)
    monkeypatch.chdir(work)
    code, cap = _main(["pose", "robot.glb", "-o", "typo.obj", *args], capsys)
    assert code == 2 and needle in cap.err and cap.err.count("\n") == 1, cap.err
    assert not (work / "typo.obj").exists()


def test_export_naming_its_own_input_says_so(work, capsys, monkeypatch):
    monkeypatch.chdir(work)
    before = (work / "robot.glb").read_bytes()
    code, cap = _main(["export", "robot.glb", "-o", "robot.glb"], capsys)
    assert code == 2 and "input" in cap.err and "suffix" not in cap.err and ".fbx" not in cap.err, cap.err
    assert (work / "robot.glb").read_bytes() == before


def test_batch_scheduler_without_dask_refuses_before_the_output_folder(work, capsys, monkeypatch):
    monkeypatch.chdir(work)
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    code, cap = _main(["batch", "in", "-o", "no_dask_out", "--scheduler", "tcp://127.0.0.1:1"], capsys)
    assert code == 2 and "pip install 'autobones[dask]'" in cap.err and cap.err.count("\n") == 1, cap.err
    assert not (work / "no_dask_out").exists()


def test_batch_report_claims_no_detected_landmarks_for_a_file_that_did_not_load(tmp_path):
    from autobones.batch import make_options, run_batch

    (tmp_path / "in").mkdir()
    (tmp_path / "in" / "broken.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    report = run_batch(tmp_path / "in", tmp_path / "out", make_options(transfer=True), jobs=1)
    (rec,) = report["files"]
    assert rec["status"] == "failed" and "only 1 face;" in rec["error"]
    assert rec.get("landmarks") is None


def test_one_naming_rule_for_outputs(work, tmp_path, capsys, monkeypatch):
    """place, transfer and batch name a head's rig alike: NAME.rig.glb, NAME.rig.json, NAME.weights.npz
    (batch wrote NAME.glb before)."""
    import shutil

    (tmp_path / "in").mkdir()
    for name in ("robot.obj", "robot.landmarks.json"):
        shutil.copy(work / "s" / name, tmp_path / "in" / name)
    expected = ["robot.rig.glb", "robot.rig.json", "robot.weights.npz"]
    for command, extra in (("place", ["--density", "sparse"]),
                           ("transfer", ["--landmarks", "../in/robot.landmarks.json"])):
        (tmp_path / command).mkdir()
        monkeypatch.chdir(tmp_path / command)
        code, cap = _main([command, "../in/robot.obj", *extra], capsys)
        assert code == 0, cap.err
        assert sorted(os.listdir(tmp_path / command)) == expected, command
    monkeypatch.chdir(tmp_path)
    code, cap = _main(["batch", "in", "-o", "batch", "--density", "sparse", "-q"], capsys)
    assert code == 0, cap.err
    assert sorted(os.listdir(tmp_path / "batch")) == ["batch_report.json", *expected]


# ---------------------------------------------------------------------------------- error strings

NOUNS = ("faces", "vertices", "landmarks", "names", "points", "values", "fields", "deltas", "labels",
         "coordinates", "pairs", "rows", "bones", "files", "muscles", "frames", "targets", "shapes")


def _count_then_plural():
    """Messages of AutobonesError / parser errors where a counted value meets a plural noun with no
    agreement: ``{len(F)} faces`` reads "1 faces" when there is one (use errors.counted)."""
    bad = []
    for folder in (ROOT / "autobones", ROOT / "cli"):
        for path in folder.rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                name = getattr(node, "func", None)
                name = getattr(name, "id", None) or getattr(name, "attr", None)
                if not isinstance(node, ast.Call) or name not in ("AutobonesError", "error"):
                    continue
                for js in (n for a in node.args for n in ast.walk(a) if isinstance(n, ast.JoinedStr)):
                    for prev, a, b in zip([None] + js.values, js.values, js.values[1:]):
                        if not (isinstance(a, ast.FormattedValue) and isinstance(b, ast.Constant)):
                            continue
                        count = isinstance(a.value, ast.Call) and getattr(a.value.func, "id", "") in ("len", "int") \
                            or isinstance(a.value, ast.Name) and len(a.value.id) == 1
                        # the noun may follow a few qualifiers: "{n} NaN or infinite values"
                        words = []
                        for w in re.findall(r"[\w-]+|[^\w\s-]", str(b.value))[:4]:
                            if not re.fullmatch(r"[\w-]+", w) or w in ("of", "for", "in", "but", "the", "to", "at"):
                                break
                            words.append(w)
                        noun = next((w for w in words if w in NOUNS), None)
                        # "all {k} landmarks", "3 of {n} landmarks": two or more by what comes before
                        plural_by_context = isinstance(prev, ast.Constant) and re.search(r"(all| of) $", prev.value)
                        if count and noun and not plural_by_context:
                            bad.append(f"{path.relative_to(ROOT)}:{node.lineno}: {{{ast.unparse(a.value)}}} {noun}")
    return bad


def test_no_message_counts_one_with_a_plural_noun():
    assert _count_then_plural() == []


def _grammar(line):
    """What is wrong with one error line ('' when nothing)."""
    problems = []
    if re.search(r"(?<![\d.])1 (?!s\b)[a-z]+s\b", line) and not re.search(r"1 (is|was|has|does)\b", line):
        problems.append("1 + plural noun")
    if re.search(r"\b(\w+) \1\b", line, re.I):
        problems.append("doubled word")
    if line.count("(") != line.count(")") or line.count("[") != line.count("]"):
        problems.append("unbalanced brackets")
    if re.search(r"\s$|  |\bNone\b|\bnan\b|Traceback", line):
        problems.append("stray whitespace, None, nan or a traceback")
    return ", ".join(problems)


@pytest.mark.parametrize("args", [
    ["place", "one_face.obj"],
    ["place", "s/robot.obj", "--density", "lots"],
    ["place", "s/robot.obj", "--seed", "-1"],
    ["transfer", "s/robot.obj", "--landmarks", "one.landmarks.json"],
    ["pose", "robot.glb", "--expression", "hapiness"],
    ["pose", "robot.glb", "--gaze", "1"],
    ["pose", "robot.glb", "-o", "x.fbx"],
    ["animate", "robot.glb", "--capture", "s/take.csv", "-o", "x.txt"],
    ["export", "robot.glb", "-o", "robot.glb"],
    ["export", "robot.glb", "-o", "x.abc"],
    ["landmarks", "s/goat.obj", "--from", "missing.pp"],
    ["landmarks", "s/goat.obj", "--assist", "one.landmarks.json"],
    ["samples", "s"],
    ["batch", "in", "-o", "in"],
    ["view", "nothing_here.glb", "--no-browser"],
    ["bogus"],
])
def test_error_messages_are_one_grammatical_line(work, capsys, monkeypatch, args):
    monkeypatch.chdir(work)
    (work / "one_face.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    (work / "one.landmarks.json").write_text('{"format": "autobones-landmarks/1", "landmarks": '
                                             '{"pronasale": [0.0, 2.9, 1.2]}}')
    before = sorted(os.listdir(work))
    try:
        code, cap = _main(args, capsys)
    except SystemExit as exc:  # argparse's own errors exit through the parser
        code, cap = exc.code, capsys.readouterr()
    assert code == 2 and cap.out == ""
    lines = cap.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("autobones"), cap.err
    assert re.match(r"autobones( [a-z-]+)?: error: \S", lines[0]), lines[0]
    assert _grammar(lines[0]) == "", f"{_grammar(lines[0])}: {lines[0]}"
    assert sorted(os.listdir(work)) == before  # nothing written


@pytest.mark.parametrize("line, problem", [
    ("autobones place: error: x.obj: only 1 faces; a head needs a real surface", "1 + plural noun"),
    ("autobones pose: error: the the rig", "doubled word"),
    ("autobones pose: error: (see autobones pose --help", "unbalanced brackets"),
    ("autobones pose: error: got None", "None"),
])
def test_the_grammar_check_catches_what_it_should(line, problem):
    assert problem in _grammar(line)
    assert _grammar("autobones place: error: x.obj: only 1 face; a head took 1.5 s (see autobones place --help)") == ""
