"""Issue #16 item 2, the anatomy seed 000 lacks: lids hinging on the line through the eye corners,
and the linear muscles procerus, nasalis, risorius and platysma (Lee, Terzopoulos & Waters 1995's
linear muscles, in generic_rig/muscles.json, driving FACS action units of Ekman, Friesen & Hager
2002). The project's own heads only: the default head and the ICT identity in tests/data."""
import copy

import numpy as np
import pytest

import autobones
from autobones.errors import AutobonesError
from autobones.expressions.bones import turn_lids
from autobones.expressions.definitions import load_expressions, model_parameters
from autobones.expressions.lids import attach_hinge_share, closing_angle, lid_hinges
from autobones.expressions.model import ExpressionModel
from autobones.geometry.rotations import line_turn, x_turn

from shared_data import ROOT, data

HEADS = {
    "default": (None, ROOT / "generic_rig" / "default_head.landmarks.json"),
    "ict": (data("ict/identity002.obj"), data("ict/identity002.landmarks.json")),
}


@pytest.fixture(scope="module")
def model():
    cache = {}

    def get(name, definitions=None):
        if name not in cache:
            cache[name] = autobones.transfer(*HEADS[name])
        rig = cache[name]
        return rig, ExpressionModel(definitions).fit(rig)

    return get


def _canonical_landmarks(rig):
    return {k: rig.frame.to_canonical(np.asarray(v, float).reshape(1, 3))[0]
            for k, v in rig.extra["landmarks"].items()}


def _nearest_skin(rig, m, point):
    idx = np.flatnonzero(m.skin_)
    return idx[np.argmin(np.linalg.norm(rig.vertices[idx] - np.asarray(point), axis=1))]


# ------------------------------------------------------------------------------ lids
def test_line_turn_is_a_rotation_about_its_axis():
    rng = np.random.default_rng(0)
    P = rng.normal(size=(50, 3))
    ang = rng.uniform(-1, 1, 50)
    # about +X it is the lid joints' x_turn
    assert np.allclose(line_turn(P, [1.0, 0, 0], ang), x_turn(P, ang), atol=1e-12)
    u = np.array([0.9, -0.2, 0.3])
    u /= np.linalg.norm(u)
    Q = P + line_turn(P, u, ang)
    # distances to the axis and positions along it are kept; a positive angle turns right-handedly
    assert np.allclose(Q @ u, P @ u)
    assert np.allclose(np.linalg.norm(np.cross(Q, u), axis=1), np.linalg.norm(np.cross(P, u), axis=1))
    a, b = np.cross(u, [0, 1.0, 0]), None
    b = a + line_turn(a[None], u, 0.5)[0]
    assert np.cross(a, b) @ u > 0
    assert abs(closing_angle(a, b, np.zeros(3), u) - np.degrees(0.5)) < 1e-9


def test_lids_hinge_on_the_line_through_the_eye_corners(model):
    """The default head's lids hinge, near their margins, on the line through the exocanthion
    and the endocanthion (raised to the fissure's mid-height), oriented to the subject's left and
    mirrored between the eyes; away from the margins the turn is about the eye pivot."""
    rig, m = model("default")
    L = _canonical_landmarks(rig)
    points, axes, close, share, joints = m.lid_hinges_
    assert joints.tolist() == [True, True, False, False]          # the upper lids hinge
    for e, s in enumerate("lr"):
        ex, en = L[f"exocanthion_{s}"], L[f"endocanthion_{s}"].copy()
        en[1] = 0.5 * (L[f"palpebrale_superius_{s}"][1] + L[f"palpebrale_inferius_{s}"][1])
        u = (ex - en) / np.linalg.norm(ex - en)
        assert np.allclose(points[e], ex) and abs(abs(axes[e] @ u) - 1.0) < 1e-12 and axes[e][0] > 0
        assert close[e] > m.lid_close_deg_[e] > 0        # a hinge in front of the pivot turns farther
    assert np.allclose(axes[0] * [1, -1, -1], axes[1], atol=1e-6)   # mirror images
    assert share.min() >= 0 and 0.99 < share.max() <= 1.0
    assert not share[~m.skin_ & ~m.attached_].any()
    # the margin hinges, the brow does not
    top = _nearest_skin(rig, m, rig.extra["landmarks"]["palpebrale_superius_l"])
    brow = _nearest_skin(rig, m, rig.extra["landmarks"]["brow_middle_l"])
    assert share[top] > 0.8 and share[brow] == 0.0


def test_the_default_head_still_blinks_closed(model):
    """AU43 brings each upper margin down onto the lower one at least as far as the eye pivot's
    turn alone did (the default head's lids are one closed surface, so its margin weights are
    partial and neither closes fully), with nothing turned over."""
    from autobones.expressions.unfold import flipped_faces

    rig, m = model("default")
    doc = copy.deepcopy(load_expressions())
    doc["model"]["eyelids"]["hinge"] = "pivot"
    _, m0 = model("default", doc)
    assert np.allclose(m.lid_close_deg_, m0.lid_close_deg_) and (m.lid_close_deg_ > 0).all()
    lm = rig.extra["landmarks"]
    V, V0 = m.pose(au={43: 1.0}), m0.pose(au={43: 1.0})
    for s in "lr":
        top = _nearest_skin(rig, m, lm[f"palpebrale_superius_{s}"])
        bot = _nearest_skin(rig, m, lm[f"palpebrale_inferius_{s}"])
        rest, hinged, pivot = (np.linalg.norm(X[top] - X[bot]) for X in (rig.vertices, V, V0))
        assert hinged < 0.75 * rest and hinged <= pivot, (s, rest, hinged, pivot)
    assert not flipped_faces(rig.vertices, V, rig.faces).any()


def test_without_a_corner_landmark_the_lids_turn_about_the_eye_pivot(model):
    """A missing endocanthion (or ``hinge`` "pivot") leaves that eye to the eye pivot's +X turn of
    Bibliowicz 2005: no hinge share, and turn_lids then gives exactly the old turn."""
    rig, m = model("default")
    L = _canonical_landmarks(rig)
    eyes = {s: m.pivots_[m.bones_.index(f"eye_{s}")] for s in "lr"}
    lid = m.params_["eyelids"]
    L2 = {k: v for k, v in L.items() if k != "endocanthion_r"}
    points, axes, close, share, joints = lid_hinges(m.canonical_, m.skin_, L2, eyes, m.face_unit_, lid, m.surface_)
    assert np.allclose(axes[1], [1, 0, 0]) and close[1] == 0 and np.allclose(points[1], eyes["r"])
    assert close[0] > 0                                   # the other eye keeps its hinge
    right = m.canonical_[:, 0] < -0.1 * m.face_unit_
    assert not share[right].any() and share[~right].max() > 0.9
    doc = copy.deepcopy(load_expressions())
    doc["model"]["eyelids"]["hinge"] = "pivot"
    _, _, _, none, _ = lid_hinges(m.canonical_, m.skin_, L, eyes, m.face_unit_, model_parameters(doc)["eyelids"],
                               m.surface_)
    assert not none.any()
    # share 0: the turn is the eye pivot's, to the last bit
    d0 = np.zeros_like(m.canonical_)
    amounts = np.array([1.0, 0.7, 0.4, 0.2])
    old = turn_lids(d0, m.canonical_, amounts, m.lid_weights_, m.lid_close_deg_, m.lid_lower_range_, m.lid_pivots_)
    new = turn_lids(d0, m.canonical_, amounts, m.lid_weights_, m.lid_close_deg_, m.lid_lower_range_, m.lid_pivots_,
                    (points, axes, close, np.zeros(len(d0)), np.ones(4, bool)))
    assert np.array_equal(old, new)
    # the lower lids keep the pivot's turn: a lower-only pose is the old one exactly
    low = np.array([0.0, 0.0, 1.0, 0.8])
    old = turn_lids(d0, m.canonical_, low, m.lid_weights_, m.lid_close_deg_, m.lid_lower_range_, m.lid_pivots_)
    new = turn_lids(d0, m.canonical_, low, m.lid_weights_, m.lid_close_deg_, m.lid_lower_range_, m.lid_pivots_,
                    m.lid_hinges_)
    assert np.array_equal(old, new)


def test_a_lash_row_hinges_with_its_margin_as_one_piece(model):
    """ICT's upper lash rows sit on the margin: they take the hinge whole (share 1) and turn as one
    rigid piece about the corner line; the eye shells, rooted on both lids, follow the skin."""
    from autobones.geometry.topology import mesh_parts

    rig, m = model("ict")
    parts = mesh_parts(len(rig.vertices), rig.faces)
    share = m.lid_hinges_[3]
    V = m.pose_parameters(np.zeros(len(m.muscle_names_)), 0.0, [1.0, 1.0, 0.0, 0.0])
    hinged = 0
    for p in np.unique(parts[m.attached_]):
        rows = np.flatnonzero(parts == p)
        if np.ptp(m.lid_weights_[:, rows], axis=1).max() == 0.0 and m.lid_weights_[:2, rows[0]].max() > 0.5:
            assert np.ptp(share[rows]) == 0.0
            if share[rows[0]] == 1.0:
                hinged += 1
                E = rig.faces[np.isin(rig.faces, rows).all(axis=1)]
                e0 = np.linalg.norm(rig.vertices[E[:, 0]] - rig.vertices[E[:, 1]], axis=1)
                e1 = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
                assert np.allclose(e0, e1, rtol=1e-9)
    assert hinged >= 6, hinged                               # 3 upper lash rows per eye


def test_attached_parts_take_the_hinge_share_of_their_roots():
    share = np.array([0.0, 0.2, 0.9, 0.0, 0.0, 0.0])
    W = np.zeros((4, 6))
    W[0, :3] = 1.0                                          # an upper lid of three skin vertices
    attached = np.array([False, False, False, True, True, True])
    source = np.array([0, 1, 2, 2, 1, 0])
    parts = [(np.array([3, 4]), np.array([3])), (np.array([5]), np.array([5]))]
    out = attach_hinge_share(share, W, attached, source, parts)
    assert out[:3].tolist() == share[:3].tolist()
    assert out[3] == out[4] == 1.0 and out[5] == 0.0


# ------------------------------------------------------------------------------ new linear muscles
NEW = ("procerus", "nasalis", "risorius", "platysma")


def test_the_new_muscles_come_with_the_generic_rig(model):
    """Each new muscle is defined on both sides in generic_rig/muscles.json, built into the generic
    rig with its influence field ``muscle/<name>`` and carried onto a head by ``transfer``, and its
    type has a shortening in expressions.json (a muscle that moves)."""
    from autobones.rig_building.build import load_muscle_definitions

    defs = {m["name"]: m for m in load_muscle_definitions()}
    types = load_expressions()["muscle_types"]
    rig, m = model("default")
    for t in NEW:
        assert types[t]["shortening"] > 0
        for s in "lr":
            name = f"{t}_{s}"
            assert defs[name]["type"] == t and defs[name]["side"] == s
            assert name in m.muscle_names_
            f = np.asarray(rig.fields[f"muscle/{name}"])
            assert f.max() > 0.9 and (f > 0.1).sum() >= 10, name
            # its contraction moves the skin, on its own side only
            g = np.linalg.norm(m.muscle_basis_[m.muscle_names_.index(name)], axis=1)
            x = m.canonical_[:, 0] * (1 if s == "l" else -1)
            assert g.max() > 0.01 * m.face_unit_ and g[x < -0.2 * m.face_unit_].max() < 1e-3 * g.max(), name


def _moves(rig, m, au, landmark):
    """Canonical displacement (3,) in face units of the skin nearest ``landmark`` under ``au``."""
    i = _nearest_skin(rig, m, rig.extra["landmarks"][landmark])
    V = rig.frame.to_canonical(m.pose(au=au))
    return (V[i] - m.canonical_[i]) / m.face_unit_


def test_each_new_muscle_pulls_as_its_anatomy_says(model):
    """Procerus draws the glabella down over the nasal root, nasalis the side of the dorsum down
    and out, risorius the mouth corner out, platysma the corner and lower lip down (canonical:
    +Y up, +X the subject's left); each pulls its insertion toward its origin."""
    rig, m = model("default")
    mj = m.joints_

    def pull(name, landmark):
        c = np.zeros(len(m.muscle_names_))
        c[m.muscle_names_.index(name)] = 1.0
        if landmark == "insertion":        # the skin at the muscle's insertion
            idx = np.flatnonzero(m.skin_)
            i = idx[np.argmin(np.linalg.norm(m.canonical_[idx] - mj.insertions[mj.names.index(name)], axis=1))]
        else:
            i = _nearest_skin(rig, m, rig.extra["landmarks"][landmark])
        V = rig.frame.to_canonical(m.pose_parameters(c))
        return (V[i] - m.canonical_[i]) / m.face_unit_

    for name, landmark, check in (
            ("procerus_l", "glabella", lambda d: d[1] < -0.01),
            ("nasalis_l", "insertion", lambda d: d[1] < -0.002 and d[0] > 0.0),
            ("risorius_l", "cheilion_l", lambda d: d[0] > 0.01),
            ("risorius_r", "cheilion_r", lambda d: d[0] < -0.01),
            ("platysma_l", "cheilion_l", lambda d: d[1] < -0.01),
            ("platysma_l", "labiale_inferius", lambda d: d[1] < -0.005)):
        d = pull(name, landmark)
        j = mj.names.index(name)
        assert check(d), (name, landmark, d)
        assert d @ (mj.origins[j] - mj.insertions[j]) > 0, name


def test_the_action_units_use_the_new_muscles(model):
    """AU4 draws the nasal root down with the corrugators (procerus), AU9 too; AU20 stretches the
    corners out (risorius), AU21 (platysma) draws them down; AU11 exists; one-sided AU20 leaves the
    other half still; a rig transferred before these muscles existed still poses every AU."""
    rig, m = model("default")
    aus = load_expressions()["action_units"]
    assert "procerus" in aus["4"]["muscles"] and "procerus" in aus["9"]["muscles"]
    assert "nasalis" in aus["9"]["muscles"] and "nasalis" in aus["11"]["muscles"]
    assert "risorius" in aus["20"]["muscles"] and aus["21"]["muscles"] == {"platysma": 1.0}
    assert _moves(rig, m, {4: 1.0}, "glabella")[1] < -0.01
    assert _moves(rig, m, {9: 1.0}, "glabella")[1] < -0.005
    assert _moves(rig, m, {20: 1.0}, "cheilion_l")[0] > 0.01 and _moves(rig, m, {20: 1.0}, "cheilion_r")[0] < -0.01
    assert _moves(rig, m, {21: 1.0}, "cheilion_l")[1] < -0.01
    assert np.linalg.norm(_moves(rig, m, {11: 1.0}, "alare_l")) > 0.01
    V = m.pose(au={"20L": 1.0})
    d = np.linalg.norm(V - rig.vertices, axis=1)
    right = m.canonical_[:, 0] < -0.15 * m.face_unit_
    assert d[right].max() < 1e-3 * d.max()
    # an old rig (26 muscles): the AUs keep what its muscles give, the new types give nothing
    old = copy.copy(rig)
    old.muscles = [mm for mm in rig.muscles if mm["type"] not in NEW]
    m_old = ExpressionModel().fit(old)
    assert len(m_old.muscle_names_) == len(m.muscle_names_) - 8
    for au in (4, 9, 11, 20, 21):
        assert np.isfinite(m_old.pose(au={au: 1.0})).all()
    with pytest.raises(AutobonesError):
        m_old.pose(muscles={"procerus": 1.0})


def test_an_opening_lid_turns_about_the_eye_pivot_only(model):
    """AU5 (a negative upper amount: the levator retracts the lid over the eyeball) is the eye
    pivot's turn, hinge or not."""
    rig, m = model("default")
    d0 = np.zeros_like(m.canonical_)
    amounts = np.array([-0.3, -0.3, 0.0, 0.0])
    old = turn_lids(d0, m.canonical_, amounts, m.lid_weights_, m.lid_close_deg_, m.lid_lower_range_, m.lid_pivots_)
    new = turn_lids(d0, m.canonical_, amounts, m.lid_weights_, m.lid_close_deg_, m.lid_lower_range_, m.lid_pivots_,
                    m.lid_hinges_)
    assert np.array_equal(old, new) and np.abs(new).max() > 0
