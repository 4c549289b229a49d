"""Explaining a captured expression by a rig's shapes (autobones.arkit.explain): bounded least squares,
the explained fraction, the capture's rigid motion taken out, cosine and size."""
import numpy as np
import pytest

from autobones.arkit.explain import cosine_and_size, explain, rigid_align
from autobones.errors import AutobonesError
from autobones.geometry.rotations import axis_rotation


def _shapes(n=200, seed=3):
    rng = np.random.default_rng(seed)
    return {name: rng.normal(size=(n, 3)) for name in ("jawOpen", "mouthSmileLeft", "eyeBlinkLeft")}


def test_a_mix_of_the_shapes_is_explained_fully_with_its_weights():
    T = _shapes()
    d = 0.3 * T["jawOpen"] + 0.7 * T["eyeBlinkLeft"]
    w, e = explain(d, T)
    assert e == pytest.approx(1.0, abs=1e-6)
    assert w["jawOpen"] == pytest.approx(0.3, abs=1e-6) and w["eyeBlinkLeft"] == pytest.approx(0.7, abs=1e-6)
    assert w["mouthSmileLeft"] == pytest.approx(0.0, abs=1e-6)


def test_weights_stay_in_arkits_range_and_the_rest_is_unexplained():
    T = _shapes()
    rng = np.random.default_rng(9)
    other = rng.normal(size=(200, 3))
    # twice a shape: the weight stops at 1 and half is left; a field unlike any shape stays near 0
    w, e = explain(2.0 * T["jawOpen"], T)
    assert w["jawOpen"] == pytest.approx(1.0) and 0.4 < e < 0.6
    w, e = explain(other, T)
    assert all(0.0 <= v <= 1.0 for v in w.values()) and e < 0.15
    # a negative of a shape cannot be made with weights >= 0: nothing explained
    w, e = explain(-T["jawOpen"], T)
    assert w["jawOpen"] == pytest.approx(0.0, abs=1e-12) and e == pytest.approx(0.0, abs=1e-2)
    # without the upper bound, the double is made exactly
    w, e = explain(2.0 * T["jawOpen"], T, bounds=(0.0, np.inf))
    assert w["jawOpen"] == pytest.approx(2.0, abs=1e-6) and e == pytest.approx(1.0, abs=1e-6)


def test_only_the_masked_vertices_are_judged_and_dead_targets_take_no_weight():
    T = _shapes()
    T["tongueOut"] = np.zeros((200, 3))
    d = T["mouthSmileLeft"].copy()
    mask = np.zeros(200, dtype=bool)
    mask[:100] = True
    d[~mask] = 50.0  # outside the mask: not judged
    w, e = explain(d, T, mask)
    assert e == pytest.approx(1.0, abs=1e-6) and w["tongueOut"] == 0.0
    assert explain(np.zeros((200, 3)), T) == ({n: 0.0 for n in T}, 1.0)
    with pytest.raises(AutobonesError):
        explain(d, {})
    with pytest.raises(AutobonesError):
        explain(d[:50], T)
    with pytest.raises(AutobonesError):
        explain(d, T, mask[:50])


def test_rigid_align_takes_out_the_heads_motion_but_not_the_faces():
    rng = np.random.default_rng(5)
    V0 = rng.normal(size=(300, 3))
    face = np.zeros((300, 3))
    face[:60] = rng.normal(scale=0.2, size=(60, 3))  # a fifth of the vertices move: the face
    R = axis_rotation(1, 12.0) @ axis_rotation(0, 7.0)
    V = (V0 + face) @ R.T + np.array([3.0, -1.0, 0.5])
    X = rigid_align(V, V0)
    np.testing.assert_allclose(X[60:], V0[60:], atol=1e-9)
    np.testing.assert_allclose(X[:60] - V0[:60], face[:60], atol=1e-9)


def test_cosine_and_size():
    a = np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0]])
    assert cosine_and_size(a, a) == pytest.approx((1.0, 1.0))
    assert cosine_and_size(-2.0 * a, a) == pytest.approx((-1.0, 2.0))
    c, s = cosine_and_size(np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]), a)
    assert c == pytest.approx(0.0) and s == pytest.approx(1.0 / np.sqrt(5.0))
