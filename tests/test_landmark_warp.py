"""autobones.geometry.landmark_warp: the landmarks' spline near them, their affine map far from them."""
import numpy as np
import pytest

from autobones.errors import AutobonesError
from autobones.geometry.landmark_warp import LocalLandmarkWarp
from autobones.geometry.tps import ThinPlateSpline


def _face_landmarks(seed=0):
    """20 points on the front of a unit sphere (a face's landmarks on a head)."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(20, 3)) * [0.4, 0.4, 0.1] + [0, 0, 1]
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def test_exact_at_the_landmarks_and_affine_far_away():
    P = _face_landmarks()
    rng = np.random.default_rng(1)
    Q = 1.5 * P + [0.2, -0.1, 0.3] + 0.05 * rng.normal(size=P.shape)
    warp = LocalLandmarkWarp().fit(P, Q)
    np.testing.assert_allclose(warp.transform(P), Q, atol=1e-12)
    far = np.array([[0.0, 0.0, -8.0], [6.0, 5.0, 0.0]])
    np.testing.assert_allclose(warp.transform(far), warp.far_[0] + far @ warp.far_[1:], atol=1e-9)
    assert np.all(warp.blend(P) == 1.0) and np.all(warp.blend(far) < 1e-12)


@pytest.mark.parametrize("seed", range(3))
def test_reproduces_any_affine_map(seed):
    rng = np.random.default_rng(seed)
    P = _face_landmarks(seed) * 90 + 500
    A, t = rng.normal(size=(3, 3)), rng.normal(size=3) * 10
    X = rng.normal(size=(2000, 3)) * 120 + 500
    np.testing.assert_allclose(LocalLandmarkWarp().fit(P, P @ A + t).transform(X), X @ A + t,
                               atol=1e-8 * np.abs(X @ A + t).max())


def test_the_same_warp_in_any_frame_and_unit():
    P = _face_landmarks()
    rng = np.random.default_rng(2)
    Q = P + 0.1 * rng.normal(size=P.shape)
    X = rng.normal(size=(500, 3))
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    moved = LocalLandmarkWarp().fit(1000 * P @ R.T + 7, Q).transform(1000 * X @ R.T + 7)
    np.testing.assert_allclose(moved, LocalLandmarkWarp().fit(P, Q).transform(X), atol=1e-9)


def test_the_spline_whole_near_the_landmarks_fading_beyond():
    """Within ``core`` RMS radii of a landmark the warp is the spline; beyond, its share falls
    monotonically (one Gaussian width: exp(-1/2))."""
    P = _face_landmarks()
    rng = np.random.default_rng(3)
    Q = P + 0.1 * rng.normal(size=P.shape)
    warp = LocalLandmarkWarp().fit(P, Q)
    r = warp.radius_
    near = P + 0.2 * r * np.array([1.0, 0, 0])
    np.testing.assert_allclose(warp.transform(near), ThinPlateSpline().fit(P, Q).transform(near), atol=1e-12)
    steps = np.linalg.norm(P[0]) + r * np.linspace(0.0, 3.0, 50)
    ray = P[0] / np.linalg.norm(P[0]) * steps[:, None]          # outward from a landmark, away from the rest
    share = warp.blend(ray)
    assert np.all(np.diff(share) <= 1e-15) and share[0] == 1.0 and share[-1] < 1e-3
    at = np.array([P[0] * (1 + (warp.core + warp.width) * r / np.linalg.norm(P[0]))])
    np.testing.assert_allclose(warp.blend(at), np.exp(-0.5), rtol=1e-9)


def test_refuses_a_bad_width():
    with pytest.raises(AutobonesError):
        LocalLandmarkWarp(width=0.0).fit(_face_landmarks(), _face_landmarks())
    with pytest.raises(AutobonesError):
        LocalLandmarkWarp().transform(np.zeros((1, 3)))
