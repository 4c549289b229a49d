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
from autobones.rig_transfer.mouth_parts import carried_mouth_parts, rigid_mouth_parts

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
                with mock.patch.object(pipeline, "repair_jaw_weights", lambda V, F, W, names, lm, details=None, still=None: W):
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
    # the teeth go whole, with the jaw or the skull (next test), whichever side their faces look at
    teeth = np.zeros(len(V), dtype=bool)
    teeth[_teeth(V, F, lm, rig)] = True
    assert jaw[(side < 0) & ~teeth].min() >= 0.99 and jaw[(side > 0) & ~teeth].max() <= 0.01
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


# --- issue 31, check 2 ---------------------------------------------------------------------------
# jaw >= 0.9 at pogonion / menton / labiale_inferius, <= 0.1 at pronasale / nasion / vertex (the
# vertex nearest each given landmark), no edge off the lip line stepping by more than 0.3, on the
# head as given and on its rotated (an arbitrary angle), x0.001, x1000 and decimated (5k) copies

CHIN = ("pogonion", "menton", "labiale_inferius")
FACE_ABOVE = ("pronasale", "nasion", "vertex")


def _rotation(seed=31):
    """An arbitrary rotation (3, 3) (a random unit quaternion)."""
    w, x, y, z = (q := np.random.default_rng(seed).normal(size=4)) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _variant(V, F, lm, how):
    if how == "rotated":
        R, c = _rotation(), V.mean(axis=0)
        return (V - c) @ R.T, F, {k: (np.asarray(p) - c) @ R.T for k, p in lm.items()}
    if how in ("x0.001", "x1000"):
        s = float(how[1:])
        return V * s, F, {k: np.asarray(p) * s for k, p in lm.items()}
    if how == "decimated":
        import fast_simplification

        Vd, Fd = fast_simplification.simplify(V.astype(np.float32), F.astype(np.int32), 1 - 5000 / len(V))
        return Vd.astype(np.float64), Fd.astype(np.int64), lm
    return V, F, lm


def _check2(V, F, lm, jaw):
    """(weights at the six landmarks given: dict, worst step off the lip line, edges over 0.3); the
    lip line both on ``V`` and on its float32 copy (a glb's): an edge counts as off it when either
    says so."""
    E, on = lip_line_edges(V, F, lm)
    _, on32 = lip_line_edges(V.astype(np.float32).astype(np.float64), F, lm)
    jump = np.abs(jaw[E[:, 0]] - jaw[E[:, 1]])[~(on & on32)]
    at = {n: float(jaw[_nearest(V, lm[n])]) for n in CHIN + FACE_ABOVE if n in lm}
    return at, float(jump.max()), int((jump > MAX_JUMP).sum())


def _cow():
    V, F = load_mesh(data("zoo/cowHead.obj"))
    return V, F, read_landmarks(TEST_LANDMARKS / "cowHead.landmarks.json")


@pytest.mark.parametrize("name,how", [("cow", "as given"), ("cow", "rotated"), ("cow", "x0.001"), ("cow", "x1000"),
                                      ("goat", "rotated"), ("james", "rotated"), ("ict", "rotated"),
                                      ("ict", "decimated"), ("ict", "as given")])
def test_check2_chin_with_the_jaw_face_above_not_and_no_tear(name, how):
    V, F, lm = _cow() if name == "cow" else _head(name)
    V, F, lm = _variant(np.asarray(V, dtype=np.float64), np.asarray(F), lm, how)
    rig = autobones.transfer((V, F), lm)
    at, worst, over = _check2(V, F, lm, _jaw(rig))
    # measured at 6d56e5c, before this repair: the cow stepped by 1.00 on 6 edges off its lip line as
    # a glb stores it (float32; 3 on the rotated copy, 6 at x1000); the rotated james and ICT
    # identity002 had jaw 0.61 and 0.89 at the menton; identity002 decimated to 5k stepped by 0.73
    # (17 edges over 0.3); the rotated goat passed (menton 0.99)
    assert all(at[n] >= 0.9 for n in CHIN if n in at), at
    assert all(at[n] <= 0.1 for n in FACE_ABOVE if n in at), at
    assert worst <= MAX_JUMP, (worst, over)
    assert "jaw" not in rig.options   # nothing to report: the landmarks give a clean cut


def test_cow_glb_keeps_the_lip_line(tmp_path):
    """The cow's stomion is one of its vertices, so that vertex (and its mirror image) lies exactly
    on the mouth plane; written to a glb (float32) its coordinates round across the plane. The jaw
    weight read back from the file must still step only on the lip line."""
    from autobones.io.gltf import read_accessor, read_glb

    V, F, lm = _cow()
    mouth = mouth_frame(lm)
    on_plane = np.abs((V - mouth["stomion"]) @ mouth["normal"]) == 0
    assert on_plane.sum() >= 2   # the stomion's vertex and its mirror image: what made the case
    rig = autobones.transfer((V, F), lm)
    rig.save(tmp_path / "cow.glb")
    doc, body = read_glb(tmp_path / "cow.glb")
    prim = doc["meshes"][0]["primitives"][0]
    Vg = read_accessor(doc, body, prim["attributes"]["POSITION"]).astype(np.float64)
    joints = read_accessor(doc, body, prim["attributes"]["JOINTS_0"])
    weights = read_accessor(doc, body, prim["attributes"]["WEIGHTS_0"]).astype(np.float64)
    jaw = (weights * (joints == rig.skeleton.names.index("jaw"))).sum(axis=1)
    E, on_line = lip_line_edges(Vg, F, lm)
    jump = np.abs(jaw[E[:, 0]] - jaw[E[:, 1]])[~on_line]
    assert jump.max() <= MAX_JUMP + 1e-3, jump.max()   # was 1.00 on 6 edges
    # the lip line itself does not move with the rounding
    np.testing.assert_array_equal(on_line, lip_line_edges(V, F, lm)[1])


def test_mouth_surface_bends_between_chin_and_nose_at_a_snouts_tip():
    """A camel's lips meet at its snout's tip, ahead of the stomion: there the hand-placed pogonion
    lies 0.02 face units above the plane of the stomion and the corners and the pronasale 0.05
    (issue 31: the repair pinned that chin to the upper lip, jaw 0.01). The mouth surface rises
    ahead of the stomion to pass between them; on human mouths it stays the plane."""
    from autobones.rig_transfer.jaw_seeds import mouth_height

    lm = {"stomion": [0.0, 0.0, 0.42], "cheilion_l": [0.33, 0.0, 0.0], "cheilion_r": [-0.33, 0.0, 0.0],
          "pogonion": [0.0, 0.02, 0.49], "pronasale": [0.0, 0.046, 0.49], "nasion": [0.0, 0.45, -0.4],
          "exocanthion_l": [0.5, 0.12, -1.1], "exocanthion_r": [-0.5, 0.12, -1.1]}
    lm = {k: np.asarray(v) for k, v in lm.items()}
    mouth = mouth_frame(lm)
    assert 0.02 < mouth["lift"] < 0.046
    h = mouth_height(np.array([lm["pogonion"], lm["pronasale"], lm["stomion"], lm["cheilion_l"]]), mouth)
    assert h[0] < 0 < h[1] and abs(h[2]) < 1e-12 and abs(h[3]) < 1e-12
    for name in ("ict", "james"):
        assert mouth_frame(_head(name)[2])["lift"] == 0.0


def test_mouth_plane_is_steady_when_the_stomion_is_on_the_corners_line():
    """The stuffed toy's stomion lies 0.09 half-widths off the line between its mouth corners: the
    plane through the three turned 60 degrees from the face's and took the chin for the lips. Moved
    onto that line, a tenth of a millimetre up or down, james's mouth plane stays level."""
    lm = read_landmarks(data("menpo3d/james.landmarks.json"))
    ref = mouth_frame(lm)["normal"]
    mid = 0.5 * (lm["cheilion_l"] + lm["cheilion_r"])
    fu = face_unit(np.zeros((1, 3)), lm)
    for dy in (-1e-3, 1e-3):
        moved = dict(lm, stomion=mid + dy * fu * ref + 1e-3 * fu * mouth_frame(lm)["forward"])
        n = mouth_frame(moved)["normal"]
        assert np.degrees(np.arccos(np.clip(n @ ref, -1, 1))) < 25


def test_a_head_without_a_lip_line_says_so(rigs):
    """The robot has no mouth landmarks: the jaw weight may step nowhere, and its menton, two edges
    below the nose tip, cannot be jaw 1 and fall off smoothly; the sidecar says so in one line."""
    V, F, lm, rig = rigs("robot")
    note = rig.options["jaw"]
    assert "no lip line" in note and "menton" in note and "\n" not in note, note
    assert "jaw" not in rigs("goat")[3].options


def test_a_step_against_a_seed_is_spread_down_a_chain_of_pins():
    """A chin seed (1) whose neighbours the data term holds at 0 (the SMPL man's chin underside into its
    neck): once an edge's spring reaches its cap the free end is pinned one allowed step below the seed,
    then the next, each after its own springs' doublings. 16 rounds stopped at 1, 0.73, 0.46, 0 (a 0.46
    step; 0.31 on the SMPL man); the chain needs 23-25."""
    import scipy.sparse as sp

    from autobones.rig_transfer import jaw as jaw_module

    n = 12
    E = np.c_[np.arange(n - 1), np.arange(1, n)]
    A = sp.csr_matrix((np.ones(2 * (n - 1)), (np.r_[E[:, 0], E[:, 1]], np.r_[E[:, 1], E[:, 0]])), shape=(n, n))
    L = (sp.diags(np.asarray(A.sum(axis=1)).ravel()) - A).tocsr()
    for hold in (1e2, 1e4):
        value, fixed = np.zeros(n), np.zeros(n, dtype=bool)
        value[0], fixed[0] = 1.0, True
        x, rounds = jaw_module._solve(E, L, np.full(n, hold), np.zeros(n), value, fixed, np.zeros(n - 1, dtype=bool),
                                      np.ones(n - 1, dtype=bool))
        assert rounds < jaw_module.ROUNDS
        assert np.abs(np.diff(x)).max() <= jaw_module.TARGET_JUMP + 1e-9
        np.testing.assert_allclose(x[:4], [1.0, 0.73, 0.46, 0.19], atol=1e-6)
        assert x[4:].max() < 0.01


def _teeth(V, F, lm, rig):
    """Vertices of the small separate parts inside the mouth (:mod:`autobones.rig_transfer.mouth_parts`)."""
    sk = rig.skeleton
    return rigid_mouth_parts(V, F, rig.weights, sk.names, sk.heads, rig.frame, lm)[1]


def test_teeth_ride_the_jaw_or_the_skull_whole(rigs):
    """ICT's 32 separate teeth: each moves whole, the ones ICT's own jawOpen moves with the jaw and the
    others with the skull, and a 1 % jitter of the landmarks leaves them so; the mouth bag opens with the
    jaw as ICT's does. Before, the repair's field
    reached them through whichever seeds lay near: upper incisors jaw 0-1, lower molars 0-0.5, and a
    jitter moved them by up to 1.0 (measured on identity001)."""
    V, F, lm, rig = rigs("ict")
    jaw = _jaw(rig)
    parts = mesh_parts(len(V), F)
    teeth = _teeth(V, F, lm, rig)
    assert len(np.unique(parts[teeth])) == 32
    moved = np.linalg.norm(load_mesh(data("ict/jawOpen.obj"))[0] - load_mesh(data("ict/generic_neutral_mesh.obj"))[0],
                           axis=1)
    for p in np.unique(parts[teeth]):
        rows = parts == p
        assert np.ptp(jaw[rows]) == 0.0
        assert jaw[rows][0] == float(moved[rows].mean() > 0.1 * moved.max()), p
    np.testing.assert_allclose(rig.weights[teeth].sum(axis=1), 1.0, atol=1e-12)
    # the mouth bag (one 2,977-vertex part), skinned with the jaw turned to fit jawOpen on the lower teeth:
    # measured on identity002 12.6 % of the largest motion off before (its floor and roof seeded, the rest about
    # half jaw), 5.0 % now (benchmarks/teeth.py)
    D = load_mesh(data("ict/jawOpen.obj"))[0] - load_mesh(data("ict/generic_neutral_mesh.obj"))[0]
    inner = carried_mouth_parts(V, F, rig.weights, rig.skeleton.names, rig.skeleton.heads, rig.frame, lm)[1]
    bag = np.setdiff1d(inner, teeth)
    assert len(np.unique(parts[bag])) == 1
    c = rig.skeleton.heads[rig.skeleton.names.index("jaw")]
    lower = teeth[jaw[teeth] == 1.0]
    U, _, Vt = np.linalg.svd((V[lower] - c).T @ (V[lower] + D[lower] - c))
    R = Vt.T @ np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))]) @ U.T
    t = (V[lower] + D[lower] - c - (V[lower] - c) @ R.T).mean(axis=0)
    err = np.linalg.norm(jaw[bag, None] * ((V[bag] - c) @ R.T + t + c - V[bag]) - D[bag], axis=1)
    assert err.mean() < 0.07 * moved.max(), err.mean() / moved.max()
    rng = np.random.default_rng(0)
    ex = np.linalg.norm(np.subtract(lm["exocanthion_l"], lm["exocanthion_r"]))
    jittered = {k: np.asarray(p) + 0.01 * ex * rng.standard_normal(3) / np.sqrt(3) for k, p in lm.items()}
    again = _jaw(autobones.transfer((V, F), jittered))
    np.testing.assert_array_equal(again[teeth], jaw[teeth])


def test_teeth_added_to_a_scan_ride_whole(rigs):
    """A stand-in off ICT's topology: two small boxes set inside james's closed mouth (a game head's
    separate upper and lower teeth), 0.3 ex-ex behind the stomion and 0.08 above and below its level: the upper
    rides the skull, the lower the jaw, each whole; a stud set in the jaw's falloff moves whole as well."""
    import trimesh

    from autobones.orient import frame_from_landmarks

    V, F, lm = _head("james")
    fu = face_unit(V, lm)
    frame = frame_from_landmarks(V, F, lm)   # the frame transfer reads the head in: the stomion's level is its
    parts = [(V, F)]
    for side in (1.0, -1.0):
        box = trimesh.creation.box(extents=(0.1 * fu,) * 3)
        up, front = frame.rotation[1], frame.rotation[2]   # canonical +Y, +Z in the head's frame
        parts.append((box.vertices + lm["stomion"] - 0.3 * fu * front + side * 0.08 * fu * up, box.faces))
    # and a stud in the jaw's falloff farther than the mouth's reach (0.9 ex-ex) from the stomion: any small
    # closed part moves whole
    stud = trimesh.creation.box(extents=(0.06 * fu,) * 3)
    jaw0 = _jaw(rigs("james")[3])
    far = np.linalg.norm(V - lm["stomion"], axis=1) > 1.0 * fu
    parts.append((stud.vertices + V[far][np.argmin(np.abs(jaw0[far] - 0.5))], stud.faces))
    Vt = np.vstack([p[0] for p in parts])
    Ft = np.vstack([parts[0][1], parts[1][1] + len(V), parts[2][1] + len(V) + 8, parts[3][1] + len(V) + 16])
    rig = autobones.transfer((Vt, Ft), lm)
    jaw = _jaw(rig)
    np.testing.assert_array_equal(jaw[len(V):len(V) + 8], 0.0)
    np.testing.assert_array_equal(jaw[len(V) + 8:len(V) + 16], 1.0)
    assert np.ptp(rig.weights[len(V) + 16:], axis=0).max() == 0.0
    np.testing.assert_allclose(rig.weights.sum(axis=1), 1.0, atol=1e-12)
    assert len(rigid_mouth_parts(Vt, Ft, rig.weights, rig.skeleton.names, rig.skeleton.heads, rig.frame, lm)[1]) == 16
