"""Lid margins and the blink, and the lip line of jawOpen, on one-surface heads (autobones.arkit.lids,
curves, the source's closing fractions, soft pins in the deformation transfer, and the james
scan's blink closing its own lids without more folds than before."""
import numpy as np
import pytest

import autobones
from autobones.arkit.deformation_transfer import DeformationTransfer
from autobones.arkit.lids import LidClosure, canthal_parameter, eye_sides, gap_closure, margin_points
from autobones.arkit.names import ARKIT_NAMES
from autobones.arkit.shapes import load_shapes
from autobones.arkit.fissures import lip_motion, mouth_fissure
from autobones.arkit.targets import CORRESPONDENCE, arkit_targets
from autobones.orient import Frame
from shared_data import data

EYE = {"endocanthion_l": [1.0, 0.0, 0.0], "exocanthion_l": [4.0, 0.2, -0.5],
       "palpebrale_superius_l": [2.2, 0.6, 0.1], "palpebrale_inferius_l": [2.8, -0.4, 0.0]}


def test_margins_pass_through_the_landmarks_and_face_each_other():
    lm = {k: np.array(v) for k, v in EYE.items()}
    assert eye_sides(lm) == ["l"]
    assert eye_sides({k: v for k, v in lm.items() if k != "palpebrale_inferius_l"}) == []
    t_up, t_lo = canthal_parameter(np.array([lm["palpebrale_superius_l"], lm["palpebrale_inferius_l"]]), lm, "l")
    U, L = margin_points(lm, "l", np.array([0.0, t_up, t_lo, 1.0]))
    np.testing.assert_allclose(U[[0, 3]], [lm["endocanthion_l"], lm["exocanthion_l"]], atol=1e-12)
    np.testing.assert_allclose(L[[0, 3]], [lm["endocanthion_l"], lm["exocanthion_l"]], atol=1e-12)
    np.testing.assert_allclose(U[1], lm["palpebrale_superius_l"], atol=1e-12)
    np.testing.assert_allclose(L[2], lm["palpebrale_inferius_l"], atol=1e-12)
    # points at the same t are across the eye from each other: same projection on the canthal axis
    t = np.linspace(0.1, 0.9, 9)
    U, L = margin_points(lm, "l", t)
    np.testing.assert_allclose(canthal_parameter(U, lm, "l"), t, atol=1e-12)
    np.testing.assert_allclose(canthal_parameter(L, lm, "l"), t, atol=1e-12)
    assert (U[:, 1] > L[:, 1]).all()


def test_the_sources_blink_closes_its_own_eye_and_nothing_else():
    S = load_shapes()
    lc = LidClosure().fit(S.vertices, S.faces, S.landmarks, S.vertices, S.faces, S.landmarks)
    assert lc.sides_ == ["l", "r"]
    names = ["eyeBlinkLeft", "eyeBlinkRight", "eyeWideLeft", "jawOpen"]
    kappa, _ = lc.closing(np.stack([S.deltas[n] for n in names]))
    mid = slice(len(lc.t_) // 4, 3 * len(lc.t_) // 4)
    # ICT's blink closes 0.8-0.9 of its left gap mid-eye (its lids are thick) and leaves the right
    assert 0.7 < kappa[0, 0, mid].min() and kappa[0, 0, mid].max() < 1.0
    assert np.abs(kappa[0, 1]).max() < 0.02 and np.abs(kappa[1, 0]).max() < 0.02
    assert kappa[1, 1, mid].min() > 0.7
    assert kappa[2, 0, mid].max() < -0.1            # eyeWide opens
    moving = lc.moving_shapes(np.stack([S.deltas[n] for n in names]))
    assert moving.tolist() == [True, True, True, False]


def test_pins_hold_vertices_where_asked():
    # a flat grid carrying a zero shape onto itself, its rim held (its source never moves there):
    # only the pins move anything
    n = 12
    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    V = np.stack([x.ravel(), y.ravel(), np.zeros(n * n)], axis=1)
    i = np.arange(n - 1)[:, None] * n + np.arange(n - 1)[None, :]
    F = np.concatenate([np.stack([i, i + 1, i + n], -1).reshape(-1, 3), np.stack([i + 1, i + n + 1, i + n], -1).reshape(-1, 3)])
    pinned = np.array([5 * n + 5, 6 * n + 6])
    moving = np.linalg.norm(V - [5.5, 5.5, 0.0], axis=1) < 4.0
    dt = DeformationTransfer().fit(V, F, V, V, F, moving=moving, pinned=pinned)
    g = np.array([[[0.0, 0.0, 1.0], [0.0, 0.0, -0.5]]])
    X = dt.transform(np.zeros((1, n * n, 3)), pins=g)
    np.testing.assert_allclose(X[0, pinned], g[0], atol=0.02)
    assert np.abs(X[0, 0]).max() < 1e-3                # the rim: held
    assert 0.0 < X[0, 5 * n + 6, 2] < 1.0              # between the pins: in between
    np.testing.assert_array_equal(dt.transform(np.zeros((1, n * n, 3))), 0.0)  # no pins: nothing


def test_gap_closure_measures_what_it_says():
    lm = {k: np.array(v) for k, v in EYE.items()}
    up, lo = lm["palpebrale_superius_l"], lm["palpebrale_inferius_l"]
    V = np.array([up, lo, up + [0.0, 0.0, -1.0], lo + [1.0, 0.0, -1.0]])
    F = np.array([[0, 1, 2], [1, 3, 2]])
    D = np.zeros_like(V)
    D[0] = 0.5 * (lo - up)                             # the upper landmark halfway down
    c = gap_closure(V, F, D, lm, "l", up=[0.0, 1.0, 0.0])
    assert c["vertices"] == pytest.approx(0.5) and c["points"] == pytest.approx(0.5)
    assert c["vertical"] == pytest.approx(0.5)


@pytest.fixture(scope="module")
def james():
    """The menpo3d james scan (one surface: lids and visible eye, no eyeballs) with its ARKit shapes."""
    return autobones.transfer(data("menpo3d/james.obj"), data("menpo3d/james.landmarks.json"), arkit=True)


def test_james_blink_brings_its_own_upper_lids_down(james):
    rig = james
    up = rig.frame.rotation[1]
    for side, name in (("l", "eyeBlinkLeft"), ("r", "eyeBlinkRight")):
        c = gap_closure(rig.vertices, rig.faces, rig.arkit_targets[name], rig.landmarks, side, up)
        # measured 79 % (left) / 90 % (right) vertically at the landmarks, 71 / 72 % in 3D there,
        # 65 / 66 % between the nearest vertices (an edge apart sideways on this coarse scan);
        # before: 33 / 88, 36 / 72, 37 / 67 (ICT's own blink on its own head: 82, 74, 77); the
        # right eye's lids close by the gradients alone and are left as they give them
        assert c["vertical"] > 0.75, (side, c)
        assert c["points"] > 0.65, (side, c)
        assert c["vertices"] > 0.58, (side, c)
        # the other eye stays open
        other = "eyeBlinkRight" if side == "l" else "eyeBlinkLeft"
        assert abs(gap_closure(rig.vertices, rig.faces, rig.arkit_targets[other], rig.landmarks, side, up)["vertical"]) < 0.1


def test_james_lids_fold_no_more_than_before(james):
    rec = james.arkit
    folds = rec["flipped_triangles"]
    src = rec["source_flipped_triangles"]
    assert all(c <= src.get(n, 0) for n, c in folds.items()), folds
    # each shape alone: 7 before the lids were closed (eyeBlinkLeft 2, eyeBlinkRight 2, mouthClose 3); with
    # the lips free to part, mouthClose alone pushes them through each other (37; ICT's own folds 597 so),
    # which is why it is judged on top of jawOpen, where nothing is left after the repair
    assert sum(c for n, c in folds.items() if n != "mouthClose") <= 4, folds
    assert sum(rec["folds"]["after_repair"].values()) == 0, rec["folds"]["after_repair"]
    assert set(folds) == set(ARKIT_NAMES)


def test_lids_change_only_the_shapes_that_move_lids(james):
    from autobones.arkit.fissures import eye_fissures

    S = load_shapes()
    V, F = james.vertices, james.faces
    lc = LidClosure().fit(S.vertices, S.faces, S.landmarks, V, F, james.landmarks)
    assert len(lc.vertices_) > 10 and lc.sides_ == ["l", "r"]
    names = S.names
    D = np.stack([S.deltas[n] for n in names])
    moving = lc.moving_shapes(D)
    assert moving[names.index("eyeBlinkLeft")] and not moving[names.index("jawOpen")]
    # the same transfer without the second, pinned solve: equal on the shapes that move no lid
    dt = DeformationTransfer().fit(S.vertices, S.faces, _correspondence(james, S), V, F,
                                   moving=np.linalg.norm(D, axis=2).max(axis=0) > 0,
                                   free=eye_fissures(V, F, james.landmarks, james.frame)
                                   | mouth_fissure(V, F, james.landmarks, james.frame))
    X = dt.transform(D)
    # the gradients alone leave james's left lids apart (33 % closed vertically); the right ones close
    # 0.8 of what ICT's do or a little less, depending on the correspondence's schedule (88 % vertically
    # with transfer's, pinned with the ARKit set's lighter one)
    assert lc.needed(D, X)[0]
    tol = 1e-5 * james.frame.size
    eye = np.linalg.norm(np.subtract(james.landmarks["exocanthion_l"], james.landmarks["endocanthion_l"]))
    repaired = james.arkit["folds"]["before_repair"]  # the fold repair changed these (the lip line's folds)
    for j, n in enumerate(names):
        err = np.abs(X[j] - james.arkit_targets[n]).max()
        # the pinned solve moves the left upper lid by a few percent of the eye's width or more (6.6 % measured)
        assert (err > 0.04 * eye) if n == "eyeBlinkLeft" else (moving[j] or repaired[n] or err < tol), (n, err)


def test_a_head_whose_lids_close_by_themselves_is_left_alone():
    # ICT's skin carrying its own shapes: the gradients reproduce its blink, nothing to pin
    S = load_shapes()
    lc = LidClosure().fit(S.vertices, S.faces, S.landmarks, S.vertices, S.faces, S.landmarks)
    D = np.stack([S.deltas[n] for n in S.names])
    assert lc.needed(D, D).tolist() == [False, False]
    # lids kept open (the blink's displacements halved): both eyes are closed by the pins
    assert lc.needed(D, 0.5 * D).tolist() == [True, True]


def _correspondence(rig, S):
    from autobones.rig_transfer.correspondence import dense_correspondence

    shared = [n for n in S.landmarks if n in rig.landmarks]
    return dense_correspondence(S.vertices, S.faces, rig.vertices, rig.faces, {n: S.landmarks[n] for n in shared},
                                {n: np.asarray(rig.landmarks[n], dtype=float) for n in shared}, **CORRESPONDENCE)[0]


def test_mouth_fissure_is_the_row_of_triangles_across_the_lip_line():
    # a face-on grid (canonical frame = input frame), lips closed along y = 0.05 between x = -2 and 2
    n = 21
    x, y = np.meshgrid(np.linspace(-5, 5, n), np.linspace(-5, 5, n))
    V = np.c_[x.ravel(), y.ravel(), np.zeros(n * n)]
    F = np.array([[i * n + j, i * n + j + 1, (i + 1) * n + j + 1] for i in range(n - 1) for j in range(n - 1)]
                 + [[i * n + j, (i + 1) * n + j + 1, (i + 1) * n + j] for i in range(n - 1) for j in range(n - 1)])
    lm = {"cheilion_r": [-2.0, 0.05, 0.0], "stomion": [0.0, 0.05, 0.0], "cheilion_l": [2.0, 0.05, 0.0],
          "labiale_superius": [0.0, 1.0, 0.0], "labiale_inferius": [0.0, -1.0, 0.0]}
    frame = Frame(np.eye(3), np.zeros(3), 1.0)
    m = mouth_fissure(V, F, lm, frame)
    C = V[F].mean(axis=1)
    # the two triangles of each grid cell across y = 0.05, cells wholly between the corners (x -1.5 .. 1.5)
    expect = (C[:, 1] > 0) & (C[:, 1] < 0.5) & (np.abs(C[:, 0]) < 1.6)
    assert m.sum() == expect.sum() == 12 and (m == expect).all()
    assert not mouth_fissure(V, F, {k: v for k, v in lm.items() if k != "stomion"}, frame).any()
    # a mouth already open (no triangle across the line) has none
    assert not mouth_fissure(V, F[~expect], lm, frame).any()


def test_james_jaw_parts_its_own_lips(james):
    rig = james
    up = rig.frame.rotation[1]
    upper, lower, opening = lip_motion(rig.vertices, rig.landmarks, rig.arkit_targets["jawOpen"], up)
    # in mouth widths; measured 0.085 / 0.591 / 0.464 (ICT's own jawOpen on its skin 0.049 / 0.798 /
    # 0.657); with the lip line's 25 triangles held, the lips moved together: 0.280 / 0.363 / 0.075
    assert opening > 0.35 and upper < 0.15 and lower > 0.45, (upper, lower, opening)
    held, _ = arkit_targets(rig, free_lips=False)
    assert lip_motion(rig.vertices, rig.landmarks, held["jawOpen"], up)[2] < 0.2
