"""The transferred jaw weight (autobones.rig_transfer.jaw): it reaches the chin and the lower lip on
any landmarked head (an animal, a cartoon robot, a synthetic long snout, humans) and falls off
smoothly: no edge off the lip line steps by more than 0.3 (a torn flap when the jaw opens)."""
from unittest import mock

import numpy as np
import pytest

import autobones
from autobones.geometry.topology import mesh_parts
from autobones.io.landmarks import read_landmarks
from autobones.io.mesh import load_mesh
from autobones.rig_transfer import pipeline
from autobones.rig_transfer.jaw import (MAX_JUMP, face_unit, inner_mouth_sides, lip_line_edges, mouth_frame, repair_jaw,
                                       with_jaw)

from shared_data import ROOT, data, flat_grid, long_snout

TEST_LANDMARKS = ROOT / "tests" / "landmarks"


def _head(name):
    """(V, F, landmarks) of a test head."""
    if name == "goat":
        V, F = load_mesh(data("misc/goathead.obj"))
        return V, F, read_landmarks(TEST_LANDMARKS / "goathead.landmarks.json")
    if name == "robot":
        V, F = load_mesh(data("misc/robot_head_neutral.obj"))
        return V, F, read_landmarks(TEST_LANDMARKS / "robot_head_neutral.landmarks.json")
    if name == "long_snout":  # james's face three times as long in front of the eyes
        V, F = load_mesh(data("menpo3d/james.obj"))
        V, lm = long_snout(V, F, read_landmarks(data("menpo3d/james.landmarks.json")), 2.0)
        return V, F, lm
    mesh, marks = {"ict": ("ict/identity002.obj", "ict/identity002.landmarks.json"),
                   "james": ("menpo3d/james.obj", "menpo3d/james.landmarks.json")}[name]
    V, F = load_mesh(data(mesh))
    return V, F, read_landmarks(data(marks))


@pytest.fixture(scope="module")
def rigs():
    cache = {}

    def get(name, repaired=True):
        if (name, repaired) not in cache:
            V, F, lm = _head(name)
            if repaired:
                cache[name, repaired] = V, F, lm, autobones.transfer((V, F), lm)
            else:  # the carried weights, as before the repair
                with mock.patch.object(pipeline, "repair_jaw_weights", lambda V, F, W, names, lm, details=None: W):
                    cache[name, repaired] = V, F, lm, autobones.transfer((V, F), lm)
        return cache[name, repaired]

    return get


def _jaw(rig):
    return rig.weights[:, rig.skeleton.names.index("jaw")]


def _nearest(V, p):
    return int(np.argmin(np.linalg.norm(V - p, axis=1)))


def _below_stomion(V, lm):
    """The vertex nearest the stomion on the lower lip's side of the mouth plane."""
    mouth = mouth_frame(lm)
    below = (V - mouth["stomion"]) @ mouth["normal"] < 0
    d = np.linalg.norm(V - mouth["stomion"], axis=1)
    return int(np.flatnonzero(below)[np.argmin(d[below])])


@pytest.mark.parametrize("name", ["goat", "robot", "long_snout"])
def test_jaw_reaches_the_chin_and_the_lower_lip(rigs, name):
    V, F, lm, rig = rigs(name)
    jaw = _jaw(rig)
    # the chin: the pogonion, or the menton on heads without one (goat, robot, the iBUG-68 names)
    assert jaw[_nearest(V, lm.get("pogonion", lm["menton"]))] >= 0.5
    if "stomion" in lm:  # the robot has no mouth
        assert jaw[_below_stomion(V, lm)] >= 0.5
        # ... and the upper lip stays on the skull: the cut is at the lip line
        mouth = mouth_frame(lm)
        above = ((V - mouth["stomion"]) @ mouth["normal"] > 0) & \
            (np.linalg.norm(V - mouth["stomion"], axis=1) < 0.1 * face_unit(V, lm))
        assert jaw[above].min() <= 0.1
    for name_up in ("pronasale", "nasion", "vertex"):
        if name_up in lm:
            assert jaw[_nearest(V, lm[name_up])] <= 0.05


@pytest.mark.parametrize("name", ["goat", "robot", "long_snout"])
def test_jaw_falls_off_smoothly_off_the_lip_line(rigs, name):
    V, F, lm, rig = rigs(name)
    jaw = _jaw(rig)
    E, on_line = lip_line_edges(V, F, lm)
    jump = np.abs(jaw[E[:, 0]] - jaw[E[:, 1]])
    assert jump[~on_line].max() <= MAX_JUMP, (name, jump[~on_line].max())
    # measured before the repair: goat 0.82-0.87 (138 edges over 0.3), robot 0.87 (40), the
    # stretched james 0.90 (174)
    assert on_line.sum() < 0.05 * len(E)  # the exempt lip line is a thin band


@pytest.mark.parametrize("name", ["goat", "robot", "long_snout"])
def test_weights_still_partition(rigs, name):
    V, F, lm, rig = rigs(name)
    W = rig.weights
    assert W.min() >= 0
    np.testing.assert_allclose(W.sum(axis=1), 1.0, atol=1e-9)
    names = rig.skeleton.names
    eyes = W[:, [names.index("eye_l"), names.index("eye_r")]].sum(axis=1) > 0
    _, _, _, before = rigs(name, repaired=False)
    # eyeballs keep their weights; the jaw's gain or loss is the head bone's
    np.testing.assert_array_equal(W[eyes], before.weights[eyes])
    j, h = names.index("jaw"), names.index("head")
    moved = np.delete(np.arange(W.shape[1]), [j, h])
    gain = W[:, j] - before.weights[:, j]
    fine = before.weights[:, h] >= gain  # the head bone had enough to give
    np.testing.assert_allclose(W[fine][:, moved], before.weights[fine][:, moved], atol=1e-12)


@pytest.mark.parametrize("name", ["ict", "james"])
def test_human_heads_keep_their_jaw_weights(rigs, name):
    V, F, lm, rig = rigs(name)
    _, _, _, before = rigs(name, repaired=False)
    jaw, jaw0 = _jaw(rig), _jaw(before)
    parts = mesh_parts(len(V), F)
    skin = parts == np.bincount(parts).argmax()
    # the mouth interior's floor and roof are set on purpose (test below): compared elsewhere
    d = np.abs(jaw - jaw0)[skin & (inner_mouth_sides(V, F, lm) == 0)]
    # measured on the skin off the mouth interior: ICT identity002 mean 0.047 (18% by more than 0.1;
    # 0.042 / 17% before the interior was seeded: the interior's surroundings follow it), james 0.018
    # (7%): the falloff widened where it stepped by up to 0.8 (under the jaw, on the
    # cheeks) and the lip cut made sharp; ICT's teeth change more (the upper ones to 0, as they should).
    # (ICT was 0.035 / 10% before the fit's reference shape followed the landmark warp near the face:
    # its carried jaw weight grew by 9% of its area, the repaired one stayed within 1%)
    assert d.mean() < 0.05 and (d > 0.1).mean() < 0.2, (d.mean(), (d > 0.1).mean())
    for n in ("menton", "labiale_inferius"):
        assert jaw[_nearest(V, lm[n])] >= min(0.85, jaw0[_nearest(V, lm[n])] - 0.05)
    assert jaw[_below_stomion(V, lm)] >= 0.9  # was 0.51 (ICT) and 0.53 (james): a soft cut
    for n in ("labiale_superius", "pronasale", "nasion"):
        assert jaw[_nearest(V, lm[n])] <= max(0.05, jaw0[_nearest(V, lm[n])])
    E, on_line = lip_line_edges(V, F, lm)
    jump, jump0 = (np.abs(j[E[:, 0]] - j[E[:, 1]])[~on_line] for j in (jaw, jaw0))
    assert jump.max() <= min(MAX_JUMP, jump0.max())


@pytest.mark.parametrize("name", ["ict", "james", "goat", "robot", "long_snout"])
def test_mouth_interior_floor_goes_with_the_jaw_and_roof_stays(rigs, name):
    """A head with a mouth interior (ICT: the insides of the lips, teeth, tongue, mouth bag): its
    floor is jaw 1 and its roof jaw 0 (the carried weight gave about half on both: measured median
    0.68 on the floor); closed mouths (james, the goat, the robot, the long snout) have none and
    their jaw weight is as without the rule."""
    V, F, lm, rig = rigs(name)
    side = inner_mouth_sides(V, F, lm)
    jaw = _jaw(rig)
    if name != "ict":
        assert not side.any()
        return
    assert (side < 0).sum() > 300 and (side > 0).sum() > 200, ((side < 0).sum(), (side > 0).sum())
    assert jaw[side < 0].min() >= 0.99 and jaw[side > 0].max() <= 0.01
    # the floor lies below the mouth plane and faces up, the roof above it facing down
    mouth = mouth_frame(lm)
    s = (V - mouth["stomion"]) @ mouth["normal"]
    assert (s[side < 0] < 0).all() and (s[side > 0] > 0).all()


def test_repair_smooths_a_step_and_keeps_a_smooth_field():
    V, F = flat_grid(n=31)
    step = (V[:, 0] > 0).astype(float)  # a cliff across the grid, no landmarks
    out = repair_jaw(V, F, step, {})
    E, _ = lip_line_edges(V, F, {})
    assert np.abs(out[E[:, 0]] - out[E[:, 1]]).max() <= MAX_JUMP
    assert out[V[:, 0] > 0.5].min() > 0.9 and out[V[:, 0] < -0.5].max() < 0.1
    smooth = np.clip(0.5 + 0.5 * V[:, 0], 0, 1)
    change = np.abs(repair_jaw(V, F, smooth, {}) - smooth)
    inside = np.abs(V[:, :2]).max(axis=1) < 0.8  # the free border bends a ramp a little (0.1 at most)
    assert change[inside].max() < 0.05 and change.mean() < 0.02, (change[inside].max(), change.mean())
    # deterministic, and the same on an unwelded copy (every triangle its own corners)
    np.testing.assert_array_equal(out, repair_jaw(V, F, step, {}))
    Vu, Fu = V[F].reshape(-1, 3), np.arange(3 * len(F)).reshape(-1, 3)
    np.testing.assert_allclose(repair_jaw(Vu, Fu, step[F].ravel(), {}), out[F].ravel(), atol=1e-9)


def test_with_jaw_moves_the_difference_to_the_head_bone():
    W = np.array([[0.2, 0.8, 0.0], [0.1, 0.3, 0.6], [0.5, 0.1, 0.4], [0.0, 0.0, 1.0]])
    jaw = np.array([0.5, 0.1, 0.9, 0.0])
    out = with_jaw(W, 2, 1, jaw)
    np.testing.assert_allclose(out.sum(axis=1), 1.0)
    np.testing.assert_allclose(out[:, 2], jaw)
    np.testing.assert_allclose(out[0], [0.2, 0.3, 0.5])    # the head gives
    np.testing.assert_allclose(out[1], [0.1, 0.8, 0.1])    # the head takes
    np.testing.assert_allclose(out[2], [0.1, 0.0, 0.9])    # the head had too little: the neck gives the rest
    np.testing.assert_allclose(out[3], [0.0, 1.0, 0.0])
