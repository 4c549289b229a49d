"""expressions.wires (muscle wires and their smoothing), muscles.influence_fields, skull, creases."""
import numpy as np

from autobones.expressions.creases import crease_fields
from autobones.expressions.definitions import load_expressions, model_parameters, muscle_types
from autobones.expressions.mouth import mouth_line
from autobones.expressions.muscles import MuscleJoints, influence_fields
from autobones.expressions.skull import skull_clamp, slide_over_bone, tissue_thickness
from autobones.expressions.surface import skin_surface
from autobones.expressions.wires import locator_weights, muscle_basis, muscle_wires, smooth_muscle_fields
from shared_data import flat_grid

DOC = load_expressions()
PARAMS = model_parameters(DOC)
TYPES = muscle_types(DOC)


def face(n=41):
    """A flat 2 x 2 face (z = 0, facing +Z, fu = 1) with a mouth from x = -0.5 to 0.5 at y = 0."""
    V, F = flat_grid(n)
    surf = skin_surface(V, F, [], 10)
    corners = (np.array([0.5, 0.0, 0.0]), np.array([-0.5, 0.0, 0.0]), np.array([0.0, 0.0, 0.0]))
    mouth = mouth_line(V, surf.normals, surf.skin, corners, np.array([0.0, 0.0, -1.0]), 1.0, PARAMS["lips"])
    return V, F, surf, mouth


def joints(types=("zygomaticus_major",), sides=("l",)):
    k = len(types)
    return MuscleJoints([f"{t}_{s}" for t, s in zip(types, sides)], list(types), list(sides),
                        np.tile([0.6, 0.6, -0.1], (k, 1)), np.tile([0.2, 0.1, 0.0], (k, 1)), np.full(k, 0.1))


def test_locator_weights_follow_the_profile_and_keep_to_their_side():
    t = np.linspace(0.3, 1.12, 7)
    infl = np.full((7, 3), 0.4)
    cw = locator_weights(t, 0, infl, ["l", "r", "m"], 0.35, 0.5)
    assert (cw >= 0).all() and (cw.sum(axis=1) < 1).all()
    assert not cw[:, 1].any() and cw[:, 2].all()                  # the other side's muscle does not pull
    assert np.argmax(cw[:, 0]) == np.argmin(np.abs(t - 1.0))      # the own locator peaks at the insertion
    g = locator_weights(np.array([-0.4, 0.0, 0.2, 1.0]), 0, np.zeros((4, 1)), ["m"], 0.35, 0.5, galea_anchor=0.25)
    assert np.allclose(g[:3, 0], 1.0 / 1.35)                      # on the galea the own locator weighs fully


def test_a_wire_pulls_its_skin_toward_the_origin_and_leaves_the_other_lip():
    V, F, surf, mouth = face()
    mj = joints()
    G, coverage, wires = muscle_wires(V, surf.skin, mj, np.zeros((1, len(V))), TYPES, mouth, 1.0, PARAMS)
    assert wires[0]["side"] == "upper" and surf.skin[wires[0]["vertices"]].all()
    moved = np.linalg.norm(G[0], axis=1) > 0
    u = mj.directions[0]
    assert moved.any() and ((G[0][moved] @ u) < 0).all()          # shortening: toward the origin
    dist = np.min(np.linalg.norm(V[:, None, :] - wires[0]["base"][None], axis=2), axis=1)
    assert not moved[dist > wires[0]["dropoff"] + 0.2].any()      # nothing beyond the wire's dropoff
    lower_lip = (np.abs(V[:, 0]) < 0.3) & (V[:, 1] < -0.03) & (V[:, 1] > -0.08)
    assert not G[0][lower_lip].any() and (coverage >= 0).all()
    H, _ = muscle_basis(V, surf.skin, mj, np.zeros((1, len(V))), TYPES, mouth, 1.0, PARAMS, surf)
    assert H.shape == G.shape and np.abs(H).max() < np.abs(G).max()   # smoothed


def test_smoothing_keeps_a_constant_field_constant():
    V, F, surf, mouth = face(21)
    G = np.ones((2, len(V), 3))
    out = smooth_muscle_fields(G, np.array([True, False]), surf, mouth, 0.01)
    assert np.allclose(out, 1.0, atol=1e-9) and np.array_equal(G, np.ones_like(G))
    spike = np.zeros((1, len(V), 3))
    spike[0, len(V) // 2] = 1.0
    assert smooth_muscle_fields(spike, np.array([False]), surf, mouth, 0.01).max() < 0.5


def test_influence_fields_are_zero_without_a_field():
    f = influence_fields({"muscle/a": np.full(4, 0.5)}, ["a", "b"], 4)
    assert np.array_equal(f, [[0.5] * 4, [0.0] * 4])


def test_tissue_thickness_takes_the_regions_and_blends_them():
    V, F, surf, mouth = face(21)
    skull = PARAMS["skull"]
    flat = tissue_thickness(None, [], skull, 2.0, surf)
    assert np.allclose(flat, skull["default"] * 2.0)
    region = (V[:, 1] < 0).astype(int)                         # 0: forehead above, 1: cheeks below
    t = tissue_thickness(region, ["forehead", "cheeks"], skull, 1.0, surf)
    assert t.min() >= skull["forehead"] - 1e-12 and t.max() <= skull["cheeks"] + 1e-12
    assert np.isclose(t[np.argmax(V[:, 1])], skull["forehead"], atol=1e-3)
    assert np.isclose(t[np.argmin(V[:, 1])], skull["cheeks"], atol=1e-3)


def test_the_skull_clamp_and_sliding_over_bone():
    V, F, surf, mouth = face(21)
    clamp = skull_clamp(mouth)
    assert not clamp[mouth.zone >= 0.05].any() and clamp[mouth.zone == 0].all()
    G = np.tile([0.1, 0.2, 0.3], (2, len(V), 1))
    thick = np.where(V[:, 0] < 0, 0.01, 1.0)                  # thin tissue on the right half only
    out = slide_over_bone(G, np.array([True, False]), clamp, thick, surf.skull_normals, 0.04, 1.0)
    thin = clamp & (V[:, 0] < 0)
    assert np.allclose(out[0][thin, 2], 0.0) and np.allclose(out[0][thin, :2], [0.1, 0.2])
    assert np.array_equal(out[0][V[:, 0] > 0], G[0][V[:, 0] > 0]) and np.array_equal(out[1], G[1])


def test_creases_press_inward_where_the_muscle_reaches():
    V, F, surf, mouth = face(41)
    infl = np.ones((3, len(V)))
    ins = np.array([[0.2, 0.1, 0.0], [0.1, 0.2, 0.0], [0.2, 0.1, 0.0]])
    K = crease_fields(V, surf.normals, surf.skin, infl, ["frontalis_major", "corrugator", "zygomaticus_major"], ins,
                      0.0, 1.0, PARAMS["creases"])
    assert set(K) == {0, 1}
    for k in K.values():
        assert (k[:, :2] == 0).all() and (k[:, 2] <= 0).all() and k[:, 2].any()
    lam = PARAMS["creases"]["forehead_wavelength"]
    assert not K[0][V[:, 1] - 0.1 <= 0.5 * lam].any()                # furrows start above the brow
    assert not K[1][np.abs(V[:, 0]) >= PARAMS["creases"]["glabella_wavelength"]].any()
