"""autobones.placement.skin_weights: bone heat gives a smooth partition of unity on every kind of mesh."""
import numpy as np
import trimesh

from autobones.io.mesh import load_mesh
from autobones.placement.skin_weights import bone_heat_weights, segment_distances
from autobones.geometry.topology import weld

from shared_data import data, icosphere


def _check_partition(W):
    assert np.isfinite(W).all()
    assert W.min() >= 0.0
    np.testing.assert_allclose(W.sum(axis=1), 1.0, atol=1e-9)


def test_segment_distances_match_brute_force():
    rng = np.random.default_rng(0)
    P = rng.normal(size=(200, 3))
    seg = rng.normal(size=(5, 2, 3))
    t = np.linspace(0, 1, 2001)
    brute = np.stack([np.linalg.norm(P[:, None] - (s[0] + t[:, None] * (s[1] - s[0]))[None], axis=2).min(axis=1)
                      for s in seg], axis=1)
    np.testing.assert_allclose(segment_distances(P, seg), brute, atol=1e-3)


def test_two_bones_on_a_sphere_split_it_smoothly():
    V, F = icosphere(4)
    bones = np.array([[[0, 0.1, 0], [0, 0.6, 0]], [[0, -0.1, 0], [0, -0.6, 0]]], dtype=float)
    W = bone_heat_weights(V, F, bones)
    _check_partition(W)
    top, bottom = V[:, 1] > 0.5, V[:, 1] < -0.5
    assert W[top, 0].min() > 0.6 and W[bottom, 1].min() > 0.6
    # smooth: across the equator the weight changes gradually, no jump between neighbours
    E = np.asarray(trimesh.Trimesh(V, F, process=False).edges_unique)
    assert np.abs(W[E[:, 0], 0] - W[E[:, 1], 0]).max() < 0.15
    # monotone in height: weight of the top bone follows y
    order = np.argsort(V[:, 1])
    assert np.corrcoef(V[order, 1], W[order, 0])[0, 1] > 0.95


def test_disconnected_parts_and_unreferenced_vertices_get_weights():
    V1, F1 = icosphere(2)
    V2, F2 = icosphere(1, radius=0.2)
    V = np.vstack([V1, V2 + [3, 0, 0], [[10, 10, 10]]])  # last vertex is in no face
    F = np.vstack([F1, F2 + len(V1)])
    bones = np.array([[[0, 0, 0], [0, 0.5, 0]], [[3, 0, 0], [3, 0.1, 0]]], dtype=float)
    W = bone_heat_weights(V, F, bones)
    _check_partition(W)
    assert W[len(V1):-1, 1].min() > 0.99  # the small part follows its own bone


def test_unwelded_faces_still_share_heat():
    V, F = icosphere(3)
    # every face its own three vertices, as in low-poly game assets
    Vs, Fs = V[F].reshape(-1, 3), np.arange(3 * len(F)).reshape(-1, 3)
    bones = np.array([[[0, 0.1, 0], [0, 0.6, 0]], [[0, -0.1, 0], [0, -0.6, 0]]], dtype=float)
    W, Ws = bone_heat_weights(V, F, bones), bone_heat_weights(Vs, Fs, bones)
    _check_partition(Ws)
    # copies of one point get one weight, equal to the welded mesh's
    np.testing.assert_allclose(Ws, W[F.ravel()], atol=1e-9)


def test_non_manifold_edges_and_holes():
    V, F = icosphere(3)
    F = F[V[F].mean(axis=1)[:, 1] < 0.7]  # a hole at the top
    fin = np.array([[0, 0.0, 0.0], [0, 0.0, 2.0], [0, 1.0, 1.0]])  # a fin glued on an existing edge
    e = F[0, :2]
    V2 = np.vstack([V, fin[2]])
    F2 = np.vstack([F, [e[0], e[1], len(V)]])
    bones = np.array([[[0, 0.1, 0], [0, 0.6, 0]], [[0, -0.1, 0], [0, -0.6, 0]]], dtype=float)
    W = bone_heat_weights(V2, F2, bones)
    _check_partition(W)


def test_real_multi_part_head_ict():
    V, F = load_mesh(data("ict/generic_neutral_mesh.obj"))
    V = V / 33.8
    bones = np.array([[[0, -0.4, 0], [0, 0, 0]], [[0, 0, 0], [0, 0.3, 0]], [[0.1, 0.1, 0.3], [0.1, 0.1, 0.33]]])
    W = bone_heat_weights(V, F, bones)
    _check_partition(W)
    assert (W.max(axis=1) > 0).all()


def test_weld_merges_copies_only():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 0], [1, 0, 0], [0, 0, 1]], dtype=float)
    F = np.array([[0, 1, 2], [3, 4, 5]])
    Vw, Fw, index = weld(V, F, 1e-9)
    assert len(Vw) == 4 and index[0] == index[3] and index[1] == index[4]
    np.testing.assert_array_equal(Vw[index], V)
