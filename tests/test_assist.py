"""Assisted landmarks (issue #35 part 2): the contract's other names from five given ones, by the
generic head's fit (autobones.landmarks.assist), and ``autobones landmarks HEAD --assist PARTIAL``."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from shared_data import ROOT, data

from autobones.errors import AutobonesError
from autobones.io.landmarks import NAMES, read_landmarks, write_landmarks
from autobones.io.mesh import load_mesh
from autobones.landmarks.assist import REQUIRED, assist_landmarks, confidence, read_off


def _head(rel):
    V, F = load_mesh(data(f"{rel}.obj"))
    return V, F, read_landmarks(data(f"{rel}.landmarks.json"))


@pytest.fixture(scope="module")
def identity000():
    V, F, truth = _head("ict/identity000")
    return V, F, truth, assist_landmarks(V, F, {n: truth[n] for n in REQUIRED})


def _errors(points, truth):
    unit = np.linalg.norm(truth["exocanthion_l"] - truth["exocanthion_r"])
    return {n: 100 * np.linalg.norm(points[n] - truth[n]) / unit for n in truth if n not in REQUIRED}


def test_proposals_on_an_ict_identity_are_within_the_measured_bound(identity000):
    # measured 2026-12-04: mean 9.6 %, worst 18.2 % (palpebrale_superius_l) of ex-ex over the 22 published
    # names that were not given (benchmarks/landmarks.py --assist); bounds with margin
    V, F, truth, out = identity000
    err = _errors(out.points, truth)
    assert len(err) == 22
    assert np.mean(list(err.values())) < 11.0, err
    assert max(err.values()) < 22.0, err


def test_every_contract_name_is_returned_given_ones_unchanged(identity000):
    V, F, truth, out = identity000
    assert list(out.points) == [n for n in NAMES if n in out.points]
    assert set(out.points) | set(out.omitted) == set(NAMES)
    for n in REQUIRED:
        np.testing.assert_array_equal(out.points[n], truth[n])
        assert out.confidence[n] == 1.0
    conf = np.array([out.confidence[n] for n in out.points if n not in REQUIRED])
    assert ((conf >= 0) & (conf < 1)).all()
    assert out.unit == pytest.approx(np.linalg.norm(truth["exocanthion_l"] - truth["exocanthion_r"]))
    assert out.frame is not None and out.frame.up == "+y" and out.frame.front == "+z"


def test_the_same_input_gives_the_same_output_bit_for_bit(identity000):
    V, F, truth, out = identity000
    again = assist_landmarks(V, F, {n: truth[n] for n in REQUIRED})
    assert list(again.points) == list(out.points)
    for n in out.points:
        assert again.points[n].tobytes() == out.points[n].tobytes(), n
        assert again.confidence[n] == out.confidence[n], n


def test_a_rotated_millimetre_copy_maps_back(identity000):
    # measured: 1.2e-13 % of ex-ex (the fit is equivariant); bound 0.01 %
    V, F, truth, out = identity000
    R = Rotation.from_euler("xyz", [30, -70, 110], degrees=True).as_matrix()
    turned = assist_landmarks(1000 * V @ R.T, F, {n: 1000 * R @ truth[n] for n in REQUIRED})
    assert set(turned.points) == set(out.points)
    for n in out.points:
        assert np.linalg.norm(turned.points[n] @ R / 1000 - out.points[n]) < 1e-4 * out.unit, n
        assert turned.confidence[n] == pytest.approx(out.confidence[n], abs=1e-9)


def test_an_animal_gets_proposals_too():
    V, F = load_mesh(data("zoo/cowHead.obj"))
    truth = read_landmarks(ROOT / "tests" / "landmarks" / "cowHead.landmarks.json")
    out = assist_landmarks(V, F, {n: truth[n] for n in REQUIRED})
    assert len(out.points) + len(out.omitted) == len(NAMES)
    assert len(out.points) >= 30
    assert all(np.isfinite(p).all() for p in out.points.values())


@pytest.mark.parametrize("change, words", [
    (lambda g: g.pop("cheilion_r"), "missing cheilion_r"),
    (lambda g: g.update(nose=g["pronasale"]), "unknown landmark names nose"),
    (lambda g: g.update(pronasale=np.array([np.nan, 0.0, 0.0])), "pronasale"),
    (lambda g: g.update(exocanthion_l=g["exocanthion_r"], exocanthion_r=g["exocanthion_l"],
                        cheilion_l=g["cheilion_r"], cheilion_r=g["cheilion_l"]), "exchanged"),
    (lambda g: g.update(pronasale=g["pronasale"] + 100.0), "pronasale"),
])
def test_bad_given_landmarks_are_refused(change, words):
    V, F, truth = _head("menpo3d/james")
    given = {n: truth[n].copy() for n in REQUIRED}
    change(given)
    with pytest.raises(AutobonesError, match=words):
        assist_landmarks(V, F, given)


def test_confidence_is_one_at_a_given_point_and_falls_with_distance_and_residual():
    c = confidence([0.0, 0.5, 1.0, 2.0], [0.0] * 4, [1.0] * 4)
    assert c[0] == 1.0 and c[2] == pytest.approx(0.5) and (np.diff(c) < 0).all()
    assert confidence([0.0], [0.1], [1.0])[0] == pytest.approx(np.exp(-1))
    assert confidence([0.0], [0.0], [-0.5])[0] == 0.0


def test_read_off_carries_points_by_their_barycentric_coordinates():
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    F = np.array([[0, 1, 2], [1, 3, 2]])
    P = 2.0 * V + [0.0, 0.0, 5.0]        # each vertex's point on a "target": scaled and shifted
    Q, face = read_off(np.array([[0.25, 0.25, 0.0], [0.75, 0.75, 0.3]]), V, F, P)
    np.testing.assert_allclose(Q, [[0.5, 0.5, 5.0], [1.5, 1.5, 5.0]], atol=1e-12)
    assert face.tolist() == [0, 1]


CLI = [sys.executable, "-m", "cli.main"]


def _run(args, cwd):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run(CLI + args, cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


def test_cli_assist_writes_every_name_with_confidence(tmp_path):
    V, F, truth = _head("menpo3d/james")
    write_landmarks(tmp_path / "five.json", {n: truth[n] for n in REQUIRED})
    r = _run(["landmarks", str(data("menpo3d/james.obj")), "--assist", "five.json", "-o", "out.json"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert "5 given" in r.stdout
    written = json.loads((tmp_path / "out.json").read_text())
    got = read_landmarks(tmp_path / "out.json")
    assert len(got) >= 40 and set(written["confidence"]) == set(got)
    for n in REQUIRED:
        np.testing.assert_allclose(got[n], truth[n], atol=1e-9)


@pytest.mark.parametrize("extra, words", [
    ([], "missing cheilion_l"),
    (["--from", "four.json"], "give one of them"),
])
def test_cli_assist_bad_input_is_one_line_exit_2_nothing_written(tmp_path, extra, words):
    V, F, truth = _head("menpo3d/james")
    write_landmarks(tmp_path / "four.json", {n: truth[n] for n in REQUIRED if n != "cheilion_l"})
    r = _run(["landmarks", str(data("menpo3d/james.obj")), "--assist", "four.json", "-o", "out.json"] + extra,
             tmp_path)
    assert r.returncode == 2
    assert words in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not (tmp_path / "out.json").exists()
