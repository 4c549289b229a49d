"""expressions.lids, jaw, mouth_parts, bones and the rotation helpers of geometry.rotations."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from autobones.errors import AutobonesError
from autobones.expressions.bones import blend_bones, bone_transforms, turn_jaw, turn_lids
from autobones.expressions.definitions import load_expressions, model_parameters
from autobones.expressions.jaw import jaw_column, jaw_glide, jaw_weights, with_jaw_column
from autobones.expressions.lids import (attach_lid_weights, eye_corners, eye_lid_weights, lid_attachments,
                                        lid_weights, margin_release)
from autobones.expressions.mouth import mouth_line
from autobones.geometry.mouth_parts import inner_mouth_parts, mouth_part_weights
from autobones.expressions.surface import skin_surface
from autobones.geometry.rotations import align_rotation, axis_rotation, euler_rotation, x_turn
from shared_data import flat_grid

PARAMS = model_parameters(load_expressions())


def face(n=41, z=0.0):
    """A flat 2 x 2 sheet at height ``z`` facing +Z, its faces and SkinSurface."""
    V, F = flat_grid(n, 1.0, z)
    return V, F, skin_surface(V, F, [], 10)


# ------------------------------------------------------------------------------ rotations


def test_rotation_helpers():
    R = axis_rotation(0, 90.0)
    assert np.allclose(R @ R.T, np.eye(3)) and np.isclose(np.linalg.det(R), 1.0)
    assert np.allclose(R @ [0.0, 1.0, 0.0], [0.0, 0.0, 1.0])
    assert np.allclose(euler_rotation((10, 20, 30)),
                       axis_rotation(2, 30) @ axis_rotation(1, 20) @ axis_rotation(0, 10))
    assert np.allclose(euler_rotation([5]), axis_rotation(0, 5))
    rng = np.random.default_rng(0)
    for a, b in [rng.normal(size=(2, 3)), (np.array([0, 0, 1.0]), np.array([0, 0, -1.0]))]:
        a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
        assert np.allclose(align_rotation(a, b) @ a, b)
    P = rng.normal(size=(5, 3))
    assert np.allclose(x_turn(P, np.radians(25.0)), P @ (axis_rotation(0, 25.0) - np.eye(3)).T)


# ------------------------------------------------------------------------------ bones


def test_turning_the_lids_closes_the_margin():
    ps, pi = np.array([0.0, 0.05, 0.12]), np.array([0.0, -0.01, 0.12])
    phi = np.degrees(np.arctan2(ps[1], ps[2]) - np.arctan2(pi[1], pi[2]))
    V = np.array([ps, pi])
    d0 = np.zeros((2, 3))
    w = np.array([[1.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]])
    d = turn_lids(d0, V, np.array([1.0, 0, 0, 0]), w, np.array([phi, 0.0]), 0.35, np.zeros((2, 3)))
    p = V[0] + d[0]
    assert np.isclose(np.arctan2(p[1], p[2]), np.arctan2(pi[1], pi[2])) and not d[1].any() and not d0.any()
    assert np.array_equal(turn_lids(d0, V, np.zeros(4), w, np.array([phi, 0.0]), 0.35, np.zeros((2, 3))), d0)


def test_the_jaw_turns_about_its_pivot_by_its_weight():
    rng = np.random.default_rng(1)
    V = rng.normal(size=(20, 3))
    pivot = np.array([0.0, 0.5, -0.5])
    w = np.r_[np.ones(10), np.zeros(10)]
    d = turn_jaw(np.zeros_like(V), V, 20.0, w, pivot, np.zeros(3))
    assert np.allclose(np.linalg.norm(V[:10] + d[:10] - pivot, axis=1), np.linalg.norm(V[:10] - pivot, axis=1))
    assert not d[10:].any()
    g = turn_jaw(np.zeros_like(V), V, 10.0, w, pivot, np.array([0.0, -0.001, 0.002]))
    assert np.allclose(g[:10] - turn_jaw(np.zeros_like(V), V, 10.0, w, pivot, np.zeros(3))[:10], [0, -0.01, 0.02])


def test_bone_transforms_and_blending():
    names = ["neck", "head", "jaw", "eye_l", "eye_r"]
    piv = np.array([[0, -1.0, 0], [0, 0, 0], [0, 0.1, 0.2], [0.3, 0.4, 0.5], [-0.3, 0.4, 0.5]])
    assert bone_transforms(names, piv, 0.0, None, None, None, None) == {}
    T = bone_transforms(names, piv, 0.0, None, None, (0.0, 30.0, 0.0), None)
    R, t = T[1]
    assert np.allclose(R @ piv[1] + t, piv[1]) and set(T) == {1, 2, 3, 4}   # jaw and eyes ride the head
    T = bone_transforms(names, piv, 0.0, None, np.array([0.3, 0.4, 5.0]), None, None)
    R, t = T[3]
    assert np.allclose(R @ [0, 0, 1.0], [0, 0, 1.0])                        # the left eye looks straight ahead
    with pytest.raises(AutobonesError, match="neck"):
        bone_transforms(["head"], piv[:1], 0.0, None, None, None, (5.0, 0, 0))
    V = np.random.default_rng(2).normal(size=(6, 3))
    W = np.zeros((6, 5))
    W[:, 1] = 1.0
    T = bone_transforms(names, piv, 0.0, None, None, (10.0, 0.0, 0.0), None)
    d = blend_bones(np.zeros_like(V), V, W, T)
    assert np.allclose(V + d, V @ T[1][0].T + T[1][1])


def test_an_aimed_eye_starts_from_the_heads_own_front():
    """A transferred rig's canonical frame leans with the face (the goat's 46 degrees); its head's
    axes (``basis``) do not. An eye aimed at a point straight ahead of the head along the basis'
    front does not turn (it turned by the lean before: the aim started from the canonical +Z), and a
    point ahead and to the left turns it about the basis' up."""
    names = ["neck", "head", "jaw", "eye_l", "eye_r"]
    piv = np.array([[0, -1.0, 0], [0, 0, 0], [0, 0.1, 0.2], [0.3, 0.4, 0.5], [-0.3, 0.4, 0.5]])
    basis = axis_rotation(0, 40.0).T   # rows left, up, front of a head pitched 40 degrees in the canonical frame
    ahead = piv[3] + 10.0 * basis[2]
    R = bone_transforms(names, piv, 0.0, None, ahead, None, None, basis=basis)[3][0]
    assert np.abs(R - np.eye(3)).max() < 1e-9
    R = bone_transforms(names, piv, 0.0, None, piv[3] + 10.0 * (basis[2] + basis[0]), None, None, basis=basis)[3][0]
    axis = Rotation.from_matrix(R).as_rotvec()
    assert abs(np.degrees(np.linalg.norm(axis)) - 45.0) < 1e-6 and axis @ basis[1] > 0.999 * np.linalg.norm(axis)


# ------------------------------------------------------------------------------ lids


def test_lid_weights_open_above_and_below_the_fissure():
    V, F, surf = face(61, z=0.12)
    skin = surf.skin
    c = np.array([0.0, 0.0, 0.0])
    corners = eye_corners({}, c, "l", 1.0)
    up, low, close = eye_lid_weights(V, skin, c, corners, 1.0, 1.0, PARAMS["eyelids"])
    mid_y = np.interp(V[:, 0], [corners[1][0], corners[0][0]], [0.02, 0.02])
    assert close > 0 and up.max() == pytest.approx(1.0, abs=0.05) and low.max() > 0.5
    assert not up[V[:, 1] < mid_y - 1e-9].any() and not low[V[:, 1] > mid_y + 1e-9].any()
    assert not up[np.abs(V[:, 0]) > 1.6 * 0.15 * 1.5 + 0.05].any()          # within the lid's width
    W, close2, piv = lid_weights(V, F, skin, {}, {"l": c}, 1.0, PARAMS["eyelids"], surf)
    assert W.shape == (4, len(V)) and (W >= 0).all() and (W <= 1).all() and not W[[1, 3]].any()
    assert np.isclose(close2[0], close) and close2[1] == 0.0 and np.array_equal(piv[0], c)


def test_lid_margins_and_attached_parts():
    V, F, surf = face(21)
    lw = np.zeros((4, len(V)))
    top = V[:, 1] > 0.5
    lw[0, top] = 0.8
    assert np.allclose(margin_release(lw, 0.85), np.where(top, 1 - 0.85 * 0.8, 1.0))
    # a small part touching the upper lid skin (a row of lashes), one far off
    lash = np.array([[0.0, 0.6, 0.0], [0.05, 0.65, 0.02], [0.0, 0.7, 0.03]])
    far = np.array([[0.0, 0.0, 1.0], [0.1, 0.0, 1.0], [0.0, 0.1, 1.0]])
    V2 = np.r_[V, lash, far]
    n = len(V)
    skin = np.r_[np.ones(n, bool), np.zeros(6, bool)]
    part = np.r_[np.zeros(n, int), [1, 1, 1, 2, 2, 2]]
    lw2 = np.c_[lw, np.zeros((4, 6))]
    attached, source, parts = lid_attachments(V2, skin, part, np.zeros(n + 6), lw2.max(axis=0), 1.0, 0.5)
    assert attached[n:n + 3].all() and not attached[n + 3:].any() and not attached[:n].any()
    assert skin[source[attached]].all() and len(parts) == 1
    W = attach_lid_weights(lw2, attached, source, parts)
    assert np.allclose(W[:, n:n + 3], W[:, [n]]) and W[0, n] == 0.8          # turns whole with its lid
    assert np.array_equal(W[:, :n], lw) and not lw2[:, n:].any()             # a new array


# ------------------------------------------------------------------------------ jaw


def test_the_jaw_weight_opens_the_lower_lip_only():
    V, F, surf = face(41)
    corners = (np.array([0.5, 0.0, 0.0]), np.array([-0.5, 0.0, 0.0]), np.array([0.0, 0.0, 0.0]))
    mouth = mouth_line(V, surf.normals, surf.skin, corners, np.array([0.0, 0.0, -1.0]), 1.0, PARAMS["lips"])
    w = np.clip(0.5 - V[:, 1], 0.0, 1.0)                                       # a soft rig weight
    jaw = jaw_column(w, V, surf.skin, mouth, None, 1.0, PARAMS, surf)
    at = {tuple(np.round(v[:2], 3)): i for i, v in enumerate(V)}
    assert jaw[at[(0.0, 0.05)]] == 0.0 and jaw[at[(0.0, -0.05)]] == 1.0      # upper lip / lower lip
    assert jaw[at[(0.0, 0.5)]] == w[at[(0.0, 0.5)]]                           # the rig's weight outside the mouth
    assert (jaw >= 0).all() and (jaw <= 1).all()
    W = np.c_[1.0 - w, w, np.zeros(len(V))]                                    # head, jaw, eye
    Wj = with_jaw_column(W, 1, 0, jaw)
    assert np.allclose(Wj.sum(axis=1), 1.0) and np.array_equal(Wj[:, 1], jaw)
    assert np.array_equal(jaw_weights(W, ["head", "jaw", "eye_l"], V, surf.skin, mouth, None, 1.0, PARAMS, surf), Wj)
    assert np.array_equal(jaw_weights(W, ["head", "neck"], V, surf.skin, mouth, None, 1.0, PARAMS, surf), W)
    assert np.allclose(jaw_glide([0.003, 0.002], 2.0), [0.0, -0.006, 0.004])
    assert np.array_equal(jaw_glide([], 1.0), [0.0, 0.0, 0.0])


def test_mouth_parts_ride_the_jaw_below_and_the_skull_above():
    st = np.array([0.0, 0.0, 0.5])
    tooth_low = np.array([[0.0, -0.05, 0.4], [0.02, -0.02, 0.4], [0.0, -0.03, 0.38]])
    tooth_up = tooth_low * [1.0, -1.0, 1.0]
    gum = np.array([[x, y, 0.3] for x in (-0.3, 0.0, 0.3) for y in (-0.3, -0.01, 0.2, 0.4)])
    front = np.array([[0.0, 0.0, 0.9], [0.1, 0.0, 0.9], [0.0, 0.1, 0.9]])     # in front of the lips: not inside
    V = np.r_[tooth_low, tooth_up, gum, front]
    part = np.r_[[0] * 3, [1] * 3, [2] * 12, [3] * 3]
    found = inner_mouth_parts(V, part, np.ones(len(V), bool), st, 1.0, 0.9, 0.2)
    assert [len(r) for r, _, _ in found] == [3, 3, 12] and [s for _, _, s in found] == [True, True, False]
    W = np.zeros((len(V), 2))
    W[:, 0] = 1.0
    Wm, rows = mouth_part_weights(W, 1, 0, V, found, st, np.array([0.0, 0.0, -1.0]), 1.0, 0.03, 0.1)
    assert np.array_equal(rows, np.arange(18)) and np.allclose(Wm.sum(axis=1), 1.0)
    assert (Wm[:3, 1] == 1).all() and (Wm[3:6, 1] == 0).all()
    g = Wm[6:18, 1]
    assert (g[V[6:18, 1] < -0.05] == 1).all() and (g[V[6:18, 1] > 0.05] == 0).all()
    assert np.array_equal(Wm[18:], W[18:])
