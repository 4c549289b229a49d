"""autobones.expressions (the skin/muscle model of Bibliowicz 2005 §4.2, the FACS AUs of Erdoğdu 2010), wires.py, muscles.py."""
import numpy as np
import pytest
from scipy.spatial import cKDTree

import autobones
from autobones.errors import AutobonesError
from autobones.expressions.definitions import load_expressions
from autobones.expressions.model import ExpressionModel
from autobones.expressions.muscles import muscles_from_rig
from autobones.expressions.unfold import flipped_faces
from autobones.expressions.wires import WireDeformer, dropoff, wire_weights

from shared_data import ROOT, data

HEADS = {
    "default": (None, ROOT / "generic_rig" / "default_head.landmarks.json"),
    "ict": (data("ict/identity002.obj"), data("ict/identity002.landmarks.json")),
}
DOC = load_expressions()
AUS = sorted(DOC["action_units"], key=int)
EMOTIONS = sorted(DOC["expressions"])


@pytest.fixture(scope="module")
def model():
    cache = {}

    def get(name):
        if name not in cache:
            rig = autobones.transfer(*HEADS[name])
            cache[name] = (rig, ExpressionModel().fit(rig))
        return cache[name]

    return get


def _nearest(rig, model, point):
    """Index of the skin vertex nearest an input-frame point."""
    idx = np.flatnonzero(model.skin_)
    return idx[cKDTree(rig.vertices[idx]).query(np.asarray(point, dtype=np.float64))[1]]


def _part_edges(rig, V, rows):
    """Edge lengths (rest, posed) of the faces whose corners are all in the (n,) bool ``rows``."""
    E = rig.faces[rows[rig.faces].all(axis=1)]
    return (np.linalg.norm(rig.vertices[E[:, 0]] - rig.vertices[E[:, 1]], axis=1),
            np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1))


# ------------------------------------------------------------------------------ wire, muscles


def test_wire_moves_points_on_the_base_wire_fully_and_nothing_beyond_the_dropoff():
    x = np.linspace(-2, 2, 41)
    V = np.array([[a, b, 0.0] for a in x for b in x])
    base = np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    w = WireDeformer(0.5).fit(V, base)
    moved = base + [[0.0, 0.0, 0.0], [0.0, 0.3, 0.0], [0.0, 0.0, 0.0]]
    d = w.displacement(moved)
    on = np.flatnonzero((np.abs(V[:, 1]) < 1e-12) & (np.abs(V[:, 0]) < 1e-12))
    assert np.allclose(d[on], [0.0, 0.3, 0.0])
    # halfway along a segment: half the control vertex displacement
    half = np.flatnonzero(np.isclose(V[:, 0], 0.5) & (np.abs(V[:, 1]) < 1e-12))
    assert np.allclose(d[half], [0.0, 0.15, 0.0])
    far = np.abs(V[:, 1]) >= 0.5
    assert not d[far].any()
    assert np.isclose(dropoff(0.5), (1 - 0.25) ** 2) and dropoff(1.0) == 0.0 and dropoff(0.0) == 1.0
    # linear in the deforming wire
    assert np.allclose(w.displacement(base + 2 * (moved - base)), 2 * d)
    with pytest.raises(AutobonesError):
        wire_weights(V, base[:1], 0.5)


def test_muscle_contraction_scales_about_the_origin(model):
    rig, _ = model("default")
    mj = muscles_from_rig(rig)
    i = mj.names.index("zygomaticus_major_l")
    q = mj.contract(mj.insertions[i:i + 1], i, 0.25)[0]
    assert np.allclose(q, mj.origins[i] + 0.75 * (mj.insertions[i] - mj.origins[i]))
    assert np.allclose(mj.contract(mj.origins[i:i + 1], i, 0.5)[0], mj.origins[i])


def test_a_muscle_on_an_aponeurosis_scales_about_its_anchor(model):
    """With an anchor (frontalis on the galea) the anchor point stays, the insertion moves toward
    it, and a locator above the origin moves with the origin as one piece."""
    rig, _ = model("default")
    mj = muscles_from_rig(rig)
    i = mj.names.index("frontalis_inner_l")
    o, ins = mj.origins[i], mj.insertions[i]
    L = ins - o
    D = mj.locator_displacements(np.array([o + 0.25 * L, ins, o - 0.3 * L, o]), i, anchor=0.25)
    assert np.allclose(D, [np.zeros(3), -0.75 * L, 0.25 * L, 0.25 * L])
    assert np.array_equal(mj.locator_displacements(ins[None], i, anchor=None),
                          mj.locator_displacements(ins[None], i))


@pytest.mark.parametrize("name", ["default", "ict"])
def test_frontalis_draws_the_scalp_down_toward_the_raised_brow(model, name):
    """Frontalis has no bony origin (the galea): its contraction raises the brow and pulls the
    skin above its origin down toward it, as ICT's browInnerUp_L does."""
    rig, m = model(name)
    mj = muscles_from_rig(rig)
    i = mj.names.index("frontalis_inner_l")
    o, ip = mj.origins[i], mj.insertions[i]
    c = np.zeros(len(m.muscle_names_))
    c[m.muscle_names_.index("frontalis_inner_l")] = 1.0
    d = m.pose_parameters(c) - rig.vertices
    u = (ip - o) / np.linalg.norm(ip - o)
    brow, scalp = _nearest(rig, m, ip), _nearest(rig, m, o - 0.25 * (ip - o))
    assert d[brow] @ u < -0.05 * m.shortening_[i] * np.linalg.norm(ip - o)      # the brow rises
    assert d[scalp] @ u > 0.05 * m.shortening_[i] * np.linalg.norm(ip - o)      # the scalp comes down
    assert np.linalg.norm(d[brow]) > np.linalg.norm(d[scalp])


# ------------------------------------------------------------------------------ the model


@pytest.mark.parametrize("name", ["default", "ict"])
def test_zero_is_the_neutral_mesh_exactly(model, name):
    rig, m = model(name)
    assert np.array_equal(m.pose(), rig.vertices)
    assert np.array_equal(m.pose(au={12: 0.0, "4": 0, "26": 0}, jaw_deg=0, gaze=(0, 0)), rig.vertices)
    assert np.array_equal(m.pose(expression={"happiness": 0.0}), rig.vertices)
    assert np.array_equal(rig.pose(au={12: 0}), rig.vertices)


@pytest.mark.parametrize("name", ["default", "ict"])
def test_left_only_au12_leaves_the_right_half_still(model, name):
    rig, m = model(name)
    d = np.linalg.norm(m.pose(au={"12L": 1.0}) - rig.vertices, axis=1)
    x = m.canonical_[:, 0]
    left, right = d[x > 0].sum(), d[x < 0].sum()
    assert left > 0 and right < 0.02 * left, (left, right)
    # and it really is a smile: the left mouth corner goes up and out
    lm = rig.extra["landmarks"]
    c = _nearest(rig, m, lm["cheilion_l"])
    move = rig.frame.to_canonical(m.pose(au={"12L": 1.0})[c:c + 1]) - m.canonical_[c:c + 1]
    assert move[0, 1] > 0.02 * m.face_unit_ and move[0, 0] > 0, move / m.face_unit_


@pytest.mark.parametrize("name", ["default", "ict"])
def test_au4_leaves_the_mouth_still(model, name):
    """Mouth: skin within 0.35 fu of the stomion; its largest displacement stays under 2% of the
    brows' largest."""
    rig, m = model(name)
    d = np.linalg.norm(m.pose(au={4: 1.0}) - rig.vertices, axis=1) / rig.frame.size
    st = m.mouth_["stomion"]
    mouth = np.linalg.norm(m.canonical_ - st, axis=1) < 0.35 * m.face_unit_
    lm = rig.extra["landmarks"]
    brows = [_nearest(rig, m, lm[f"brow_{p}_{s}"]) for p in ("inner", "middle") for s in "lr"]
    assert d[brows].max() > 0.02 * m.face_unit_
    assert d[mouth].max() < 0.02 * d[brows].max(), (d[mouth].max(), d[brows].max())


@pytest.mark.parametrize("name", ["default", "ict"])
def test_jaw_opens_the_lower_lip_only(model, name):
    rig, m = model(name)
    lm = rig.extra["landmarks"]
    V = rig.frame.to_canonical(m.pose(jaw_deg=15.0))
    lo, up = _nearest(rig, m, lm["labiale_inferius"]), _nearest(rig, m, lm["labiale_superius"])
    d_lo = V[lo] - m.canonical_[lo]
    d_up = np.linalg.norm(V[up] - m.canonical_[up])
    assert d_lo[1] < -0.08 * m.face_unit_, d_lo / m.face_unit_
    assert d_up < 0.05 * np.linalg.norm(d_lo), (d_up, np.linalg.norm(d_lo))
    # AU26 (jaw drop) parts the lips the same way
    V26 = rig.frame.to_canonical(m.pose(au={26: 1.0}))
    assert V26[lo, 1] - V26[up, 1] < m.canonical_[lo, 1] - m.canonical_[up, 1] - 0.05 * m.face_unit_


def test_au43_closes_the_eyelids(model):
    """ICT's eyes are open: each upper lid margin comes down onto its lower lid."""
    rig, m = model("ict")
    lm = rig.extra["landmarks"]
    V = m.pose(au={43: 1.0})
    for s in "lr":
        ps, pi = np.asarray(lm[f"palpebrale_superius_{s}"]), np.asarray(lm[f"palpebrale_inferius_{s}"])
        top = _nearest(rig, m, ps)
        up = rig.frame.rotation[1]
        # the upper lid travels down over the eyeball (in front of the lower lid, which sits
        # deeper): its margin's height comes to within a quarter of the fissure of the lower lid's
        before = (rig.vertices[top] - pi) @ up
        after = (V[top] - pi) @ up
        assert before > 0.5 * np.linalg.norm(ps - pi) and abs(after) < 0.25 * before, (s, before, after)
        assert np.linalg.norm(V[top] - rig.skeleton.heads[rig.skeleton.names.index(f"eye_{s}")]) > \
            0.9 * np.linalg.norm(rig.vertices[top] - rig.skeleton.heads[rig.skeleton.names.index(f"eye_{s}")])
    # AU5 opens them wider, and the lids alone leave the rest of the face alone
    top = _nearest(rig, m, lm["palpebrale_superius_l"])
    assert m.pose(au={5: 1.0})[top] @ rig.frame.rotation[1] > rig.vertices[top] @ rig.frame.rotation[1]
    d = np.linalg.norm(V - rig.vertices, axis=1)
    far = np.linalg.norm(m.canonical_ - m.mouth_["stomion"], axis=1) < 0.4 * m.face_unit_
    assert not d[far].any()


def test_eyelashes_and_eye_shells_follow_the_lids(model):
    """ICT's eyelashes and eye-occlusion shells are separate small parts: they close with the lid
    skin they sit on, and nothing else that is not skin (eyeballs, teeth) moves with the lids."""
    rig, m = model("ict")
    from autobones.geometry.topology import mesh_parts

    parts = mesh_parts(len(rig.vertices), rig.faces)
    att = m.attached_
    assert att.sum() > 1000 and not (att & m.skin_).any()
    assert len(np.unique(parts[att])) >= 12            # 6 lash strips and 6 shells, both eyes
    lm = rig.extra["landmarks"]
    V = m.pose(au={43: 1.0})
    d = np.linalg.norm(V - rig.vertices, axis=1)
    top = _nearest(rig, m, lm["palpebrale_superius_l"])
    # the lashes nearest the upper lid margin travel with it
    idx = np.flatnonzero(att)
    near = idx[np.argsort(np.linalg.norm(rig.vertices[idx] - rig.vertices[top], axis=1))[:20]]
    assert np.all(d[near] > 0.5 * d[top]), (d[near].min(), d[top])
    assert not d[~att & ~m.skin_].any()


def test_a_row_of_lashes_turns_as_one_piece(model):
    """A lid part touching one lid only (ICT's lash rows) turns with that lid as one rigid piece,
    its corners included; a part touching both lids (an eye-occlusion shell) stretches."""
    rig, m = model("ict")
    from autobones.geometry.topology import mesh_parts

    parts = mesh_parts(len(rig.vertices), rig.faces)
    V = m.pose_parameters(np.zeros(len(m.muscle_names_)), 0.0, [1.0, 1.0, 0.6, 0.6])
    rigid, stretched = 0, 0
    for p in np.unique(parts[m.attached_]):
        rows = np.flatnonzero(parts == p)
        e0, e1 = _part_edges(rig, V, parts == p)
        if np.ptp(m.lid_weights_[:, rows], axis=1).max() == 0.0:
            rigid += 1
            assert np.allclose(e0, e1, rtol=1e-9), p
            assert np.linalg.norm(V[rows] - rig.vertices[rows], axis=1).min() > 0.0
        else:
            stretched += 1
            assert np.abs(e1 / e0 - 1.0).max() > 1e-3, p
    assert rigid >= 12 and stretched >= 4, (rigid, stretched)   # 2 x 6 lash rows; shells
    # and every such part follows the muscles of the skin it touches (a brow raise moves them)
    for p in np.unique(parts[m.attached_]):
        rows = np.flatnonzero(parts == p)
        assert np.abs(m.muscle_basis_[:, rows]).max() > 0.0, p


def test_the_mouth_inside_follows_icts_own_jaw(model):
    """ICT's jawOpen turns its lower teeth, gums and tongue about a centre below and behind the
    condyle and leaves the pharynx still: the model's jaw at ICT's 25 degrees reproduces the
    mouth's inner parts to >= 80 %, and nothing behind the jaw joint's blend moves. With the jaw joint
    at the condyle (issue #32) and the definitions' glide: 83.6 % on this face-only landmark file, the
    joint where human faces put it (``face_joints.json``); 80.8 % with the tragions given, the joint
    from the ear canals. The generic's own jaw mapped by the face's similarity, 0.15 ex-ex off the
    condyle, happened to turn these parts closer to ICT's centre: 90.3 % (with the gums-and-tongue part
    split at the stomion and the pharynx turned with the jaw: 83 %)."""
    rig, m = model("ict")
    from autobones.io.mesh import load_mesh

    N0 = load_mesh(data("ict/generic_neutral_mesh.obj"))[0]
    X = rig.vertices + (load_mesh(data("ict/jawOpen.obj"))[0] - N0)
    V = m.pose(jaw_deg=25.0)
    rows = m.mouth_parts_
    D = X[rows] - rig.vertices[rows]
    explained = 1.0 - np.linalg.norm(V[rows] - X[rows]) / np.linalg.norm(D)
    assert explained >= 0.8, explained
    j = m.bones_.index("jaw")
    reach = float(m.doc_["model"]["mouth_parts"]["pharynx"]) * m.face_unit_   # the hold's blend
    behind = rows[m.canonical_[rows, 2] < m.pivots_[j][2] - reach]
    assert len(behind) > 50 and not np.linalg.norm(V[behind] - rig.vertices[behind], axis=1).any()


def test_teeth_ride_the_jaw_or_the_skull(model):
    """ICT's teeth are separate parts: the lower ones turn with the jaw as rigid bodies, the upper
    ones stay with the skull; the gums and tongue part splits at the occlusal plane."""
    rig, m = model("ict")
    from autobones.geometry.topology import mesh_parts

    parts = mesh_parts(len(rig.vertices), rig.faces)
    j = m.bones_.index("jaw")
    V = m.pose(jaw_deg=20.0)
    d = np.linalg.norm(V - rig.vertices, axis=1)
    teeth = [p for p in np.unique(parts[m.mouth_parts_]) if (parts == p).sum() < 500]
    assert len(teeth) == 32
    up = rig.frame.rotation[1]
    st = np.asarray(rig.extra["landmarks"]["stomion"])
    for p in teeth:
        rows = parts == p
        w = m.jaw_weights_[rows, j]
        assert np.all(w == w[0]) and w[0] in (0.0, 1.0)
        above = (rig.vertices[rows].mean(axis=0) - st) @ up > 0
        assert (w[0] == 0.0) == above
        assert (d[rows].max() == 0.0) == above
        if not above:   # a rigid body: its edge lengths are kept
            e0, e1 = _part_edges(rig, V, rows)
            assert np.allclose(e0, e1, rtol=1e-6)


def test_linear_pose_is_the_pose_without_clamp_and_folds(model):
    rig, m = model("default")
    c = m.parameters(au={12: 0.6, 1: 0.4, 15: 0.3})["contractions"]
    lids = np.array([0.4, 0.0, 0.2, 0.0])
    A, b = m.linear_pose(6.0, lids)
    assert A.shape == (len(c), len(rig.vertices), 3)
    assert np.allclose(b, m.pose_parameters(np.zeros_like(c), 6.0, lids))
    X = m.pose_parameters(c, 6.0, lids)
    free = ~m.clamp_
    assert np.allclose((b + np.tensordot(c, A, 1))[free], X[free])


def test_eyes_gaze_with_the_aim_control(model):
    rig, m = model("ict")
    eye = rig.skeleton.names.index("eye_l")
    ball = np.flatnonzero(rig.weights[:, eye] > 0.99)
    assert len(ball) > 50
    pivot = rig.skeleton.heads[eye]
    front = rig.frame.rotation[2]
    left = rig.frame.rotation[0]
    # looking at a point far to the subject's left turns the eyeball's front that way
    target = pivot + 10 * rig.frame.size * (front + left)
    V = m.pose(look_at=target)
    cornea = ball[np.argsort((rig.vertices[ball] - pivot) @ front)[-20:]]
    a0 = (rig.vertices[cornea].mean(axis=0) - pivot)
    a1 = (V[cornea].mean(axis=0) - pivot)
    assert a1 @ left > a0 @ left + 0.2 * np.linalg.norm(a0)
    assert np.allclose(np.linalg.norm(V[ball] - pivot, axis=1), np.linalg.norm(rig.vertices[ball] - pivot, axis=1))
    # a gaze of (yaw, pitch) turns the eye by that angle, and the skin does not move
    V = m.pose(gaze=(20.0, 0.0))
    b0 = rig.frame.to_canonical(rig.vertices[cornea]).mean(axis=0) - m.pivots_[eye]
    b1 = rig.frame.to_canonical(V[cornea]).mean(axis=0) - m.pivots_[eye]
    turn = np.degrees(np.arctan2(b1[0], b1[2]) - np.arctan2(b0[0], b0[2]))
    assert abs(turn - 20.0) < 0.5, turn
    assert not (V[m.skin_] - rig.vertices[m.skin_]).any()


# Folds the model still makes at intensity 1 (strict xfail: fixing one makes its test fail, so
# this list stays honest). The jaw's folds under the chin (AU27, fear: 64 triangles on the
# default head, ~110 on ICT) are relaxed by expressions.unfold.unfold; on ICT the mouth corners'
# slivers (under 1% of the median skin triangle) may still turn over, at most 4 (AU27, fear).
KNOWN_FLIPS = set()


@pytest.mark.parametrize("name", ["default", "ict"])
@pytest.mark.parametrize("what", [f"au{a}" for a in AUS] + EMOTIONS)
def test_no_flipped_triangles_and_no_nan_at_intensity_1(model, name, what, request):
    """Skin triangles (the largest part, eyeballs excluded) whose normal turns over; sub-millimetre
    triangles (under 1% of the median skin triangle: ICT's mouth corners) are counted apart and
    may fold at most 8 at a time."""
    if (name, what) in KNOWN_FLIPS:
        request.applymarker(pytest.mark.xfail(strict=True, reason="known fold, see KNOWN_FLIPS"))
    rig, m = model(name)
    V = m.pose(au={what[2:]: 1.0}) if what.startswith("au") else m.pose(expression=what)
    assert np.isfinite(V).all()
    F, V0 = rig.faces, rig.vertices
    skin = m.skin_[F].all(axis=1)
    area = 0.5 * np.linalg.norm(np.cross(V0[F[:, 1]] - V0[F[:, 0]], V0[F[:, 2]] - V0[F[:, 0]]), axis=1)
    tiny = 0.01 * np.median(area[skin])
    flips = flipped_faces(V0, V, F, min_area=tiny) & skin
    assert flips.sum() == 0, f"{flips.sum()} flipped skin triangles"
    assert (flipped_faces(V0, V, F) & skin).sum() <= 8
    assert np.linalg.norm(V - rig.vertices, axis=1).max() > 0.005 * m.face_unit_ * rig.frame.size


def test_deterministic_linear_and_fast(model):
    rig, m = model("ict")
    m2 = ExpressionModel().fit(rig)
    a = m.pose(expression="happiness", jaw_deg=5, gaze=(5, 3))
    assert np.array_equal(a, m2.pose(expression="happiness", jaw_deg=5, gaze=(5, 3)))
    # the muscle stage is linear in the contractions (before the skull clamp)
    p = m.parameters(au={12: 0.5, 4: 0.3})
    assert p["contractions"].shape == (len(m.muscle_names_),)
    G = np.tensordot(p["contractions"], m.muscle_basis_, axes=1)
    assert np.allclose(G, 0.5 * np.tensordot(m.parameters(au={12: 1})["contractions"], m.muscle_basis_, 1)
                       + 0.3 * np.tensordot(m.parameters(au={4: 1})["contractions"], m.muscle_basis_, 1))
    assert np.array_equal(m.pose_parameters(p["contractions"], p["jaw_deg"], p["eyelids"]), m.pose(au={12: 0.5, 4: 0.3}))
    # away from the skull the posed skin is the neutral plus the muscle fields, in the input frame
    one = np.zeros(len(m.muscle_names_))
    one[m.muscle_names_.index("zygomaticus_major_l")] = 0.5
    moved = m.pose_parameters(one) - rig.vertices
    free = ~m.clamp_
    assert np.allclose(moved[free], 0.5 * m.muscle_fields()[m.muscle_names_.index("zygomaticus_major_l")][free])


def test_muscle_parameters_and_errors(model):
    rig, m = model("default")
    a = m.pose(muscles={"zygomaticus_major": 1.0})
    b = m.pose(au={12: 1.0})
    assert np.array_equal(a, b)
    one = m.pose(muscles={"zygomaticus_major_l": 1.0})
    assert np.array_equal(one, m.pose(au={"12L": 1}))
    for bad in ({"au": {99: 1}}, {"au": {"12X": 1}}, {"muscles": {"orbicularis": 1}}, {"expression": "joy"},
                {"au": {12: float("nan")}}, {"eyelids": {"middle": 1}}):
        with pytest.raises(AutobonesError):
            m.pose(**bad)
    with pytest.raises(AutobonesError):
        m.pose_parameters(np.zeros(3))
    with pytest.raises(AutobonesError):
        ExpressionModel().pose()


def test_the_data_file_defines_the_seed_aus_and_emotions():
    need = {"1", "2", "4", "5", "6", "9", "10", "12", "14", "15", "17", "20", "25", "26", "43"}
    assert need <= set(DOC["action_units"])
    assert set(EMOTIONS) == {"surprise", "fear", "happiness", "sadness", "disgust", "anger"}
    for e in DOC["expressions"].values():
        assert set(e["au"]) <= set(DOC["action_units"])
    types = set(DOC["muscle_types"])
    for au in DOC["action_units"].values():
        assert set(au.get("muscles", {})) <= types


@pytest.mark.parametrize("name, mesh, marks", [
    ("goat", data("misc/goathead.obj"), ROOT / "tests" / "landmarks" / "goathead.landmarks.json"),
    ("robot", data("misc/robot_head_neutral.obj"), ROOT / "tests" / "landmarks" / "robot_head_neutral.landmarks.json"),
])
def test_cartoon_and_animal_heads_pose(name, mesh, marks):
    """The same definitions on a goat and a robot: finite, neutral exact, one-sided AUs one-sided.
    (The robot folds nothing at intensity 1; the goat's long jaw folds under AU26/27 and its
    lids under AU7/AU43, not checked here.)"""
    rig = autobones.transfer(mesh, marks)
    m = ExpressionModel().fit(rig)
    assert np.array_equal(m.pose(au={12: 0}), rig.vertices)
    skin = m.skin_[rig.faces].all(axis=1)
    for what in list(m.action_units) + list(m.expressions):
        V = m.pose(au={what: 1}) if what in m.action_units else m.pose(expression=what)
        assert np.isfinite(V).all()
        if name == "robot":
            assert not (flipped_faces(rig.vertices, V, rig.faces) & skin).any(), what
    d = np.linalg.norm(m.pose(au={"12L": 1}) - rig.vertices, axis=1)
    x = m.canonical_[:, 0]
    assert d[x < 0].sum() < 0.02 * d[x > 0].sum()


def test_the_model_rebuilds_from_the_saved_rig(model, tmp_path):
    """Everything the model reads is in the glb's sidecars (rig.json: frame, bones, muscles,
    landmarks, label names; weights.npz: weights and fields): a rig rebuilt from them poses the same."""
    import json

    from autobones.orient import Frame
    from autobones.rig import Rig, sidecar_attributes, sidecar_paths
    from autobones.skeleton import Skeleton

    rig, m = model("ict")
    glb = tmp_path / "head.glb"
    rig.save(glb)
    js, npz = sidecar_paths(glb)
    with open(js) as fh:
        doc = json.load(fh)
    z = np.load(npz)
    fr = doc["frame"]
    names = [b["name"] for b in doc["bones"]]
    skel = Skeleton(names, [names.index(b["parent"]) if b["parent"] else -1 for b in doc["bones"]],
                    [b["head"] for b in doc["bones"]], [b["tail"] for b in doc["bones"]])
    again = Rig(vertices=rig.vertices, faces=rig.faces, skeleton=skel, weights=z["weights"].astype(np.float64),
                labels=np.array(doc["labels"]), facial_mask=np.zeros(len(rig.vertices), bool),
                frame=Frame(np.array(fr["rotation"]), np.array(fr["origin"]), fr["head_size"]),
                **sidecar_attributes({k: doc[k] for k in ("muscles", "landmarks", "field_labels")}),
                fields={k[6:]: z[k] for k in z.files if k.startswith("field/")})
    for kw in ({"expression": "happiness"}, {"au": {26: 1.0}}, {"au": {43: 1.0}}, {"expression": "anger"}):
        assert np.abs(again.pose(**kw) - m.pose(**kw)).max() < 1e-6 * rig.frame.size, kw
