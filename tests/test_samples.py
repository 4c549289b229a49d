"""`autobones samples DIR`: every file written, each a valid input, licences recorded; refusals write nothing."""
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from shared_data import ROOT

CLI = [sys.executable, "-m", "cli.main"]


def run(args, cwd):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run(CLI + args, cwd=cwd, env=env, capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    cwd = tmp_path_factory.mktemp("samples")
    r = run(["samples", "s"], cwd)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    assert r.stdout.count("\n") == 1 and r.stdout.startswith("s: 14 files")
    return cwd / "s"


def test_every_sample_file_is_written(written):
    from autobones.samples import NAMES

    assert sorted(os.listdir(written)) == sorted(NAMES)
    assert all((written / n).stat().st_size > 0 for n in NAMES)


@pytest.mark.parametrize("head, at_least", [("default_head", 44), ("scan", 27), ("bust", 20), ("robot", 13),
                                            ("goat", 14)])
def test_each_head_loads_and_its_landmarks_lie_on_it(written, head, at_least):
    import autobones
    from autobones.io.landmark_checks import validate_landmarks
    from autobones.io.landmarks import read_landmarks

    V, F = autobones.load_mesh(written / f"{head}.obj")
    assert len(V) > 1000 and len(F) > 500
    lm = read_landmarks(written / f"{head}.landmarks.json")
    # transfer needs 10 shared names; the check refuses points off the surface or in other units
    assert len(validate_landmarks(lm, V, F, min_count=10, source=head)) >= at_least


def test_the_meshes_are_the_licensed_originals(written):
    """The scan is menpo3d's james, bit for bit as tests/data stores it (the landmarks were made in its frame)."""
    from autobones.io.mesh import load_mesh
    from shared_data import data

    V1, F1 = load_mesh(written / "scan.obj")
    V0, F0 = load_mesh(data("menpo3d/james.obj"))
    assert np.array_equal(V0, V1) and np.array_equal(F0, F1)


def test_the_picked_points_file_matches_the_json(written):
    from autobones.io.landmarks import read_landmarks

    a, b = read_landmarks(written / "goat.pp"), read_landmarks(written / "goat.landmarks.json")
    assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)


def test_the_take_is_a_capture_animate_reads(written):
    from autobones.arkit.capture import read_capture

    cap = read_capture(str(written / "take.csv"), fps=60)
    assert len(cap.times) >= 60 and len(cap.weights) == 52
    assert 0.5 < cap.weights["mouthSmileLeft"].max() <= 1 and cap.weights["eyeBlinkLeft"].max() == 1
    assert cap.angles["HeadYaw"].max() > 0.1


ALLOWED = ("MIT", "BSD-3-Clause", "CC0", "CC BY 3.0", "CC BY 4.0", "Apache-2.0")


def test_licences_name_every_file_and_allow_redistribution(written):
    from autobones.samples import NAMES

    text = (written / "LICENSES.md").read_text()
    rows = [r for r in text.splitlines() if r.startswith("| `")]
    for name in NAMES[:-2]:  # every head, landmark file, goat.pp and take.csv: a row naming it and its licence
        row = next((r for r in rows if f"`{name}`" in r), None)
        assert row is not None, f"{name} has no row in LICENSES.md"
        licence = row.split("|")[3]
        assert any(a in licence for a in ALLOWED) and not re.search(r"\bN[CD]\b", licence), row
    assert "Redistribution and use in source and binary forms" in text  # BSD asks for its text


def test_a_folder_that_holds_anything_is_refused_and_left_alone(tmp_path):
    (tmp_path / "s").mkdir()
    (tmp_path / "s" / "mine.txt").write_text("keep")
    r = run(["samples", "s"], tmp_path)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.count("\n") == 1 and "not empty" in r.stderr and "--force" in r.stderr
    assert os.listdir(tmp_path / "s") == ["mine.txt"] and sorted(os.listdir(tmp_path)) == ["s"]
    r = run(["samples", "s", "--force"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "s" / "mine.txt").read_text() == "keep" and len(os.listdir(tmp_path / "s")) == 15


@pytest.mark.parametrize("target, message", [("nope/s", "does not exist; create it first"),
                                             ("afile", "exists and is not a folder")])
def test_bad_destinations_are_one_line_and_write_nothing(tmp_path, target, message):
    (tmp_path / "afile").write_text("x")
    r = run(["samples", target], tmp_path)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and message in r.stderr, r.stderr
    assert sorted(os.listdir(tmp_path)) == ["afile"]


def test_the_empty_folder_the_user_is_in(tmp_path):
    """`autobones samples .` in a new empty folder (it cannot be removed and replaced: it was a traceback)."""
    r = run(["samples", "."], tmp_path)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    from autobones.samples import NAMES

    assert sorted(os.listdir(tmp_path)) == sorted(NAMES)
    assert (tmp_path / "default_head.obj").stat().st_mode & 0o777 == 0o666 & ~_umask()


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_a_failure_half_way_leaves_no_folder(tmp_path, monkeypatch):
    from autobones import samples

    real, calls = samples.sample_bytes, []

    def failing(name):
        calls.append(name)
        if len(calls) == 5:
            raise OSError("disk full")
        return real(name)

    monkeypatch.setattr(samples, "sample_bytes", failing)
    with pytest.raises(OSError):
        samples.write_samples(tmp_path / "s")
    assert os.listdir(tmp_path) == []  # neither the folder nor the staging folder
    (tmp_path / "s").mkdir()   # an existing empty folder: staged inside it, still nothing left
    calls.clear()
    with pytest.raises(OSError):
        samples.write_samples(tmp_path / "s")
    assert os.listdir(tmp_path / "s") == []


def test_path_gives_a_written_sample_and_refuses_unknown_names():
    from autobones import AutobonesError, samples

    assert samples.path("robot.obj").is_file()
    with pytest.raises(AutobonesError, match="not a sample file"):
        samples.path("robot.ply")
