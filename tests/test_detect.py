"""Automatic landmarks (autobones.landmarks) and landmark previews (autobones.landmarks.preview).

The detector is MediaPipe, installed by the ``landmarks`` extra (tools/test-setup.sh);
these tests fail, never skip, without it.
"""
import itertools
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import autobones
from autobones.landmarks.detect import DetectedLandmarks, LandmarkDetector
from autobones.landmarks.mediapipe import MEDIAPIPE_POINTS
from autobones.landmarks.refine import refine, symmetry_plane
from autobones.landmarks.views import lift, weighted_median
from autobones.errors import AutobonesError
from autobones.io.landmarks import NAMES, mirror_name, read_landmarks
from autobones.io.mesh import load_mesh
from autobones.io.mesh import default_head
from autobones.orient import detect_frame
from shared_data import ROOT, data

CLI = [sys.executable, "-m", "cli.main"]


def run(args, cwd):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run(CLI + args, cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


def errors(found, truth):
    """Per-name distance in % of the true outer-eye-corner distance."""
    unit = np.linalg.norm(np.subtract(truth["exocanthion_l"], truth["exocanthion_r"]))
    return {n: 100 * np.linalg.norm(np.subtract(found[n], truth[n])) / unit for n in truth if n in found}


@pytest.fixture(scope="module")
def ict():
    path = data("ict/identity000.obj")
    V, F = load_mesh(path)
    return V, F, read_landmarks(data("ict/identity000.landmarks.json")), LandmarkDetector().detect(V, F)


# --- the pieces -------------------------------------------------------------------------------

def test_lift_interpolates_inside_and_reaches_the_nearest_covered_pixel():
    H, W = 6, 8
    rows, cols = np.mgrid[0:H, 0:W].astype(float)
    S = np.stack([cols, rows, cols + rows], axis=2)          # a plane: point = (x, y, x + y)
    S[:, 6:] = np.nan                                        # empty on the right
    P = lift(lambda r, c: S[r, c], np.isfinite(S[..., 0]), np.array([[2.25, 3.5], [6.5, 1.0], [7.0 + 3.5, 1.0]]),
             reach=2)
    np.testing.assert_allclose(P[0], [2.25, 3.5, 5.75])      # bilinear, exact on a plane
    np.testing.assert_allclose(P[1], [5.0, 1.0, 6.0])        # nearest covered pixel, 1.5 px away
    assert np.all(np.isnan(P[2]))                            # 5.5 px from cover: beyond reach


def test_weighted_median_ignores_missing_and_unweighted_candidates():
    X = np.array([[[0.0, 0, 0]], [[1.0, 1, 1]], [[2.0, 2, 2]], [[np.nan, 0, 0]], [[100.0, 100, 100]]])
    w = np.array([[1.0], [1.0], [1.0], [5.0], [0.0]])
    np.testing.assert_allclose(weighted_median(X, w)[0], [1.0, 1.0, 1.0])
    w2 = np.array([[1.0], [1.0], [3.0], [0.0], [0.0]])
    np.testing.assert_allclose(weighted_median(X, w2)[0], [2.0, 2.0, 2.0])
    assert np.all(np.isnan(weighted_median(X[:1], np.zeros((1, 1)))))


def _mirrored_set(normal, offset, rng):
    normal = normal / np.linalg.norm(normal)
    reflect = lambda p: p - 2 * (p @ normal - offset) * normal
    pts = {}
    for n in NAMES:
        if n.endswith("_l"):
            p = rng.normal(size=3)
            p += (offset + 0.5 + abs(rng.normal()) - p @ normal) * normal   # on the left side
            pts[n], pts[mirror_name(n)] = p, reflect(p)
        elif not n.endswith("_r"):
            p = rng.normal(size=3)
            pts[n] = p - (p @ normal - offset) * normal
    return pts, reflect


def test_symmetry_plane_is_recovered_from_mirrored_landmarks():
    rng = np.random.default_rng(0)
    normal = np.array([0.9, 0.3, -0.2])
    pts, _ = _mirrored_set(normal, 0.7, rng)
    n, c = symmetry_plane(pts)
    np.testing.assert_allclose(n, normal / np.linalg.norm(normal), atol=1e-12)
    assert c == pytest.approx(0.7)


def test_symmetry_plane_of_placed_landmarks_turns_and_scales_with_them():
    # hand-placed landmarks are never exact mirror images: the plane fitted to a lopsided set must
    # still be the same plane whatever frame and unit the file is in (a per-coordinate median of
    # the pairs' directions was not: 2 degrees on the zoo's bunny)
    from scipy.spatial.transform import Rotation
    rng = np.random.default_rng(1)
    pts, _ = _mirrored_set(np.array([0.2, 0.1, 1.0]), -0.3, rng)
    pts = {n: p + rng.normal(scale=0.05, size=3) for n, p in pts.items()}
    n0, c0 = symmetry_plane(pts)
    for seed in range(4):
        R = Rotation.random(random_state=seed).as_matrix()
        n, c = symmetry_plane({k: 1000.0 * (R @ p) + 5.0 for k, p in pts.items()})
        np.testing.assert_allclose(R.T @ n, n0, atol=1e-12)
        assert (c - 5.0 * n.sum()) / 1000.0 == pytest.approx(c0, abs=1e-9)
    # integer coordinates (a hand-written file, a grid) give the plane their floats give
    ints = {k: np.round(100.0 * p).astype(np.int64) for k, p in pts.items()}
    n, c = symmetry_plane(ints)
    n1, c1 = symmetry_plane({k: p.astype(np.float64) for k, p in ints.items()})
    np.testing.assert_array_equal(n, n1)
    assert c == c1


def test_refine_makes_pairs_mirror_images_and_flags_a_lopsided_pair():
    rng = np.random.default_rng(1)
    pts, _ = _mirrored_set(np.array([1.0, 0.05, 0.0]), 0.0, rng)
    noisy = {k: v + rng.normal(scale=0.01, size=3) for k, v in pts.items()}
    noisy["cheilion_l"] = noisy["cheilion_l"] + [0.0, 0.3, 0.0]            # one side far off
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    out, flagged = refine(V, np.array([[0, 1, 2]]), noisy, unit=1.0, max_mirror_error=0.1)
    n, c = symmetry_plane(out)
    reflect = lambda p: p - 2 * (p @ n - c) * n
    for name in out:
        if name.endswith("_l"):
            np.testing.assert_allclose(out[mirror_name(name)], reflect(out[name]), atol=1e-9)
        elif not name.endswith("_r"):
            assert abs(out[name] @ n - c) < 1e-9
    assert set(flagged) == {"cheilion_l", "cheilion_r"}


def test_point_table_names_are_contract_names():
    assert set(MEDIAPIPE_POINTS) <= set(NAMES)
    assert all(all(0 <= i < 468 for i in idx) for idx in MEDIAPIPE_POINTS.values())
    # the table is left/right consistent: every bilateral name has its mirror
    assert all(mirror_name(n) in MEDIAPIPE_POINTS for n in MEDIAPIPE_POINTS if n.endswith(("_l", "_r")))


# --- on real heads ----------------------------------------------------------------------------

def test_ict_identity_landmarks_match_the_published_ones(ict):
    V, F, truth, found = ict
    assert isinstance(found, DetectedLandmarks)
    err = errors(found, truth)
    assert len(err) >= 25, f"only {sorted(err)} found; dropped {found.dropped}"
    assert np.mean(list(err.values())) < 4.0, err            # issue target 3%: see benchmarks/landmarks.py
    assert max(err.values()) < 10.0, err
    assert set(found.confidence) == set(found) and all(0 <= c <= 1 for c in found.confidence.values())
    assert found.unit == pytest.approx(np.linalg.norm(np.subtract(truth["exocanthion_l"], truth["exocanthion_r"])),
                                       rel=0.1)


def test_one_view_still_gives_every_name(ict):
    """Seen only from the front, the ICT eye corners' nearest vertices are on the eyeballs (a
    surface facing away): their points still count instead of vanishing."""
    V, F, truth, _ = ict
    found = LandmarkDetector(views=((0.0, 0.0),)).detect(V, F)
    err = errors(found, truth)
    assert len(err) == 27 and np.mean(list(err.values())) < 6.0, err


def test_a_dense_scan_is_pictured_from_a_coarser_copy(ict, monkeypatch):
    """Above PICTURE_ABOVE vertices the pictures come from a vertex-clustered copy (here forced on
    ICT's 26.7k by lowering the threshold): the landmarks stay as accurate and on the full skin."""
    import autobones.landmarks.views as views
    from autobones.geometry.closest import closest_points

    V, F, truth, _ = ict
    monkeypatch.setattr(views, "PICTURE_ABOVE", 10000)
    monkeypatch.setattr(views, "PICTURE_VERTICES", 8000)
    Vp, Fp, skin, pictured_skin = views.pictured_mesh(V, F)
    assert skin.shape == (len(F),) and pictured_skin.shape == (len(Fp),)
    assert skin.sum() < len(F) and pictured_skin.sum() < len(Fp)    # ICT's eyes, teeth... are not skin
    assert len(Vp) < 0.5 * len(V)
    found = LandmarkDetector().detect(V, F)
    err = errors(found, truth)
    # the coarser copy costs 0.3-0.7% of ex-ex on ICT identities 000-002 (3.4 / 3.7 / 4.0% from the
    # full mesh, 4.0 / 4.0 / 4.7% from the copy, in the shape-only frame; 3.9 / 4.4 / 4.4% in the
    # frame read off the file's axes): the bound is that spread, not the full mesh's 4.0
    assert len(err) >= 25 and np.mean(list(err.values())) < 4.5 and max(err.values()) < 10.0, err
    P = np.array([found[n] for n in found])
    *_, d2 = closest_points(P, V, F)
    assert np.sqrt(d2).max() < 1e-9 * np.ptp(V, axis=0).max()  # on the input's own surface


def test_scan_landmarks_match_the_published_ones():
    path = data("menpo3d/james.obj")
    found = autobones.detect_landmarks(str(path))
    err = errors(found, read_landmarks(data("menpo3d/james.landmarks.json")))
    assert len(err) >= 25 and np.mean(list(err.values())) < 4.0 and max(err.values()) < 10.0, err


def test_a_leftover_vertex_far_away_does_not_hide_the_face():
    """A vertex no triangle uses, 20 head sizes off, framed into the pictures shrank the face to a few pixels:
    "no face found" on a head whose file landmarks transfer took."""
    V, F = load_mesh(data("menpo3d/james.obj"))
    far = np.vstack([V, V.mean(axis=0) + 20 * np.ptp(V, axis=0)])
    found = autobones.detect_landmarks((far, F))
    err = errors(found, read_landmarks(data("menpo3d/james.landmarks.json")))
    assert len(err) >= 25 and np.mean(list(err.values())) < 4.0, err


def test_detected_landmarks_are_on_the_surface_and_left_is_left(ict):
    from autobones.geometry.closest import closest_points

    V, F, _, found = ict
    P = np.array(list(found.values()))
    d = np.linalg.norm(closest_points(P, V, F)[0] - P, axis=1)
    assert d.max() < 1e-9 * np.ptp(V, axis=0).max() + 1e-12
    frame = found.frame
    for n in found:
        if n.endswith("_l"):
            assert frame.to_canonical(found[n][None])[0, 0] > frame.to_canonical(found[mirror_name(n)][None])[0, 0]


def test_same_landmarks_when_the_head_is_turned_and_in_millimetres(ict):
    V, F, _, found = ict
    # facing -X, Z up, millimetres (the ICT head is in centimetres): rotation + scale x10
    R = np.array([[0.0, 0, -1], [-1, 0, 0], [0, 1, 0]])      # +Z front -> -X, +Y up -> +Z
    assert np.allclose(R @ [0, 0, 1], [-1, 0, 0]) and np.allclose(R @ [0, 1, 0], [0, 0, 1])
    assert np.linalg.det(R) == pytest.approx(1.0)
    again = LandmarkDetector().detect(10.0 * V @ R.T, F)
    assert again.frame.up == "+z" and again.frame.front == "-x"
    back = {n: (again[n] / 10.0) @ R for n in again}
    assert set(back) == set(found)
    diff = max(np.linalg.norm(back[n] - found[n]) for n in found) / found.unit
    assert diff < 1e-3, diff


@pytest.mark.parametrize("mesh", ["misc/goathead.obj", "misc/robot_head_neutral.obj"])
def test_no_face_on_animals_and_cartoons(mesh):
    with pytest.raises(AutobonesError, match="no face found"):
        autobones.detect_landmarks(str(data(mesh)))


def test_back_of_the_head_has_no_face():
    V, F = default_head()
    back = F[(V[F][:, :, 2] < -0.02).all(axis=1)]           # the half behind the ears
    with pytest.raises(AutobonesError, match="no face found"):
        autobones.detect_landmarks((V, back))


def test_face_turned_in_its_file_is_found_and_squared(ict):
    """A head turned 40 degrees about its vertical (the frame finder only tries the file's axes)
    and a face told to look the wrong way: the search and the detector's own head pose find
    the face, and the landmarks are as good as on the upright head."""
    V, F, truth, found = ict
    a = np.radians(40.0)
    R = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    turned = LandmarkDetector().detect(V @ R.T, F)
    err = errors({n: p @ R for n, p in turned.items()}, truth)
    assert len(err) >= 25 and np.mean(list(err.values())) < 4.0, err
    back = autobones.detect_landmarks((V, F), front="-z")    # told the back of the head is the front
    assert np.mean(list(errors(back, truth).values())) < 4.0


def test_face_only_scan_is_never_read_from_the_inside():
    """A partial face scan seen from behind is a hollow mask that a face detector takes for a
    face (the hollow-face illusion). MediaPipe finds only that view of this low-resolution scan,
    so the right answer here is 'no face found' -- never mirrored landmarks."""
    V, F = load_mesh(data("misc/fran_cut.obj"))
    try:
        found = LandmarkDetector().detect(V, F)
    except AutobonesError as exc:
        assert "no face found" in str(exc)
        return
    Q = {n: found.frame.to_canonical(p[None])[0] for n, p in found.items()}
    assert Q["pronasale"][2] > max(Q["exocanthion_l"][2], Q["exocanthion_r"][2])


def test_face_only_capture_in_another_frame_is_read_right_side_up(ict):
    """ICT's head cut to its front half (a face-only capture: no back of the head, the opening
    behind) and turned Z-up: the frame stands it up (orient's open-shell rule), so the face is
    pictured upright and the landmarks match the published ones. Before, the opening was taken
    for a neck cut and the face was read looking at the floor (or refused)."""
    V, F, truth, _ = ict
    frame = detect_frame(V, F)
    C = frame.to_canonical(V)
    keep = C[:, 2] > C[:, 2].max() - 0.5 * np.ptp(C[:, 2])
    Fk = F[keep[F].all(axis=1)]
    used = np.unique(Fk)
    index = np.full(len(V), -1)
    index[used] = np.arange(len(used))
    Q = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # +Y up -> +Z up
    found = LandmarkDetector().detect(V[used] @ Q.T, index[Fk])
    err = errors({n: Q.T @ p for n, p in found.items()}, truth)
    # measured: 27 names, mean 3.5 %, the brows worst (up to 8.7 %)
    assert len(err) >= 25 and np.mean(list(err.values())) < 5.0 and max(err.values()) < 12.0, err


def test_implausible_landmarks_are_refused():
    from autobones.landmarks.orientation import plausible
    from autobones.orient import Frame

    frame = Frame(rotation=np.eye(3), origin=np.zeros(3), size=1.0)
    face = {"nasion": [0, 0.5, 0.1], "pronasale": [0, 0.3, 0.2], "stomion": [0, 0.1, 0.1], "menton": [0, -0.1, 0.05],
            "exocanthion_l": [0.3, 0.5, 0], "exocanthion_r": [-0.3, 0.5, 0],
            "cheilion_l": [0.15, 0.1, 0.05], "cheilion_r": [-0.15, 0.1, 0.05]}
    make = lambda d: DetectedLandmarks({k: np.array(v, float) for k, v in d.items()}, {}, {}, {}, [], frame, 1.0)
    assert plausible(make(face))
    upside_down = {k: [v[0], -v[1], v[2]] for k, v in face.items()}
    swapped = {mirror_name(k) if k[-2:] in ("_l", "_r") else k: v for k, v in face.items()}
    hollow = {k: [-v[0], v[1], -v[2]] for k, v in face.items()}    # seen from behind: turned 180 degrees
    hollow = {mirror_name(k) if k[-2:] in ("_l", "_r") else k: v for k, v in hollow.items()}
    assert not plausible(make(upside_down)) and not plausible(make(swapped)) and not plausible(make(hollow))


def test_missing_detector_names_the_extra(monkeypatch):
    from autobones.landmarks import detect

    monkeypatch.setitem(sys.modules, "mediapipe", None)
    monkeypatch.setitem(sys.modules, "mediapipe.python", None)
    monkeypatch.setitem(sys.modules, "mediapipe.python.solutions", None)
    with pytest.raises(AutobonesError, match=r"autobones\[landmarks\]"):
        detect.MediaPipeFaceMesh()(np.zeros((8, 8, 3), np.uint8))


def test_a_face_read_from_a_few_agreeing_names_is_refused(ict):
    """When the views agree on only a few names (a face read upside down or half off the surface),
    detection refuses with one message instead of returning those few."""
    V, F, _, _ = ict
    with pytest.raises(AutobonesError, match=r"no face read reliably .* only \d+ of 27 landmarks"):
        LandmarkDetector(max_disagreement=0.004).detect(V, F)


def test_views_that_disagree_drop_the_name():
    """A detector that puts one point in a different place in every view: that name is dropped."""
    from autobones.landmarks.mediapipe import MediaPipeFaceMesh

    real = MediaPipeFaceMesh()
    calls = itertools.count()

    class Jittery:
        points = MEDIAPIPE_POINTS

        def __call__(self, image):
            px = real(image)
            if px is not None:
                k = next(calls)
                px[list(MEDIAPIPE_POINTS["pronasale"]), 0] += (-1) ** k * 40.0 * k
            return px

    found = LandmarkDetector(detector=Jittery()).detect(*default_head())
    assert "pronasale" not in found and "pronasale" in found.dropped
    assert "nasion" in found


# --- transfer, batch and the command line ------------------------------------------------------

def test_transfer_finds_landmarks_itself(tmp_path):
    path = data("ict/identity002.obj")
    details = {}
    rig = autobones.transfer(str(path), details=details)
    assert rig.options["landmarks_source"] == "detected"
    assert len(rig.options["landmarks_used"]) >= 25
    assert set(rig.extra["landmark_confidence"]) == set(rig.extra["landmarks"])
    np.testing.assert_allclose(rig.weights.sum(axis=1), 1.0, atol=1e-6)
    # the jaw lands on the chin: the transferred jaw weight is high at the published menton
    truth = read_landmarks(data("ict/identity002.landmarks.json"))
    near = np.argmin(np.linalg.norm(rig.vertices - truth["menton"], axis=1))
    assert rig.fields["jaw_weight"][near] > 0.8


def test_cli_landmarks_writes_the_contract_json_and_a_preview(tmp_path):
    r = run(["landmarks", str(ROOT / "generic_rig" / "default_head.obj"), "-o", "head.landmarks.json",
             "--preview", "head.png"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stderr == "", r.stderr                           # MediaPipe's own logging stays quiet
    doc = json.loads((tmp_path / "head.landmarks.json").read_text())
    assert doc["format"] == "autobones-landmarks/1" and doc["mesh"] == "default_head.obj"
    lm = read_landmarks(tmp_path / "head.landmarks.json")
    assert len(lm) >= 25 and set(doc["confidence"]) == set(lm)
    from PIL import Image

    with Image.open(tmp_path / "head.png") as im:
        assert im.size[1] == 640 and im.size[0] >= 2 * 640
        pixels = np.asarray(im.convert("RGB"))
    assert (np.abs(pixels.astype(int) - [220, 30, 30]).sum(axis=2) < 30).sum() > 50   # red midline markers drawn


def test_cli_no_face_is_one_line_exit_2_and_nothing_written(tmp_path):
    r = run(["landmarks", str(data("misc/goathead.obj")), "-o", "goat.json", "--preview", "goat.png"], tmp_path)
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "no face found" in r.stderr and "--landmarks" in r.stderr, r.stderr
    assert os.listdir(tmp_path) == []
    r = run(["transfer", str(data("misc/goathead.obj")), "-o", "goat.glb"], tmp_path)
    assert r.returncode == 2 and "no face found" in r.stderr and os.listdir(tmp_path) == []


def test_cli_preview_from_a_given_file_on_an_animal(tmp_path):
    r = run(["landmarks", str(data("misc/goathead.obj")), "--from", str(ROOT / "tests" / "landmarks" /
                                                                        "goathead.landmarks.json"),
             "--preview", "goat.png"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert os.listdir(tmp_path) == ["goat.png"]


def test_cli_from_a_pp_file_converts_it(tmp_path):
    src = read_landmarks(ROOT / "tests" / "landmarks" / "goathead.landmarks.json")
    pp = tmp_path / "goat.pp"
    pp.write_text("<!DOCTYPE PickedPoints>\n<PickedPoints>\n" + "".join(
        f'<point name="{n}" x="{float(p[0])!r}" y="{float(p[1])!r}" z="{float(p[2])!r}" active="1"/>\n' for n, p in src.items())
        + "</PickedPoints>\n")
    r = run(["landmarks", str(data("misc/goathead.obj")), "--from", str(pp), "-o", "goat.landmarks.json"], tmp_path)
    assert r.returncode == 0, r.stderr
    back = read_landmarks(tmp_path / "goat.landmarks.json")
    assert set(back) == set(src) and all(np.array_equal(back[n], src[n]) for n in src)


def test_batch_transfer_detects_where_no_landmark_file_is(tmp_path):
    from autobones.batch import run_batch, make_options

    (tmp_path / "in").mkdir()
    os.symlink(data("menpo3d/james.obj"), tmp_path / "in" / "james.obj")
    report = run_batch(str(tmp_path / "in"), str(tmp_path / "out"), make_options(transfer=True))
    assert report["counts"]["ok"] == 1, report
    assert report["files"][0]["landmarks"] == "detected"
    side = json.loads((tmp_path / "out" / "james.rig.json").read_text())
    assert side["options"]["landmarks_source"] == "detected"


def test_turns_are_the_24_axis_rotations_after_the_identity_frame():
    from autobones.landmarks.orientation import turn_degrees, turns

    R = list(turns())
    assert R[0] is None and list(turns(search=False)) == [None]
    R = R[1:]
    assert len(R) == 24 and len({tuple(np.rint(M).astype(int).ravel()) for M in R}) == 24
    for M in R:
        assert np.allclose(M @ M.T, np.eye(3)) and np.isclose(np.linalg.det(M), 1.0)
    assert sum(turn_degrees(M, np.eye(3)) < 1e-6 for M in R) == 1
    assert sorted({round(turn_degrees(M, np.eye(3))) for M in R}) == [0, 90, 120, 180]


def test_quiet_stderr_restores_file_descriptor_2():
    from autobones.landmarks.mediapipe import quiet_stderr

    before = os.fstat(2)
    with quiet_stderr():
        os.write(2, b"")
    after = os.fstat(2)
    assert (before.st_dev, before.st_ino) == (after.st_dev, after.st_ino)
