"""autobones.geometry: the shared layer, one operation at a time, on tiny meshes and a real head."""
import numpy as np
import pytest
import scipy.sparse as sp

from autobones.errors import AutobonesError
from autobones.geometry import laplacian as lap
from autobones.geometry.areas import triangle_areas, vertex_areas
from autobones.geometry.normals import triangle_normals, vertex_normals
from autobones.geometry.rotations import polar_rotations, rotate_between, similarity
from autobones.geometry.spatial_order import spatial_order
from autobones.geometry.smooth import ramp, smoothstep, step
from autobones.geometry.topology import (boundary_vertices, largest_part, mesh_edges, mesh_parts, part_areas, submesh, weld,
                                         weld_by_size, without_large_parts)
from autobones.geometry.validate import mesh_arrays
from autobones.io.mesh import load_mesh
from shared_data import data, icosphere


@pytest.fixture(scope="module")
def ict():
    return load_mesh(data("ict/generic_neutral_mesh.obj"))


def test_normals_point_out_of_a_sphere_and_faces_have_twice_their_area():
    V, F = icosphere(3)
    N = vertex_normals(V, F)
    assert np.allclose(np.linalg.norm(N, axis=1), 1.0)
    assert (np.einsum("ij,ij->i", N, V) > 0.99).all()
    assert np.allclose(np.linalg.norm(triangle_normals(V, F), axis=1), 2.0 * triangle_areas(V, F))


def test_normals_of_unused_and_degenerate_vertices_are_zero():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5], [2, 0, 0]], float)
    F = np.array([[0, 1, 2], [0, 1, 4]])          # the second is degenerate (collinear)
    N = vertex_normals(V, F)
    assert np.allclose(N[:3], [0, 0, 1]) and not N[3].any() and not N[4].any()


def test_vertex_areas_sum_to_the_surface_area(ict):
    V, F = ict
    A = vertex_areas(V, F)
    assert A.shape == (len(V),) and (A >= 0).all()
    assert np.isclose(A.sum(), triangle_areas(V, F).sum(), rtol=1e-12)


def test_parts_edges_and_boundary_of_two_open_triangles_and_a_sphere():
    V, F = icosphere(1)
    assert len(mesh_edges(F)) == 3 * len(F) // 2                       # closed: each edge in two faces
    assert not boundary_vertices(len(V), F).any()
    F2 = np.array([[0, 1, 2], [3, 4, 5]])
    assert list(mesh_parts(7, F2)) == [0, 0, 0, 1, 1, 1, 2]             # vertex 6 alone: its own part
    assert boundary_vertices(6, F2).all()


def test_largest_part_is_a_mesh_of_its_own():
    # a 2-triangle quad (4 vertices) beside a lone triangle (3), listed first
    V = np.array([[9, 9, 9], [9, 8, 9], [8, 9, 9], [0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    F = np.array([[0, 1, 2], [3, 4, 5], [3, 5, 6]])
    Vs, Fs, index = largest_part(V, F)
    np.testing.assert_array_equal(index, [3, 4, 5, 6])
    np.testing.assert_array_equal(Vs, V[3:])
    np.testing.assert_array_equal(Vs[Fs], V[F[1:]])


def test_submesh_keeps_the_triangles_whose_corners_it_keeps():
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [5, 5, 5]], dtype=float)
    F = np.array([[0, 1, 2], [0, 2, 3], [2, 3, 4]])
    Vs, Fs = submesh(V, F, np.array([0, 1, 2, 3]))
    np.testing.assert_array_equal(Vs, V[:4])
    np.testing.assert_array_equal(Fs, F[:2])   # the triangle on vertex 4 goes with it
    Vs, Fs = submesh(V, F, np.array([0, 2, 3]))
    np.testing.assert_array_equal(Vs[Fs], V[F[1:2]])


def test_part_areas_and_large_parts_go_by_area_not_by_vertex_count():
    # a big triangle (3 vertices, area 50) beside a small fan of 4 triangles (6 vertices, area 2)
    V = np.array([[0, 0, 5], [10, 0, 5], [0, 10, 5], [0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [-1, 0, 0],
                  [0, -1, 0]], dtype=float)
    F = np.array([[0, 1, 2], [3, 4, 5], [3, 5, 6], [3, 6, 7], [3, 7, 8]])
    part, area = part_areas(V, F)
    assert part[0] == part[1] == part[2] != part[3]
    np.testing.assert_allclose(sorted(area), [2.0, 50.0])
    assert largest_part(V, F)[2].tolist() == [3, 4, 5, 6, 7, 8]          # the most vertices: the fan
    # a 10 x 10 square (area 100), a long sliver across it (10 x 1: area 5, spread over the mesh) and
    # a lump inside (2 x 4: area 4, near the centre): from 3 % up only the sliver is a large part
    sq = np.array([[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0]], float)
    sliver = np.array([[0, 0, 5], [10, 10, 5], [0, 1.414, 5]], float)
    lump = np.array([[4, 4, 1], [6, 4, 1], [4, 8, 1]], float)
    V3 = np.vstack([sq, sliver, lump])
    F3 = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [7, 8, 9]])
    np.testing.assert_array_equal(without_large_parts(V3, F3, share=0.03), F3[[0, 1, 3]])
    assert without_large_parts(V3, F3) is F3                              # none covers 10 %
    # a second part as wide as the first leaves no clear main part: nothing dropped
    V2 = np.vstack([V[:3], V[:3] + [0, 0, 20.0]])
    np.testing.assert_array_equal(without_large_parts(V2, np.array([[0, 1, 2], [3, 4, 5]]), share=0.03),
                                  [[0, 1, 2], [3, 4, 5]])
    # a ball (radius 0.3: area 9 % of the unit sphere's) is a lump, not spread: kept inside the sphere
    # (a mouth), left out set on its top (a hat: mostly outside the sphere's convex hull)
    Vs, Fs = icosphere(2)
    for centre, kept in (([0, 0, 0.2], True), ([0, 0, 1.1], False)):
        Vb = np.vstack([Vs, 0.3 * Vs + centre])
        Fb = np.vstack([Fs, Fs + len(Vs)])
        np.testing.assert_array_equal(without_large_parts(Vb, Fb, share=0.03), Fb if kept else Fs)


def test_weld_by_size_welds_alike_in_any_unit():
    V, F = icosphere(1)
    Vd = np.vstack([V, V[:3] + 1e-9])                                     # three copies a hair apart
    Fd = np.vstack([F, [[len(V), len(V) + 1, len(V) + 2]]])
    for scale in (1e-3, 1.0, 1e3):
        Vw, Fw, index = weld_by_size(scale * Vd, Fd)
        assert len(Vw) == len(V) and (index[len(V):] == index[:3]).all()


def test_weld_merges_copies_and_drops_collapsed_faces():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1e-9, 0, 0], [1, 1e-9, 0], [0, 0, 1]], float)
    F = np.array([[0, 1, 2], [3, 4, 5], [0, 3, 1]])                     # the last collapses
    Vw, Fw, index = weld(V, F, 1e-6)
    assert len(Vw) == 4 and len(Fw) == 2 and index[0] == index[3] and index[1] == index[4]


def test_spatial_order_is_the_same_for_the_points_in_any_order_and_keeps_neighbours_near():
    X = np.random.default_rng(0).random((4000, 3)) * [2.0, 1.0, 0.5]
    p = np.random.default_rng(1).permutation(len(X))
    np.testing.assert_array_equal(X[spatial_order(X)], X[p][spatial_order(X[p])])
    step = np.linalg.norm(np.diff(X[spatial_order(X)], axis=0), axis=1)
    assert np.median(step) < 0.2 * np.median(np.linalg.norm(np.diff(X, axis=0), axis=1))  # file order: random
    assert len(spatial_order(np.zeros((0, 3)))) == 0 and spatial_order(np.ones((3, 3))).tolist() == [0, 1, 2]
    # a seam's two copies of one vertex: told apart by the weight they carry, in either order
    assert spatial_order(np.ones((2, 3)), tie=[2.0, 1.0]).tolist() == [1, 0]
    assert spatial_order(np.ones((2, 3)), tie=[1.0, 2.0]).tolist() == [0, 1]


def test_ict_has_many_parts_and_the_skin_is_the_largest(ict):
    V, F = ict
    parts = mesh_parts(len(V), F)
    sizes = np.bincount(parts)
    assert len(sizes) > 10 and sizes.max() > 0.5 * len(V)


def test_factor_spd_solves_and_agrees_with_colamd(ict):
    V, F = ict
    L, M = lap.laplacian(V, F)
    A = (M + 1e-2 * L).tocsc()
    b = np.random.default_rng(0).standard_normal((len(V), 3))
    x = lap.factor_spd(A, use_cholmod=False)(b)
    assert np.abs(A @ x - b).max() < 1e-9 * np.abs(b).max()
    x_mmd = lap.factor_spd(A, ordering="mmd_symmetric", use_cholmod=False)(b)
    assert np.abs(x - x_mmd).max() < 1e-10 * np.abs(x).max()
    assert lap.factor_spd(A, use_cholmod=False)(b[:, 0]).shape == (len(V),)


def test_factor_spd_uses_cholmod_when_it_is_installed_and_superlu_otherwise(ict):
    V, F = ict
    L, M = lap.laplacian(V, F)
    A = (M + 1e-2 * L).tocsc()
    b = np.random.default_rng(1).standard_normal(len(V))
    solve = lap.factor_spd(A)
    # the default install has no scikit-sparse: SuperLU's solve; with the [cholmod] extra, CHOLMOD's factor
    assert (lap._cholmod is not None) == ("cholmod" in type(getattr(solve, "__self__", solve)).__module__)
    x, x_lu = solve(b), lap.factor_spd(A, use_cholmod=False)(b)
    assert np.abs(x - x_lu).max() < 1e-10 * np.abs(x).max()


def test_clipped_cotangent_laplacian_is_the_cotangent_one_where_no_weight_is_negative_and_an_m_matrix_everywhere(ict):
    import igl

    V, F = icosphere(2)                                     # acute triangles only: nothing to clip
    L = lap.clipped_cotangent_laplacian(V, F)
    assert np.abs((L + igl.cotmatrix(V, F)).toarray()).max() < 1e-12
    V, F = ict                                              # a real head: obtuse and degenerate triangles
    F = np.vstack([F, [[F[0, 0], F[0, 0], F[0, 1]]]])       # plus a zero-area one
    L = lap.clipped_cotangent_laplacian(V, F)
    off = (L - sp.diags(L.diagonal())).tocoo()
    assert np.isfinite(L.data).all() and abs(L - L.T).max() < 1e-12
    E = mesh_edges(F)
    assert (off.data < 0).all() and off.nnz == 2 * (E[:, 0] != E[:, 1]).sum()   # every edge keeps a weight
    assert np.abs(np.asarray(L.sum(axis=1))).max() < 1e-9 * L.diagonal().max()
    C = -igl.cotmatrix(V, F[:-1]).tocoo()
    assert (C.data[C.row != C.col] > 0).any()               # the plain one is no M-matrix on this head


def test_diffusion_keeps_the_mass_weighted_total_and_smooths(ict):
    V, F = ict
    L, M = lap.laplacian(V, F)
    u = (V[:, 1] > np.median(V[:, 1])).astype(float)
    v = lap.diffuse(u, L, M, t=(0.02 * np.ptp(V[:, 1])) ** 2)
    assert np.isclose((M @ v).sum(), (M @ u).sum(), rtol=1e-8)        # heat is conserved
    assert v.min() > -1e-9 and v.max() < 1 + 1e-9                        # maximum principle
    E = mesh_edges(F)
    assert np.abs(v[E[:, 0]] - v[E[:, 1]]).sum() < np.abs(u[E[:, 0]] - u[E[:, 1]]).sum()


def test_smooth_steps_are_monotone_c1_and_hit_their_ends():
    t = np.linspace(-0.5, 1.5, 2001)
    s = smoothstep(t)
    assert s[0] == 0 and s[-1] == 1 and (np.diff(s) >= 0).all()
    assert np.abs(np.diff(s, 2)).max() < 1e-5                             # no kink
    assert ramp(2.0, 2.0, 4.0) == 0 and ramp(4.0, 2.0, 4.0) == 1 and ramp(3.0, 4.0, 2.0) == 0.5
    assert step(0.0, 0.0, 2.0) == 0.5 and step(-1.0, 0.0, 2.0) == 0 and step(1.0, 0.0, 2.0) == 1


def test_similarity_recovers_a_scaled_turned_point_set_and_never_mirrors():
    rng = np.random.default_rng(3)
    P = rng.standard_normal((20, 3))
    R0 = np.linalg.qr(rng.standard_normal((3, 3)))[0]
    R0 *= np.sign(np.linalg.det(R0))
    Q = 2.5 * P @ R0.T + [1.0, -2.0, 3.0]
    s, R = similarity(P, Q)
    assert abs(s - 2.5) < 1e-12 and np.abs(R - R0).max() < 1e-12
    s, R = similarity(P, P * [-1.0, 1.0, 1.0])        # a mirror image: the best proper rotation
    assert np.linalg.det(R) > 0


def test_weighted_similarity_follows_the_weighted_points():
    # points weighted 0 (a smile's mouth corners) do not pull the map; the centre is the weighted mean
    rng = np.random.default_rng(5)
    P = rng.standard_normal((12, 3))
    R0 = np.linalg.qr(rng.standard_normal((3, 3)))[0]
    R0 *= np.sign(np.linalg.det(R0))
    Q = 0.7 * P @ R0.T + [4.0, 0.0, -1.0]
    Q[:3] += rng.standard_normal((3, 3))                 # three points moved off the map
    w = np.r_[np.zeros(3), rng.uniform(0.5, 2.0, 9)]
    s, R = similarity(P, Q, w)
    assert abs(s - 0.7) < 1e-12 and np.abs(R - R0).max() < 1e-12
    p0, q0 = np.average(P, axis=0, weights=w), np.average(Q, axis=0, weights=w)
    np.testing.assert_allclose(q0 + s * (P[3:] - p0) @ R.T, Q[3:], atol=1e-12)
    s1, R1 = similarity(P, Q)                            # unweighted: the moved points pull it off
    assert abs(s1 - 0.7) > 1e-3
    s2, R2 = similarity(P, Q, np.ones(12) * 3.0)         # equal weights: the unweighted map
    assert abs(s2 - s1) < 1e-12 and np.abs(R2 - R1).max() < 1e-12


def test_polar_rotations_are_the_nearest_proper_rotations():
    rng = np.random.default_rng(4)
    R0 = np.linalg.qr(rng.standard_normal((50, 3, 3)))[0]
    R0 *= np.sign(np.linalg.det(R0))[:, None, None]
    S = np.einsum("kij,kj->kij", np.eye(3)[None].repeat(50, 0), rng.uniform(0.5, 2.0, (50, 3)))
    R = polar_rotations(R0 @ S)                       # a rotation times a stretch: the rotation
    assert np.abs(R - R0).max() < 1e-12
    mirrored = R0 * np.array([1.0, 1.0, -1.0])        # det -1: a proper rotation, no nearer one
    Rm = polar_rotations(mirrored)
    assert np.allclose(np.linalg.det(Rm), 1.0) and np.allclose(Rm @ Rm.transpose(0, 2, 1), np.eye(3))
    closest = np.linalg.norm(Rm - mirrored, axis=(1, 2))
    for turn in (np.diag([-1.0, 1.0, 1.0]), np.diag([1.0, -1.0, 1.0])):  # other proper candidates
        assert (closest <= np.linalg.norm(mirrored @ turn - mirrored, axis=(1, 2)) + 1e-12).all()


def test_rotate_between_takes_a_to_b_and_keeps_lengths():
    rng = np.random.default_rng(2)
    a = rng.standard_normal((50, 3)); a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = rng.standard_normal((50, 3)); b /= np.linalg.norm(b, axis=1, keepdims=True)
    v = rng.standard_normal((50, 3))
    assert np.allclose(rotate_between(a, b, a), b)
    assert np.allclose(np.linalg.norm(rotate_between(a, b, v), axis=1), np.linalg.norm(v, axis=1))


@pytest.mark.parametrize("V, F, words", [
    (np.zeros((3, 2)), [[0, 1, 2]], "shape"),
    (np.zeros((3, 3)), [[0, 1, 3]], "out of range"),
    (np.full((3, 3), np.nan), [[0, 1, 2]], "NaN"),
    (np.zeros((3, 3)), [[0, 1.5, 2]], "integer"),
    (np.zeros((3, 3)), np.zeros((0, 3), int), "shape"),
])
def test_mesh_arrays_refuse_bad_arrays_with_one_message(V, F, words):
    with pytest.raises(AutobonesError, match=words):
        mesh_arrays(V, F, "head")
    if words == "shape" and len(np.asarray(F)) == 0:
        assert mesh_arrays(V, F, allow_no_faces=True)[1].shape == (0, 3)


def test_closest_points_for_a_few_points_search_only_the_triangles_near_them():
    """Few queries on a large mesh take the near-triangle path; the answer is the full search's."""
    import autobones.geometry.closest as closest

    V, F = icosphere(5)
    rng = np.random.default_rng(1)
    P = rng.normal(size=(12, 3))
    P *= rng.uniform(0.8, 1.2, (12, 1)) / np.linalg.norm(P, axis=1, keepdims=True)  # near the unit sphere
    C, face, bary, d2 = closest.closest_points(P, V, F)
    assert 12 * closest.FEW < len(F)  # the near path ran
    near = closest.near_faces(P, V, F)
    assert len(near) < len(F) and np.isin(face, near).all()
    Cf, _, _, d2f = closest._closest(P, V, F)
    np.testing.assert_allclose(d2, d2f, rtol=0, atol=1e-12)
    np.testing.assert_allclose(C, Cf, rtol=0, atol=1e-12)
    np.testing.assert_allclose((bary[:, :, None] * V[F[face]]).sum(axis=1), C, atol=1e-12)


def test_mirror_plane_is_found_from_the_sample_itself_in_any_frame():
    """geometry.mirror_plane: on a mirror-symmetric point set turned at random, one of the shape starts
    lies within 10 deg of the true plane, and the reflective ICP from it lands on the plane (normal to
    1e-6 rad, mirror error ~0); the starts turn with the points."""
    from scipy.spatial import cKDTree
    from scipy.spatial.transform import Rotation

    from autobones.geometry.mirror_plane import mirror_error, refine_plane, shape_starts

    rng = np.random.default_rng(3)
    half = rng.normal(size=(600, 3)) * [0.5, 1.0, 0.7] + [0.6, 0.0, 0.0]
    P = np.vstack([half, half * [-1, 1, 1]])  # mirrored in x = 0
    Q = Rotation.from_euler("xyz", [37, -52, 71], degrees=True).as_matrix()
    for R in (np.eye(3), Q):
        X = P @ R.T + [3.0, -2.0, 1.0]
        tree = cKDTree(X)
        true_n = R @ np.array([1.0, 0.0, 0.0])
        starts = shape_starts(X, tree)
        assert max(abs(s @ true_n) for s in starts) > np.cos(np.radians(10))
        best = min((refine_plane(X, tree, s, X.mean(axis=0) @ s, 1.0) for s in starts),
                   key=lambda nd: mirror_error(X, tree, *nd))
        assert abs(best[0] @ true_n) > 1 - 1e-9
        assert mirror_error(X, tree, *best) < 1e-9


def test_onto_plane_moves_points_along_the_normal_onto_the_plane():
    """geometry.mirror_plane.onto_plane: each point lands on the plane, moved along its normal by its
    signed distance (a point on the plane stays), and halfway to its mirror image."""
    from autobones.geometry.mirror_plane import onto_plane, reflect

    rng = np.random.default_rng(5)
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    P = rng.normal(size=(50, 3)) * 3.0
    Q = onto_plane(P, n, 0.7)
    np.testing.assert_allclose(Q @ n, 0.7, atol=1e-12)
    np.testing.assert_allclose(np.cross(P - Q, n), 0.0, atol=1e-12)
    np.testing.assert_allclose(Q, 0.5 * (P + reflect(P, n, 0.7)), atol=1e-12)
    np.testing.assert_array_equal(onto_plane(Q[0], n, 0.7).shape, (3,))
