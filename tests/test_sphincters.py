"""Issue #16 item 2, the sphincters seed 000 lacks: orbicularis oris (its peripheral and marginal
parts) and orbicularis oculi (its orbital part) as elliptical rings (Waters 1987), built into the
generic rig, carried by ``transfer`` and driving AU6, AU18, AU22, AU23 and AU24 (Ekman, Friesen &
Hager 2002). Mentalis, a sheet given the same way, lifts the chin (AU17). The ring's geometry
first, then the model on the default head."""
import copy

import numpy as np
import pytest

import autobones
from autobones.errors import AutobonesError
from autobones.expressions.definitions import load_expressions, muscle_types
from autobones.expressions.model import ExpressionModel
from autobones.expressions.sphincters import sphincter_field
from autobones.geometry.ring import ring_frame, ring_outline, ring_profile
from autobones.render import muscle_segments

from shared_data import ROOT

SPHINCTERS = ("orbicularis_oris", "orbicularis_oris_marginalis", "orbicularis_oculi")
REACH = {"lateral": 2.0, "medial": 1.5, "above": 1.0, "below": 3.0}


# ------------------------------------------------------------------------------ the ring
def test_ring_frame_is_level_orthonormal_and_mirrors():
    c = np.array([0.1, -0.2, 0.5])
    axes, half = ring_frame(c, c + [0.3, 0.05, -0.1])
    assert np.allclose(axes @ axes.T, np.eye(3), atol=1e-12)
    assert abs(half - 0.3) < 1e-12                      # the up and front parts do not count
    assert axes[0] @ [1, 0, 0] > 0.999 and axes[1][1] > 0.999 and axes[2][2] > 0.999
    # the right-hand ring's x points to the subject's right; y and z still up and front
    axes_r, half_r = ring_frame(c, c + [-0.3, 0.05, -0.1])
    assert abs(half_r - half) < 1e-12 and axes_r[0][0] < -0.999 and axes_r[1][1] > 0.999 and axes_r[2][2] > 0.999
    with pytest.raises(AutobonesError):
        ring_frame(c, c + [0.0, 0.2, 0.1])              # nothing across the face


def test_ring_profile_reaches_each_quadrant_and_no_further():
    c = np.zeros(3)
    axes, half = ring_frame(c, [0.5, 0, 0])
    on_axes = {"lateral": [1, 0], "medial": [-1, 0], "above": [0, 1], "below": [0, -1]}
    for q, (sx, sy) in on_axes.items():
        r = REACH[q] * half
        P = np.array([[sx * f * r, sy * f * r, 0.0] for f in (0.2, 0.9, 0.99, 1.01)])
        rho, g = ring_profile(P, c, axes, half, REACH, core=0.3)
        assert np.allclose(rho, [0.2, 0.9, 0.99, 1.01])
        assert g[0] == 1.0 and 0 < g[2] < g[1] < 1 and g[3] == 0.0, q
    # behind the face: nothing, whatever the radius
    _, g = ring_profile(np.array([[0, 0, -0.7 * 3.0 * half]]), c, axes, half, REACH)
    assert g[0] == 0.0
    with pytest.raises(AutobonesError):
        ring_profile(np.zeros((1, 3)), c, axes, half, {**REACH, "below": 0.0})


def test_ring_halves_sum_to_the_whole_and_the_hole_is_empty():
    rng = np.random.default_rng(1)
    P = np.column_stack([rng.uniform(-1, 1, (500, 2)), np.zeros(500)])
    c = np.zeros(3)
    sym = {"lateral": 1.5, "medial": 1.5, "above": 1.0, "below": 1.2}
    al, half = ring_frame(c, [0.4, 0, 0])
    ar, _ = ring_frame(c, [-0.4, 0, 0])
    _, whole = ring_profile(P, c, al, half, sym)
    _, gl = ring_profile(P, c, al, half, sym, split=0.3)
    _, gr = ring_profile(P, c, ar, half, sym, split=0.3)
    assert np.allclose(gl + gr, whole, atol=1e-12)
    assert gl[P[:, 0] < -0.15 * half].max() == 0.0      # each half stays on its side of the blend
    rho, gh = ring_profile(P, c, al, half, sym, hole=(0.2, 0.4))
    assert gh[rho < 0.2].max() == 0.0 and np.allclose(gh[rho > 0.4], whole[rho > 0.4])


def test_ring_outline_lies_on_the_ellipse_and_pictures_each_muscle():
    c = np.array([0.0, 0.1, 0.2])
    lateral = c + [0.5, 0.0, -0.1]
    axes, half = ring_frame(c, lateral)
    P = ring_outline(c, lateral, REACH, radius=0.7, count=40)
    rho, _ = ring_profile(P, c, axes, half, REACH)
    assert P.shape == (40, 3) and np.allclose(rho, 0.7) and np.allclose((P - c) @ axes[2], 0.0)
    arc = ring_outline(c, lateral, REACH, count=9, arc=(-0.5 * np.pi, 0.5 * np.pi))
    assert np.all((arc - c) @ axes[0] >= -1e-12) and np.allclose(arc[[0, -1]] @ axes[0], c @ axes[0])
    linear = {"origin": [0.0, 0.0, 0.0], "insertion": [0.1, 0.2, 0.3]}
    ring = {"kind": "sphincter", "origin": list(c), "insertion": list(lateral), "reach": REACH}
    half_ring = {**ring, "split": 0.3}
    S = muscle_segments([linear, ring, half_ring])
    assert S.shape == (1 + 32 + 16, 2, 3)
    assert np.allclose(S[0], [linear["origin"], linear["insertion"]])
    assert np.allclose(S[1:33, 1], np.roll(S[1:33, 0], -1, axis=0))      # the ring closes
    assert np.all(S[33:, :, :] @ axes[0] - c @ axes[0] >= -1e-12)                 # the half stays lateral


def test_sphincter_field_pulls_toward_the_centre_and_pushes_out():
    c = np.zeros(3)
    P = np.array([[0.3, 0.0, 0.0], [0.0, -0.2, 0.0], [0.6, 0.0, 0.0], [0.0, 0.0, 0.0]])
    g = np.ones(4)
    radial = {"shortening": 0.5, "sphincter": {"pull": "radial", "narrow": 1.0, "close": 1.0, "protrude": 0.0}}
    d = sphincter_field(P, c, [0.4, 0, 0], g, radial)
    assert np.allclose(d[:3], -0.5 * P[:3])             # by the offset times the shortening (Waters 1987)
    sheet = {"shortening": 0.5, "sphincter": {"pull": "sheet", "narrow": 1.0, "close": 1.0, "protrude": 0.0}}
    d = sphincter_field(P, c, [0.4, 0, 0], g, sheet)
    assert np.allclose(np.linalg.norm(d[[0, 2]], axis=1), 0.5 * 0.4)   # one length, the ring's half size
    assert np.allclose(d[:3] / np.linalg.norm(d[:3], axis=1, keepdims=True),
                       -P[:3] / np.linalg.norm(P[:3], axis=1, keepdims=True))
    out = {"shortening": 0.5, "sphincter": {"pull": "radial", "narrow": 0.0, "close": -1.0, "protrude": 1.0}}
    d = sphincter_field(P, c, [0.4, 0, 0], np.array([1.0, 0.5, 0.0, 1.0]), out)
    assert np.allclose(d[:, 2], 0.5 * 0.4 * np.array([1.0, 0.25, 0.0, 1.0]))   # forward by g squared
    assert d[1, 1] < 0                                  # close < 0: away from the line (lips turned out)
    assert np.allclose(d[:, 0], 0.0)                    # narrow 0: nothing across
    with pytest.raises(AutobonesError):
        sphincter_field(P, c, [0.4, 0, 0], g, {"shortening": 1.0, "sphincter": {"pull": "twist"}})


def test_sheet_field_lifts_toward_the_line_as_one_patch():
    """A sheet (mentalis): toward the level line by the distance from it, at most the half size;
    across only with ``narrow``; forward by g squared."""
    c = np.zeros(3)
    P = np.array([[0.0, -0.1, 0.0], [0.3, -0.1, 0.0], [0.0, -0.6, 0.0], [0.5, -0.9, 0.0]])
    spec = {"shortening": 0.5, "sheet": {"pull": "line", "close": 1.0, "protrude": 0.5}}
    d = sphincter_field(P, c, [0.4, 0, 0], np.ones(4), spec)
    assert np.allclose(d[:, 0], 0.0)                    # narrow 0 by default: nothing across
    assert np.allclose(d[:, 1], 0.5 * np.array([0.1, 0.1, 0.4, 0.4]))  # up by the distance, at most the half size
    assert np.allclose(d[:, 2], 0.5 * 0.5 * 0.4)        # forward: protrude x half size x g^2


# ------------------------------------------------------------------------------ on a head
@pytest.fixture(scope="module")
def default():
    rig = autobones.transfer(None, ROOT / "generic_rig" / "default_head.landmarks.json")
    return rig, ExpressionModel().fit(rig)


def _skin_near(m, point, radius):
    return m.skin_ & (np.linalg.norm(m.canonical_ - point, axis=1) < radius)


def _landmarks(rig):
    return {k: rig.frame.to_canonical(np.asarray(v, float).reshape(1, 3))[0]
            for k, v in rig.extra["landmarks"].items()}


def test_the_sphincters_come_with_the_generic_rig(default):
    """Both halves of each sphincter are in the generic rig with a ring-shaped influence field
    carried by transfer; their types have no wire; no wire is made for them."""
    rig, m = default
    types = muscle_types(load_expressions())
    for t in SPHINCTERS:
        assert types[t]["sphincter"] is not None and "wire" not in types[t]
        for s in "lr":
            name = f"{t}_{s}"
            f = np.asarray(rig.fields[f"muscle/{name}"])
            assert name in m.muscle_names_ and f.max() > 0.9 and (f > 0.5).sum() >= 20, name
            assert name not in [w["muscle"] for w in m.wires_]
            x = m.canonical_[:, 0] * (1 if s == "l" else -1)
            g = np.linalg.norm(m.muscle_basis_[m.muscle_names_.index(name)], axis=1)
            assert g.max() > 0.01 * m.face_unit_ and g[x < -0.2 * m.face_unit_].max() < 1e-3 * g.max(), name


def test_pucker_gathers_and_pushes_out_the_lips(default):
    """AU18: the mouth narrows (the corners move toward each other) and the lips move forward;
    the eyes do not move; one-sided AU18L leaves the right half still."""
    rig, m = default
    L = _landmarks(rig)
    fu = m.face_unit_
    V = rig.frame.to_canonical(m.pose(au={18: 1.0}))
    d = V - m.canonical_
    width = lambda X: np.linalg.norm(X[_nearest(m, L["cheilion_l"])] - X[_nearest(m, L["cheilion_r"])])
    w0, w1 = width(m.canonical_), width(V)
    assert w1 < 0.9 * w0, (w0, w1)
    lips = _skin_near(m, L["stomion"], 0.12 * fu)
    assert d[lips, 2].mean() > 0.02 * fu
    eyes = _skin_near(m, L["exocanthion_l"], 0.1 * fu) | _skin_near(m, L["exocanthion_r"], 0.1 * fu)
    assert np.abs(d[eyes]).max() < 1e-3 * fu
    Vl = rig.frame.to_canonical(m.pose(au={"18L": 1.0}))
    dl = np.linalg.norm(Vl - m.canonical_, axis=1)
    assert dl[m.canonical_[:, 0] < L["stomion"][0] - 0.15 * fu].max() < 1e-3 * dl.max()


def _nearest(m, point, k=None):
    """The skin vertex nearest ``point`` (canonical), or the ``k`` nearest."""
    idx = np.flatnonzero(m.skin_)
    dist = np.linalg.norm(m.canonical_[idx] - point, axis=1)
    return idx[np.argmin(dist)] if k is None else idx[np.argsort(dist, kind="stable")[:k]]


def test_press_brings_the_lips_together_and_funnel_parts_them(default):
    """AU24 moves the upper lip down and the lower lip up; AU22 pushes the lips out and apart."""
    rig, m = default
    L = _landmarks(rig)
    fu = m.face_unit_
    up, lo = _nearest(m, L["labiale_superius"]), _nearest(m, L["labiale_inferius"])
    gap = lambda X: X[up, 1] - X[lo, 1]
    P = rig.frame.to_canonical(m.pose(au={24: 1.0}))
    assert gap(P) < gap(m.canonical_) - 0.01 * fu
    Fn = rig.frame.to_canonical(m.pose(au={22: 1.0}))
    assert gap(Fn) > gap(m.canonical_) + 0.005 * fu
    lips = _skin_near(m, L["stomion"], 0.12 * fu)
    assert (Fn - m.canonical_)[lips, 2].mean() > 0.01 * fu


def test_chin_raiser_lifts_the_chin_and_pushes_the_lower_lip_up_and_out(default):
    """AU17 (mentalis as a sheet): the chin and the lower lip rise and come forward, the chin more
    than the lip (ICT's mouthShrugLower: 25 and 12 thousandths of a head size); the upper lip and
    the nose stay; no wire is made for it."""
    rig, m = default
    L = _landmarks(rig)
    fu = m.face_unit_
    assert "mentalis_l" not in [w["muscle"] for w in m.wires_]
    d = rig.frame.to_canonical(m.pose(au={17: 1.0})) - m.canonical_
    chin = _nearest(m, 0.5 * (L["pogonion"] + L["sublabiale"]), k=6)
    lip = _nearest(m, L["labiale_inferius"], k=6)
    assert d[chin, 1].mean() > 0.02 * fu and d[chin, 2].mean() > 0.005 * fu
    assert 0 < d[lip, 1].mean() < d[chin, 1].mean() and d[lip, 2].mean() > 0
    still = _nearest(m, L["labiale_superius"], k=6).tolist() + _nearest(m, L["pronasale"], k=6).tolist()
    assert np.abs(d[still]).max() < 0.1 * d[chin, 1].mean()


def test_cheek_raiser_lifts_the_cheek_toward_the_eye(default):
    """AU6 (orbicularis oculi, pars orbitalis): the cheek under each eye rises, the skin beside the
    outer eye corner moves in toward it; the mouth corners barely move (it is not a smile)."""
    rig, m = default
    L = _landmarks(rig)
    fu = m.face_unit_
    c = np.zeros(len(m.muscle_names_))
    for s in "lr":
        c[m.muscle_names_.index(f"orbicularis_oculi_{s}")] = 1.0
    d = rig.frame.to_canonical(m.pose_parameters(c)) - m.canonical_
    for s, sign in (("l", 1.0), ("r", -1.0)):
        ex, en = L[f"exocanthion_{s}"], L[f"endocanthion_{s}"]
        centre = 0.5 * (ex + en)
        cheek = _nearest(m, centre - [0, 0.3 * fu, 0], k=6)
        assert d[cheek, 1].mean() > 0.01 * fu, s
        temple = _nearest(m, ex + [sign * 0.12 * fu, 0, 0], k=6)
        assert sign * d[temple, 0].mean() < -0.003 * fu, s
        corner = _nearest(m, L[f"cheilion_{s}"])
        assert np.linalg.norm(d[corner]) < 0.1 * np.abs(d[cheek, 1]).mean()


def test_action_units_use_the_sphincters_and_old_rigs_still_pose(default):
    rig, m = default
    aus = load_expressions()["action_units"]
    assert "orbicularis_oculi" in aus["6"]["muscles"]
    assert "orbicularis_oris" in aus["18"]["muscles"] and "orbicularis_oris" in aus["22"]["muscles"]
    assert "orbicularis_oris_marginalis" in aus["23"]["muscles"] and "orbicularis_oris_marginalis" in aus["24"]["muscles"]
    old = copy.copy(rig)
    old.muscles = [mm for mm in rig.muscles if mm["type"] not in SPHINCTERS]
    m_old = ExpressionModel().fit(old)
    assert len(m_old.muscle_names_) == len(m.muscle_names_) - 6
    for au in (6, 18, 22, 23, 24):
        assert np.isfinite(m_old.pose(au={au: 1.0})).all()
    # the other muscles' fields do not change with the sphincters there (no cross-talk)
    for nm in m_old.muscle_names_:
        a, b = m_old.muscle_basis_[m_old.muscle_names_.index(nm)], m.muscle_basis_[m.muscle_names_.index(nm)]
        assert np.abs(a - b).max() <= 1e-9 * np.abs(b).max(), nm


def test_a_rig_built_with_another_kind_of_mentalis_is_one_clear_error(default):
    """A rig whose mentalis was built as a linear muscle (before it became a sheet) posed with today's
    definitions: one clear error naming the muscle, not a wire field read as a patch."""
    rig, _ = default
    old = copy.copy(rig)
    old.muscles = [{k: v for k, v in mm.items() if k != "kind"} if mm["type"] == "mentalis" else mm
                   for mm in rig.muscles]
    with pytest.raises(AutobonesError, match="mentalis_l.*linear muscle in this rig.*sheet"):
        ExpressionModel().fit(old)


def test_an_incomplete_sphincter_definition_is_one_clear_error():
    from autobones.io.landmarks import read_landmarks
    from autobones.io.mesh import load_mesh
    from autobones.rig_building.build import build_rig, load_muscle_definitions

    V, F = load_mesh(ROOT / "generic_rig" / "default_head.obj")
    lm = read_landmarks(ROOT / "generic_rig" / "default_head.landmarks.json")
    ring = [m for m in load_muscle_definitions() if m["name"] == "orbicularis_oris_l"][0]
    for broken in ({k: v for k, v in ring.items() if k != "reach"}, {**ring, "reach": {"lateral": 1.0}},
                   {**ring, "reach": 2.0}, {**ring, "hole": [0.2]}):
        with pytest.raises(AutobonesError, match="orbicularis_oris_l"):
            build_rig(V, F, lm, muscles=[broken])


def test_a_muscle_type_without_wire_or_ring_is_one_clear_error(default):
    """A definitions file whose muscle type has neither a wire (linear) nor a sphincter entry is
    named in one error, not a KeyError from inside the wires."""
    rig, _ = default
    doc = copy.deepcopy(load_expressions())
    doc["muscle_types"]["orbicularis_oris"] = {"shortening": 0.3}
    with pytest.raises(AutobonesError, match="orbicularis_oris"):
        ExpressionModel(doc).fit(rig)
    doc["muscle_types"]["orbicularis_oris"] = {"shortening": 0.3, "sphincter": {"pull": "spiral"}}
    with pytest.raises(AutobonesError, match="pull"):
        ExpressionModel(doc).fit(rig)
