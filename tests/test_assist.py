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
from autobones.landmarks.assist import (REQUIRED, assist_landmarks, confidence, detection_agrees, read_off,
                                       with_detected)


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
    # measured 2026-12-04 with the built-in calibrated reading: mean 4.73 %, worst 10.8 %
    # (palpebrale_superius_r) of ex-ex over the 22 published names not given. In-sample: identity000 is
    # one of the nine heads the calibration was made from (benchmarks/landmarks.py --assist --reading
    # held-out measures heads it never saw); bounds with margin
    V, F, truth, out = identity000
    err = _errors(out.points, truth)
    assert len(err) == 22
    assert np.mean(list(err.values())) < 5.5, err
    assert max(err.values()) < 13.0, err
    assert err["menton"] < 1.0, err     # the human chin's profile rule (measured 0.06 %)


def test_detected_names_replace_the_fits_on_a_human_face(identity000):
    # the detector's names where it finds them (landmarks --assist does this): measured on identity000
    # mean 4.73 -> 3.72 % of ex-ex over the 22 names (pooled over the nine human heads and five copies
    # each: within 5 %, 47-50 % -> 70-76 %, benchmarks/README.md)
    V, F, truth, fit_only = identity000
    from autobones.landmarks.detect import detect_landmarks

    detected = detect_landmarks((V, F))
    out = assist_landmarks(V, F, {n: truth[n] for n in REQUIRED}, detected=detected)
    err, err0 = _errors(out.points, truth), _errors(fit_only.points, truth)
    assert np.mean(list(err.values())) < np.mean(list(err0.values())) - 0.5, (err, err0)
    for n in detected:
        if n not in REQUIRED:
            np.testing.assert_array_equal(out.points[n], detected[n])
            assert out.confidence[n] == detected.confidence[n]
    # names the detector lacks keep the fit's proposal
    for n in set(out.points) - set(detected):
        np.testing.assert_array_equal(out.points[n], fit_only.points[n])
    # and the result says which came from where
    assert out.human and fit_only.human and fit_only.detected == ()
    assert set(out.detected) == set(detected) - set(REQUIRED) and len(out.detected) >= 15


def test_a_detection_that_disagrees_with_the_given_names_is_not_used():
    given = {n: np.array(p, dtype=float) for n, p in zip(REQUIRED, ([1, 0, 0], [-1, 0, 0], [0, -0.5, 0.5],
                                                                        [0.5, -1, 0], [-0.5, -1, 0]))}
    points = {**given, "nasion": np.zeros(3), "menton": np.array([0.0, -2.0, 0.0])}
    conf = {n: 1.0 if n in given else 0.5 for n in points}
    close = {**{n: p + 0.05 for n, p in given.items()}, "nasion": np.array([0.0, 0.1, 0.0])}
    p, c = with_detected(points, conf, given, close, unit=2.0)
    np.testing.assert_array_equal(p["nasion"], [0.0, 0.1, 0.0])
    assert c["nasion"] == 1.0 and p["menton"] is points["menton"]
    for n in given:  # the given names are never replaced
        assert p[n] is given[n]
    far = {**{n: p + 0.5 for n, p in given.items()}, "nasion": np.array([0.0, 0.1, 0.0])}
    assert with_detected(points, conf, given, far, unit=2.0) == (points, conf)
    assert with_detected(points, conf, given, None, unit=2.0) == (points, conf)
    assert detection_agrees(given, close, 2.0) and not detection_agrees(given, far, 2.0)
    assert not detection_agrees(given, None, 2.0) and not detection_agrees(given, {"nasion": np.zeros(3)}, 2.0)


def test_the_generic_rigs_own_landmarks_read_off_are_within_the_measured_bound():
    # no calibration (reading = the generic's own landmarks): measured mean 8.9 %, worst 18.2 %
    from autobones.landmarks.assist import generic_skin

    V, F, truth = _head("ict/identity000")
    out = assist_landmarks(V, F, {n: truth[n] for n in REQUIRED}, reading=dict(generic_skin()[0].landmarks))
    err = _errors(out.points, truth)
    assert np.mean(list(err.values())) < 10.5, err
    assert max(err.values()) < 21.0, err


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
    # measured: 1.2e-13 % of ex-ex (the fit is equivariant), menton 0.015 % (the profile's point picked
    # among the plane cut's segment ends, computed in the copy's coordinates); bound 0.05 %
    V, F, truth, out = identity000
    R = Rotation.from_euler("xyz", [30, -70, 110], degrees=True).as_matrix()
    turned = assist_landmarks(1000 * V @ R.T, F, {n: 1000 * R @ truth[n] for n in REQUIRED})
    assert set(turned.points) == set(out.points)
    for n in out.points:
        assert np.linalg.norm(turned.points[n] @ R / 1000 - out.points[n]) < 5e-4 * out.unit, n
        assert turned.confidence[n] == pytest.approx(out.confidence[n], abs=1e-9)


def test_a_name_the_reading_lacks_is_omitted_with_the_reason():
    from autobones.landmarks.assist import generic_skin

    V, F, truth = _head("menpo3d/james")
    own = dict(generic_skin()[0].landmarks)
    reading = {n: p for n, p in own.items() if not n.startswith(("tragion", "superaurale", "subaurale"))}
    out = assist_landmarks(V, F, {n: truth[n] for n in REQUIRED}, reading=reading)
    assert sorted(out.omitted) == sorted(n for n in own if n not in reading)
    assert all("no such landmark" in why for why in out.omitted.values())
    assert set(out.points) == set(reading) | set(REQUIRED)


def test_an_animal_gets_proposals_too():
    V, F = load_mesh(data("zoo/cowHead.obj"))
    truth = read_landmarks(ROOT / "tests" / "landmarks" / "cowHead.landmarks.json")
    out = assist_landmarks(V, F, {n: truth[n] for n in REQUIRED})
    assert set(out.points) == set(NAMES) and not out.omitted
    # its ears and skull are far from a human's: the proposals there are offered at a low confidence
    assert min(out.confidence.values()) < 0.2
    assert all(np.isfinite(p).all() for p in out.points.values())
    assert not out.human and out.detected == ()     # a cow's five are no person's: the fit alone


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
    # james is a person: the line says where the names came from (the detector where it agrees)
    assert "a person's face" in r.stdout and "from the automatic detector" in r.stdout, r.stdout
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


def test_pull_back_inverts_read_off():
    from autobones.landmarks.assist_calibration import pull_back

    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    F = np.array([[0, 1, 2], [1, 3, 2]])
    P = 2.0 * V + [0.0, 0.0, 5.0]
    rest = np.array([[0.25, 0.25, 0.0], [0.75, 0.6, 0.0]])
    Q, _ = read_off(rest, V, F, P)
    np.testing.assert_allclose(pull_back(Q, V, F, P), rest, atol=1e-12)


def test_calibrate_weighs_every_family_the_same():
    from autobones.landmarks.assist_calibration import calibrate

    V = np.array([[0.0, 0, 0], [4, 0, 0], [0, 4, 0]])
    F = np.array([[0, 1, 2]])
    samples = [("a", {"nasion": [1.0, 1, 0]}), ("a", {"nasion": [1.0, 1, 0]}), ("a", {"nasion": [1.0, 1, 0]}),
               ("b", {"nasion": [2.0, 1, 0], "menton": [0.5, 0.5, 1.0]})]
    reading, counts = calibrate(samples, V, F)
    np.testing.assert_allclose(reading["nasion"], [1.5, 1.0, 0.0])      # not 1.25: family a is one vote
    np.testing.assert_allclose(reading["menton"], [0.5, 0.5, 0.0])      # snapped onto the skin
    assert counts == {"menton": 1, "nasion": 4}


def test_the_built_in_reading_lies_on_the_generic_skin():
    from autobones.geometry.closest import closest_points
    from autobones.landmarks.assist import generic_skin
    from autobones.landmarks.assist_calibration import built_in_reading

    reading = built_in_reading()
    g = generic_skin()[0]
    assert set(REQUIRED).isdisjoint(reading) and set(reading) <= set(NAMES) and len(reading) >= 30
    *_, d2 = closest_points(np.array(list(reading.values())), g.vertices, g.faces)
    assert np.sqrt(d2).max() < 1e-9
    ex = np.linalg.norm(g.landmarks["exocanthion_l"] - g.landmarks["exocanthion_r"])
    # calibrated, not arbitrary: every name within half an ex-ex of the generic's own
    assert max(np.linalg.norm(p - g.landmarks[n]) for n, p in reading.items()) < 0.5 * ex


def test_on_profile_puts_menton_at_the_lowest_midline_point_near_it():
    from autobones.landmarks.refine import midline_profile, on_profile, symmetry_plane

    V, F, truth = _head("menpo3d/james")
    unit = np.linalg.norm(truth["exocanthion_l"] - truth["exocanthion_r"])
    start = dict(truth, menton=truth["menton"] + [0.0, 0.1 * unit, 0.05 * unit])   # off, above the chin
    normal, offset = symmetry_plane(start)
    out = on_profile(V, F, start, normal, offset, unit, names=("menton",))
    assert abs(out["menton"] @ normal - offset) < 1e-6 * unit
    assert any(np.allclose(out["menton"], p) for p in midline_profile(V, F, normal, offset))
    assert np.linalg.norm(out["menton"] - truth["menton"]) < 0.05 * unit      # measured 0.008
    assert out["pronasale"] is start["pronasale"]


def test_cli_rig_without_assist_is_refused(tmp_path):
    r = _run(["landmarks", str(data("menpo3d/james.obj")), "--rig", "some_rig", "-o", "out.json"], tmp_path)
    assert r.returncode == 2 and "give --assist PARTIAL too" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out.json").exists()
