"""Small closed parts move whole (autobones.geometry.rigid_parts): found on synthetic meshes and on ICT,
and ``place``'s weights one row per eyeball and tooth."""
import numpy as np
import trimesh

from autobones.geometry.areas import vertex_areas
from autobones.geometry.rigid_parts import closed_small_parts, rigid_weights
from autobones.geometry.topology import mesh_parts
from autobones.io.mesh import load_mesh

from shared_data import data


def _scene():
    """A unit sphere (the skin), two small boxes, a small open square and a large box; (V, F, ranges)."""
    pieces = [trimesh.creation.icosphere(subdivisions=3),
              trimesh.creation.box(extents=(0.1, 0.1, 0.1)),
              trimesh.creation.box(extents=(0.15, 0.1, 0.05)),
              trimesh.Trimesh([[0, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0], [0, 0.1, 0]], [[0, 1, 2], [0, 2, 3]],
                              process=False),
              trimesh.creation.box(extents=(0.9, 0.9, 0.9))]
    V, F, ranges, n = [], [], [], 0
    for k, m in enumerate(pieces):
        V.append(np.asarray(m.vertices) + [0.0, 0.0, 0.3 * k if k else 0.0])
        F.append(np.asarray(m.faces) + n)
        ranges.append(np.arange(n, n + len(m.vertices)))
        n += len(m.vertices)
    return np.vstack(V), np.vstack(F), ranges


def test_closed_small_parts_are_the_small_boxes():
    V, F, ranges = _scene()
    found = closed_small_parts(V, F)
    # the sphere is the skin, the square is open, the large box is 0.9 / 2.1 of the extent
    assert sorted(r.tolist() for r in found) == [ranges[1].tolist(), ranges[2].tolist()]
    # unwelded (every triangle its own corners, as some exports write): welded first, the same parts
    Vu, Fu = V[F].reshape(-1, 3), np.arange(3 * len(F)).reshape(-1, 3)
    found_u = closed_small_parts(Vu, Fu)
    assert len(found_u) == 2
    assert {tuple(np.unique(np.round(Vu[r], 9), axis=0).ravel()) for r in found_u} == \
        {tuple(np.unique(np.round(V[r], 9), axis=0).ravel()) for r in ranges[1:3]}
    assert ranges[4].tolist() in [r.tolist() for r in closed_small_parts(V, F, small=0.5)]


def test_rigid_weights_one_row_per_part():
    V, F, ranges = _scene()
    rng = np.random.default_rng(0)
    W = rng.random((len(V), 4))
    W /= W.sum(axis=1, keepdims=True)
    out = rigid_weights(W, V, F, closed_small_parts(V, F), prune=0.0)
    for r in ranges[1:3]:
        assert np.ptp(out[r], axis=0).max() == 0.0
        a = vertex_areas(V, F)[r]   # the mean weighed by each corner's share of the area
        np.testing.assert_allclose(out[r[0]], (a[:, None] * W[r]).sum(axis=0) / a.sum(), atol=1e-12)
    rest = np.setdiff1d(np.arange(len(V)), np.concatenate(ranges[1:3]))
    np.testing.assert_array_equal(out[rest], W[rest])
    np.testing.assert_allclose(out.sum(axis=1), 1.0, atol=1e-12)
    assert not np.shares_memory(out, W)            # with parts: a new array, the input untouched
    assert rigid_weights(W, V, F, []) is W         # without: no copy (a head without teeth pays nothing)


def test_place_moves_ict_eyeballs_and_teeth_whole(rigs):
    """ICT's 32 teeth and 4 eyeball shells are closed and small: one weight row each (bone heat gave an
    eyeball's front and back 0.70-0.74 apart, a tooth's ends up to 0.54, at ``dense``); its lashes and
    mouth bag are open and keep the heat's weights."""
    V, F = load_mesh(data("ict/generic_neutral_mesh.obj"))
    rig = rigs("ict/generic_neutral_mesh.obj", "dense")
    parts = closed_small_parts(V, F)
    assert len(parts) == 36
    for rows in parts:
        assert np.ptp(rig.weights[rows], axis=0).max() == 0.0
    np.testing.assert_allclose(rig.weights.sum(axis=1), 1.0, atol=1e-9)
    label = mesh_parts(len(V), F)
    lashes = [p for p in np.unique(label) if p not in {label[r[0]] for r in parts} and (label == p).sum() < 300]
    assert any(np.ptp(rig.weights[label == p], axis=0).max() > 0.1 for p in lashes)
