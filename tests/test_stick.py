"""autobones.rig_transfer.stick: closest points on the target, barycentric coordinates, fold detection."""
import igl
import numpy as np
import pytest

from autobones.errors import AutobonesError
from autobones.io.mesh import load_mesh
from autobones.rig_transfer.stick import stick
from autobones.geometry.closest import barycentric

from shared_data import data, icosphere


def _grid(nx=21, ny=11, x=(-1, 1), y=(-0.5, 0.5)):
    X, Y = np.meshgrid(np.linspace(*x, nx), np.linspace(*y, ny), indexing="ij")
    V = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], axis=1)
    idx = np.arange(nx * ny).reshape(nx, ny)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    F = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return V, F


def test_points_land_on_the_target_surface_with_consistent_barycentrics():
    V, F = load_mesh(data("ict/identity000.obj"))
    rng = np.random.default_rng(0)
    X = V[::7] + rng.normal(scale=0.3, size=V[::7].shape)
    Fs = np.arange(len(X))[: 3 * (len(X) // 3)].reshape(-1, 3)
    P, face, bary, ok = stick(X, Fs, V, F)
    d2, _, _ = igl.point_mesh_squared_distance(P, V, F)
    assert np.sqrt(d2).max() < 1e-9
    np.testing.assert_allclose(np.einsum("ij,ijk->ik", bary, V[F[face]]), P, atol=1e-9)
    assert bary.min() >= 0 and np.allclose(bary.sum(axis=1), 1)
    # and they are the closest points: no target vertex is nearer
    dist = np.linalg.norm(P - X, axis=1)
    from scipy.spatial import cKDTree
    assert (dist <= cKDTree(V).query(X)[0] + 1e-9).all()
    assert ok.dtype == bool and ok.shape == (len(X),)


def test_inflated_sphere_sticks_back_radially_and_reliably():
    V, F = icosphere(3)
    P, face, bary, ok = stick(1.2 * V, F, V, F)
    np.testing.assert_allclose(P, V, atol=1e-9)
    assert ok.all()


def test_fold_over_a_sharp_ridge_is_detected():
    # target: a tent z = 1 - |x|; source: a flat sheet at z = 1.2. Every source vertex with
    # |x| < 0.2 lies in the crest's normal cone and lands on the crest line: its triangles
    # collapse; further out the projection only shrinks areas by 1/sqrt(2).
    Vt, Ft = _grid(61, 11)
    Vt[:, 2] = 1 - np.abs(Vt[:, 0])
    Vs, Fs = _grid(41, 11)
    Vs[:, 2] = 1.2
    P, face, bary, ok = stick(Vs, Fs, Vt, Ft, max_angle=90)
    crest = np.abs(Vs[:, 0]) < 0.1
    assert not ok[crest].any()
    assert ok[np.abs(Vs[:, 0]) > 0.4].all()


def test_opposite_normals_are_unreliable():
    V, F = _grid()
    Vs = V + [0, 0, 0.1]
    assert stick(Vs, F, V, F)[3].all()
    assert not stick(Vs, F, V, F[:, ::-1])[3].any()


def test_part_labels_keep_vertices_on_their_part():
    V, F = icosphere(2)
    Vt = np.concatenate([V, V * 0.5])           # outer and inner sphere
    Ft = np.concatenate([F, F + len(V)])
    face_labels = np.r_[np.zeros(len(F), int), np.ones(len(F), int)]
    Vs = 0.8 * V                                  # nearer the outer one
    P, face, _, _ = stick(Vs, F, Vt, Ft)
    assert (face < len(F)).all()
    P, face, _, _ = stick(Vs, F, Vt, Ft, labels=np.ones(len(V), int), face_labels=face_labels)
    assert (face >= len(F)).all()
    np.testing.assert_allclose(np.linalg.norm(P, axis=1), 0.5, atol=0.02)


def test_barycentric_of_degenerate_triangle_is_finite():
    A = np.zeros((1, 3))
    W = barycentric(A, A, A, A)
    assert np.isfinite(W).all() and np.allclose(W.sum(), 1)


def test_bad_input_raises():
    V, F = icosphere(1)
    with pytest.raises(AutobonesError, match="out of range"):
        stick(V, F, V, F + 1000)
    with pytest.raises(AutobonesError, match="shape"):
        stick(V[:, :2], F, V, F)
    with pytest.raises(AutobonesError, match="labels"):
        stick(V, F, V, F, labels=np.zeros(3, int), face_labels=np.zeros(len(F), int))
