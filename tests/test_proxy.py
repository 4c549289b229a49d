"""autobones.geometry.proxy and the dense-scan path of ``place``: a decimated proxy keeps every part,
its heat weights stay close to the exact solve, and the rig does not depend on the input's frame."""
import numpy as np
import pytest
import trimesh

import autobones
import autobones.placement.pipeline as pipeline
import autobones.placement.skin_weights as skin_weights
from autobones.geometry.areas import triangle_areas
from autobones.geometry.closest import closest_points
from autobones.geometry.proxy import cluster_vertices, decimate_parts, mesh_proxy
from autobones.geometry.topology import mesh_parts
from autobones.io.mesh import load_mesh
from autobones.placement.skin_weights import bone_heat_weights

from shared_data import data, icosphere


@pytest.fixture(scope="module")
def ict():
    return load_mesh(data("ict/identity002.obj"))


@pytest.fixture(scope="module")
def dense_head():
    """LeePerrySmith (8,838 vertices, one closed part) Loop-subdivided once: 35,346 vertices."""
    V, F = load_mesh(data("misc/LeePerrySmith.obj"))
    V, F = trimesh.remesh.subdivide_loop(V, F, iterations=1)
    return np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64)


@pytest.mark.parametrize("precluster", [8, 1.5])  # 1.5: the large parts are vertex-clustered first
def test_decimate_parts_keeps_every_part(ict, precluster, monkeypatch):
    import autobones.geometry.proxy as proxy_module

    monkeypatch.setattr(proxy_module, "PRECLUSTER", precluster)
    V, F = ict
    proxy = mesh_proxy(V, F, 1e-6 * np.ptp(V, axis=0).max())
    Vp, Fp, part, face_part, kept = decimate_parts(proxy.vertices, proxy.faces, 8000, min_part_vertices=200)
    n = len(proxy.vertices)
    assert len(Vp) < 0.5 * n
    # every part of the input is in the proxy, and no proxy triangle joins two parts
    assert set(np.unique(face_part)) == set(np.unique(part))
    proxy_parts = mesh_parts(len(Vp), Fp)
    for p in np.unique(proxy_parts):
        assert len(np.unique(face_part[proxy_parts[Fp[:, 0]] == p])) == 1
    # parts too small to decimate are copied vertex for vertex
    whole = kept >= 0
    assert whole.any() and not whole.all()
    np.testing.assert_array_equal(Vp[kept[whole]], proxy.vertices[whole])


def test_cluster_vertices_keeps_the_surface(dense_head):
    V, F = dense_head
    Vc, Fc = cluster_vertices(V, F, 8000)
    assert 0.7 * 8000 <= len(Vc) <= 1.3 * 8000
    assert set(np.unique(Fc)) == set(range(len(Vc)))  # every vertex used
    assert ((Fc[:, 0] != Fc[:, 1]) & (Fc[:, 1] != Fc[:, 2]) & (Fc[:, 0] != Fc[:, 2])).all()
    assert len(np.unique(np.sort(Fc, axis=1), axis=0)) == len(Fc)  # no repeated triangle
    size = np.ptp(V, axis=0).max()
    assert abs(triangle_areas(Vc, Fc).sum() / triangle_areas(V, F).sum() - 1) < 0.05
    # every input vertex near the clustered surface: within a cell (about the new edge length)
    *_, d2 = closest_points(V, Vc, Fc)
    cell = np.sqrt(triangle_areas(V, F).sum() / 8000)
    assert np.sqrt(d2.max()) < cell and np.sqrt(d2).mean() < 0.01 * size


def test_mesh_proxy_maps_every_input_vertex():
    V, F = icosphere(3)
    # an unwelded copy (every face with its own corners) and one loose vertex
    Vu = np.vstack([V[F.ravel()], [[5.0, 5.0, 5.0]]])
    Fu = np.arange(3 * len(F)).reshape(-1, 3)
    proxy = mesh_proxy(Vu, Fu, 1e-9)
    assert len(proxy.vertices) == len(V) and proxy.coarse is None
    assert proxy.index[-1] == -1
    np.testing.assert_array_equal(proxy.vertices[proxy.index[:-1]], Vu[:-1])


def test_proxy_heat_close_to_the_exact_solve(dense_head, monkeypatch):
    V, F = dense_head
    C = (V - V.mean(axis=0)) / np.ptp(V, axis=0).max()
    rng = np.random.default_rng(0)
    heads = C[rng.choice(len(C), 12, replace=False)] * 0.8
    bones = np.stack([heads, heads * 0.9], axis=1)
    exact = bone_heat_weights(C, F, bones, max_vertices=None)
    monkeypatch.setattr(skin_weights, "PROXY_VERTICES", 8000)
    W = bone_heat_weights(C, F, bones, max_vertices=20000)
    assert np.isfinite(W).all() and W.min() >= 0
    np.testing.assert_allclose(W.sum(axis=1), 1.0, atol=1e-9)
    d = np.abs(W - exact)
    assert d.mean() < 2e-3, d.mean()
    assert np.quantile(d.max(axis=1), 0.99) < 0.1
    assert (W.argmax(axis=1) == exact.argmax(axis=1)).mean() > 0.98


def test_separate_parts_keep_their_own_weights(monkeypatch):
    # two spheres 2 % of a radius apart, one bone in each: a vertex takes its own sphere's bone,
    # never the neighbour's, even where the neighbour's surface is closer than its own proxy
    V, F = icosphere(5)
    V2, F2 = np.vstack([V, V + [2.02, 0.0, 0.0]]), np.vstack([F, F + len(V)])
    bones = np.array([[[0.0, -0.3, 0.0], [0.0, 0.3, 0.0]], [[2.02, -0.3, 0.0], [2.02, 0.3, 0.0]]])
    monkeypatch.setattr(skin_weights, "PROXY_VERTICES", 2000)
    W = bone_heat_weights(V2, F2, bones, max_vertices=5000)
    np.testing.assert_array_equal(W[:len(V), 0], 1.0)
    np.testing.assert_array_equal(W[len(V):, 1], 1.0)


def _place(V, F, monkeypatch):
    monkeypatch.setattr(pipeline, "PROXY_ABOVE", 20000)
    monkeypatch.setattr(pipeline, "PROXY_VERTICES", 8000)
    return autobones.place((V, F), density="medium")


def test_place_on_a_dense_head_is_deterministic_and_frame_free(dense_head, monkeypatch):
    V, F = dense_head
    rig = _place(V, F, monkeypatch)
    assert rig.timings["proxy"] >= 0 and np.isfinite(rig.weights).all()
    np.testing.assert_allclose(rig.weights.sum(axis=1), 1.0, atol=1e-9)
    again = _place(V, F, monkeypatch)
    np.testing.assert_array_equal(again.weights, rig.weights)
    np.testing.assert_array_equal(again.skeleton.heads, rig.skeleton.heads)
    # another frame and unit: the head turned to face -x, lying on its back, in millimetres
    R = np.array([[0.0, 0.0, -1.0], [0.0, -1.0, 0.0], [-1.0, 0.0, 0.0]])
    moved = _place(1000.0 * V @ R.T, F, monkeypatch)
    heads = (moved.skeleton.heads / 1000.0) @ R
    size = rig.frame.size
    assert np.abs(heads - rig.skeleton.heads).max() < 1e-6 * size
    assert np.abs(moved.weights - rig.weights).max() < 1e-6
