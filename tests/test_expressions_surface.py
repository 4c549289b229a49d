"""expressions.surface (the welded skin), mouth (the mouth line), unfold (folds relaxed)."""
import numpy as np
import pytest

from autobones.errors import AutobonesError
from autobones.expressions.definitions import load_expressions, model_parameters
from autobones.expressions.mouth import mouth_corners, mouth_line
from autobones.expressions.surface import skin_surface, weld_if_split
from autobones.expressions.unfold import flipped_faces, rigid_patches, turned_faces, unfold
from shared_data import flat_grid

PARAMS = model_parameters(load_expressions())


def grid(n=21, half=1.0):
    """A flat (n*n, 3) grid in the z = 0 plane facing +Z, and its faces."""
    return flat_grid(n, half)


def test_a_mesh_in_pieces_is_welded_and_a_whole_one_is_not():
    V, F = grid(6)
    Vw, Fw, index, first = weld_if_split(V, F)
    assert Vw is V and Fw is F and np.array_equal(index, np.arange(len(V)))
    Vs, Fs = V[F].reshape(-1, 3), np.arange(3 * len(F)).reshape(-1, 3)     # every triangle on its own
    Vw, Fw, index, first = weld_if_split(Vs, Fs)
    assert len(Vw) == len(V)
    assert np.array_equal(Vs[first][index], Vs)                            # welded copies share a position
    assert np.array_equal(index[first], np.arange(len(Vw)))


def test_skin_surface_is_the_largest_part_without_the_eyes():
    V, F = grid(11)
    small = np.array([[0.0, 0.0, -0.5], [0.1, 0.0, -0.5], [0.0, 0.1, -0.5]])
    V2, F2 = np.r_[V, small], np.r_[F, [[len(V), len(V) + 1, len(V) + 2]]]
    eye = np.zeros(len(V2))
    eye[5] = 0.7
    s = skin_surface(V2, F2, [eye], PARAMS["skull_smoothing_passes"])
    assert s.skin[:len(V)].sum() == len(V) - 1 and not s.skin[5] and not s.skin[len(V):].any()
    assert np.allclose(s.normals[:len(V)], [0.0, 0.0, 1.0])
    assert np.allclose(np.linalg.norm(s.skull_normals, axis=1), 1.0)
    assert np.isclose(s.rest_areas.sum(), 4.0 - 3 * 0.2 ** 2 / 2)   # the three faces at the eye vertex drop
    assert (s.relax_weights.data >= 0).all()
    assert np.allclose(s.relax_degree, np.asarray(s.relax_weights.sum(axis=1)).ravel())


def test_diffusions_over_one_time_share_a_factorisation_inside_the_block(monkeypatch):
    import autobones.expressions.surface as surface_module
    from autobones.geometry.laplacian import diffuse

    V, F = grid(15)
    s = skin_surface(V, F, [], PARAMS["skull_smoothing_passes"])
    u = np.zeros(len(V))
    u[len(V) // 2] = 1.0
    alone = s.diffuse(u, 0.01)
    assert np.array_equal(alone, diffuse(u, s.laplacian, s.mass, 0.01))   # as the plain heat step
    assert alone.max() < 1.0 and alone.min() > 0.0 and abs((s.mass @ alone).sum() - (s.mass @ u).sum()) < 1e-12  # heat kept
    made = []
    real = surface_module.factor_spd
    monkeypatch.setattr(surface_module, "factor_spd", lambda A: made.append(A.shape) or real(A))
    with s.sharing_factors():
        a, b = s.diffuse(u, 0.01), s.diffuse(np.c_[u, 2 * u], 0.01)
        c = s.diffuse(u, 0.02)
    assert len(made) == 2                                   # 0.01 once, 0.02 once
    assert np.array_equal(a, alone) and np.array_equal(b[:, 0], alone) and not np.array_equal(c, alone)
    s.diffuse(u, 0.01)
    assert len(made) == 3 and s._factors is None           # dropped after the block


def test_the_mouth_line_splits_upper_from_lower_lip():
    V, F = grid(41)
    N = np.tile([0.0, 0.0, 1.0], (len(V), 1))
    skin = np.ones(len(V), dtype=bool)
    corners = (np.array([0.5, 0.0, 0.0]), np.array([-0.5, 0.0, 0.0]), np.array([0.0, 0.0, 0.0]))
    m = mouth_line(V, N, skin, corners, np.array([0.0, 0.0, -1.0]), 1.0, PARAMS["lips"])
    at = {tuple(np.round(v[:2], 3)): i for i, v in enumerate(V)}
    up, down, far = at[(0.0, 0.1)], at[(0.0, -0.1)], at[(0.0, 0.5)]
    assert m.upper[up] == 1.0 and m.upper[down] == 0.0
    assert m.zone[at[(0.0, 0.0)]] == 1.0 and m.zone[far] == 0.0 and m.zone[at[(0.9, 0.0)]] == 0.0
    assert not m.inward.any() and m.height(0.3) == 0.0 and m.half_width == 0.5
    col = np.flatnonzero(np.isclose(V[:, 0], 0.0))
    assert (np.diff(m.upper[col][np.argsort(V[col, 1])]) >= 0).all()     # monotone up through the lips


def test_mouth_corners_fall_back_to_the_muscles_and_the_front_skin():
    V, F = grid(21)
    V[:, 2] = -V[:, 1] ** 2                                              # the front is at y = 0
    skin = np.ones(len(V), dtype=bool)
    ins = {"buccinator_l": np.array([0.4, 0.0, 0.0]), "buccinator_r": np.array([-0.4, 0.0, 0.0])}
    ch_l, ch_r, st = mouth_corners({}, ins, V, skin, 1.0)
    assert np.array_equal(ch_l, ins["buccinator_l"]) and np.allclose(st, [0.0, 0.0, 0.0])
    with pytest.raises(AutobonesError):
        mouth_corners({}, {}, V, skin, 1.0)


def test_flipped_faces_and_turned_faces():
    V0 = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0], [1e-4, 0, 0], [0, 1e-4, 0]])
    F = np.array([[0, 1, 2], [3, 4, 5]])
    V1 = V0 * [1.0, -1.0, 1.0]                                            # mirrored: both turn over
    assert flipped_faces(V0, V1, F).tolist() == [True, True]
    assert flipped_faces(V0, V1, F, min_area=1e-6).tolist() == [True, False]
    assert not flipped_faces(V0, V0 * 2.0, F).any()
    n0 = np.cross(V0[F[:, 1]] - V0[F[:, 0]], V0[F[:, 2]] - V0[F[:, 0]])
    assert np.array_equal(turned_faces(V1, F, n0), flipped_faces(V0, V1, F))


def test_unfolding_removes_a_fold_and_leaves_the_rest_alone():
    V, F = grid(21)
    s = skin_surface(V, F, [], 10)
    d = np.zeros_like(V)
    assert unfold(d, V, s, 0.5) is d                                      # nothing folded: untouched
    c = np.flatnonzero(np.all(np.isclose(V[:, :2], [0.0, 0.0]), axis=1))[0]
    d[c] = [0.25, 0.0, 0.0]                                               # pushed 2.5 cells across its neighbours
    assert flipped_faces(V, V + d, F).any()
    out = unfold(d, V, s, 0.5)
    assert not flipped_faces(V, V + out, F).any()
    far = np.linalg.norm(V - V[c], axis=1) > 0.6
    assert np.array_equal(out[far], d[far])


def test_rigid_patches_moves_a_fold_with_its_surroundings():
    V, F = grid(21)
    s = skin_surface(V, F, [], 10)
    shift = np.tile([0.05, 0.02, 0.0], (len(V), 1))                      # the whole sheet translates
    c = np.flatnonzero(np.all(np.isclose(V[:, :2], [0.0, 0.0]), axis=1))[0]
    shift[c, 0] += 0.25                                                  # one vertex folds its fan
    dw, moved = rigid_patches(V, shift.copy(), s, 0.5)
    assert moved[c] and not flipped_faces(V, V + dw, F).any()
    assert np.allclose(dw[c], [0.05, 0.02, 0.0])                          # it takes the rigid motion around it
