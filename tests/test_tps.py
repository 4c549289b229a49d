"""autobones.geometry.tps: Bookstein thin-plate spline in 3-D."""
import json

import numpy as np
import pytest

from autobones.errors import AutobonesError
from autobones.io.mesh import load_mesh
from autobones.geometry.tps import ThinPlateSpline, landmark_arrays

from shared_data import data


def _random_landmarks(k=20, seed=0):
    rng = np.random.default_rng(seed)
    P = rng.normal(size=(k, 3))
    Q = P + 0.2 * rng.normal(size=(k, 3)) + 0.1 * np.sin(3 * P)
    return P, Q


def test_interpolates_the_landmarks_exactly():
    P, Q = _random_landmarks()
    tps = ThinPlateSpline().fit(P, Q)
    np.testing.assert_allclose(tps.transform(P), Q, atol=1e-10)
    assert tps.coef_.shape == (20, 3) and tps.affine_.shape == (4, 3)
    # side conditions of the TPS: kernel weights orthogonal to the affine space
    np.testing.assert_allclose(tps.coef_.sum(axis=0), 0, atol=1e-9)
    np.testing.assert_allclose(P.T @ tps.coef_, 0, atol=1e-9)


@pytest.mark.parametrize("seed", range(5))
def test_reproduces_any_affine_map(seed):
    rng = np.random.default_rng(seed)
    P = rng.normal(size=(12, 3)) * 50 + 1000       # far from the origin, large units
    A = rng.normal(size=(3, 3))
    t = rng.normal(size=3) * 100
    tps = ThinPlateSpline().fit(P, P @ A + t)
    np.testing.assert_allclose(tps.coef_, 0, atol=1e-8)
    X = rng.normal(size=(5000, 3)) * 80 + 1000
    np.testing.assert_allclose(tps.transform(X), X @ A + t, rtol=0, atol=1e-7 * np.abs(X @ A + t).max())
    assert tps.bending_energy_ < 1e-12 * np.abs(A).max() ** 2 * 1e4


def test_regularisation_trades_exactness_for_smoothness():
    P, Q = _random_landmarks(30, seed=1)
    residual, energy = [], []
    for reg in [0.0, 0.01, 0.1, 1.0, 10.0, 1e4]:
        tps = ThinPlateSpline(regularization=reg).fit(P, Q)
        residual.append(np.linalg.norm(tps.transform(P) - Q))
        energy.append(tps.bending_energy_)
    assert residual[0] < 1e-9
    assert all(a < b for a, b in zip(residual, residual[1:]))
    assert all(a > b for a, b in zip(energy, energy[1:]))
    # very strong smoothing: the least-squares affine map
    Pa = np.hstack([np.ones((30, 1)), P])
    aff = np.linalg.lstsq(Pa, Q, rcond=None)[0]
    tps = ThinPlateSpline(regularization=1e7).fit(P, Q)
    np.testing.assert_allclose(tps.transform(P), Pa @ aff, atol=1e-4)


def test_transform_is_chunked_and_matches_direct_sum():
    import autobones.geometry.tps as tps_mod

    P, Q = _random_landmarks(15, seed=2)
    tps = ThinPlateSpline().fit(P, Q)
    X = np.random.default_rng(3).normal(size=(3 * tps_mod.CHUNK + 7, 3))
    r = np.linalg.norm(X[:, None] - P[None], axis=2)
    direct = tps.affine_[0] + X @ tps.affine_[1:] + r @ tps.coef_
    np.testing.assert_allclose(tps.transform(X), direct, atol=1e-10)


def test_warps_ict_identity_landmarks_onto_the_other_head():
    src = json.load(open(data("ict/generic_neutral_mesh.landmarks.json")))["landmarks"]
    dst = json.load(open(data("ict/identity000.landmarks.json")))["landmarks"]
    names, P, Q = landmark_arrays(src, dst)
    assert len(names) == 27
    V, _ = load_mesh(data("ict/generic_neutral_mesh.obj"))
    W = ThinPlateSpline().fit(P, Q).transform(V)
    np.testing.assert_allclose(ThinPlateSpline().fit(P, Q).transform(P), Q, atol=1e-9)
    assert W.shape == V.shape and np.isfinite(W).all()


@pytest.mark.parametrize("P, words", [
    (np.eye(3), "at least 4"),
    (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 3, 0.]]), "one plane"),
    (np.array([[0, 0, 0], [1, 1, 1], [2, 2, 2], [3, 3, 3.]]), "one line"),
    (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0.]]), "same place"),
    (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [np.nan, 0, 1.]]), "NaN"),
    (np.zeros((5, 2)), "shape"),
])
def test_degenerate_landmarks_raise_a_helpful_error(P, words):
    with pytest.raises(AutobonesError, match=words):
        ThinPlateSpline().fit(P, P)


def test_bad_arguments_raise():
    P, Q = _random_landmarks(6)
    with pytest.raises(AutobonesError, match="same landmarks"):
        ThinPlateSpline().fit(P, Q[:5])
    with pytest.raises(AutobonesError, match="regularization"):
        ThinPlateSpline(regularization=-1).fit(P, Q)
    with pytest.raises(AutobonesError, match="before fit"):
        ThinPlateSpline().transform(P)
    with pytest.raises(AutobonesError, match="share only"):
        landmark_arrays({"a": [0, 0, 0]}, {"a": [0, 0, 0], "b": [1, 1, 1]})


def test_cardinal_weights_reproduce_the_warp_for_any_targets():
    """``cardinal(X) @ dst`` is the warp of X for the spline fitted to ``dst``, and the same weights
    serve other targets: they depend on the source landmarks only."""
    rng = np.random.default_rng(3)
    P = rng.normal(size=(12, 3))
    Q1, Q2 = P + 0.2 * rng.normal(size=P.shape), 2.0 * P + 1.0 + 0.1 * rng.normal(size=P.shape)
    X = rng.normal(size=(40, 3))
    S = ThinPlateSpline().fit(P, Q1).cardinal(X)
    assert S.shape == (40, 12)
    assert np.allclose(S @ Q1, ThinPlateSpline().fit(P, Q1).transform(X), atol=1e-10)
    assert np.allclose(S @ Q2, ThinPlateSpline().fit(P, Q2).transform(X), atol=1e-10)
    assert np.allclose(S.sum(axis=1), 1.0)          # constants are reproduced


def test_jacobian_matches_finite_differences():
    rng = np.random.default_rng(4)
    P = rng.normal(size=(10, 3))
    tps = ThinPlateSpline().fit(P, P + 0.3 * rng.normal(size=P.shape))
    X = rng.normal(size=(5, 3))
    J = tps.jacobian(X)
    h = 1e-6
    for a in range(3):
        d = np.zeros(3)
        d[a] = h
        fd = (tps.transform(X + d) - tps.transform(X - d)) / (2 * h)
        assert np.allclose(J[:, a, :], fd, atol=1e-6)
