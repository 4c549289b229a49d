"""Tests for autobones.render: coverage, depth, ids, lifting pixels back to 3-D."""
import numpy as np
import pytest
import trimesh

from autobones.errors import AutobonesError
from autobones.render import (
    Camera, RenderBuffers, draw_points, draw_segments, look_at, orthographic_camera,
    rasterize, render_views, save_png, shade, surface_points,
)

from shared_data import data

LPS = data("misc/LeePerrySmith.obj")


@pytest.fixture(scope="module")
def sphere():
    m = trimesh.creation.icosphere(subdivisions=5, radius=1.0)
    return np.asarray(m.vertices), np.asarray(m.faces)


@pytest.fixture(scope="module")
def lps():
    assert LPS.exists(), f"missing test mesh {LPS}: the shared data folder must sit beside the checkout"
    m = trimesh.load(LPS, process=False)
    return np.asarray(m.vertices), np.asarray(m.faces)


def _point_in_triangle(P, A, B, C):
    """Barycentrics (k, 3) of P in triangles ABC and distance of P to their planes."""
    e1, e2, d = B - A, C - A, P - A
    n = np.cross(e1, e2)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    dist = np.abs(np.einsum("kd,kd->k", d, n))
    d11, d12, d22 = (np.einsum("kd,kd->k", a, b) for a, b in ((e1, e1), (e1, e2), (e2, e2)))
    dp1, dp2 = np.einsum("kd,kd->k", d, e1), np.einsum("kd,kd->k", d, e2)
    den = d11 * d22 - d12 ** 2
    v = (d22 * dp1 - d12 * dp2) / den
    w = (d11 * dp2 - d12 * dp1) / den
    return np.stack([1 - v - w, v, w], axis=1), dist


# --------------------------------------------------------------------------- cameras

def test_look_at_maps_eye_to_origin_and_target_ahead():
    eye, target = np.array([1.0, 2.0, 3.0]), np.array([-2.0, 0.5, 1.0])
    M = look_at(eye, target, (0, 1, 0))
    assert np.allclose(M[:3, :3] @ M[:3, :3].T, np.eye(3))
    assert np.isclose(np.linalg.det(M[:3, :3]), 1.0)
    assert np.allclose((M @ np.r_[eye, 1])[:3], 0)
    assert np.allclose((M @ np.r_[target, 1])[:3], [0, 0, -np.linalg.norm(target - eye)])
    # world up appears as image up (+Y camera)
    assert (M[:3, :3] @ [0, 1, 0])[1] > 0


def test_look_at_rejects_up_parallel_to_view():
    with pytest.raises(AutobonesError):
        look_at((0, 5, 0), (0, 0, 0), (0, 1, 0))


def test_front_view_is_not_mirrored_or_upside_down():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0], [-1, -1, -1]])
    cam = orthographic_camera(V, (0, 0, 1), size=(100, 100))
    (o, x, y, z, _), depth = cam.project(V)
    assert x[0] > o[0] and np.isclose(x[1], o[1])   # +X (subject's left) -> image right
    assert y[1] < o[1] and np.isclose(y[0], o[0])   # +Y -> up = smaller row
    assert depth[3] < depth[0]                      # +Z is nearer the camera
    side = orthographic_camera(V, (1, 0, 0), size=(100, 100))
    (o, x, y, z, _), depth = side.project(V)
    assert z[0] < o[0]                              # from the left, the face (+Z) points left
    assert depth[1] < depth[0]


def test_camera_frames_points_with_margin_and_positive_depth(sphere):
    V, _ = sphere
    V = V * [2.0, 1.0, 1.0] + [5, -3, 7]
    cam = orthographic_camera(V, (0, 0, 1), size=(200, 100), margin=0.1)
    px, depth = cam.project(V)
    assert np.all(depth > 0)
    lo, hi = px.min(axis=0), px.max(axis=0)
    assert np.all(lo >= -1e-9) and hi[0] <= 199 + 1e-9 and hi[1] <= 99 + 1e-9
    # the limiting direction (height, span 2 over 100 px) uses 80% of the image
    assert np.isclose(hi[1] - lo[1], 80.0)
    assert np.allclose((lo + hi) / 2, [99.5, 49.5])


def test_ray_and_project_are_inverse():
    rng = np.random.default_rng(0)
    P = rng.normal(size=(50, 3))
    cam = orthographic_camera(P, (0.3, 0.5, 0.8), up=(0, 1, 0), size=(64, 48))
    px, depth = cam.project(P)
    o, d = cam.ray(px)
    assert np.allclose(np.linalg.norm(d, axis=1), 1)
    assert np.allclose(o + depth[:, None] * d, P)
    po, do = cam.project(o)
    assert np.allclose(po, px) and np.allclose(do, 0)


# --------------------------------------------------------------------------- rasterize

def test_sphere_covers_disk_area(sphere):
    V, F = sphere
    cam = orthographic_camera(V, (0, 0, 1), size=(301, 301))
    buf = rasterize(V, F, cam)
    expected = np.pi * cam.scale ** 2          # radius 1 in pixels = scale
    assert abs(buf.mask.sum() / expected - 1) < 0.01


def test_cube_covers_square_area():
    m = trimesh.creation.box(extents=(1, 1, 1))
    cam = orthographic_camera(m.vertices, (0, 0, 1), size=(200, 200), margin=0.1)
    buf = rasterize(m.vertices, m.faces, cam)
    side = cam.scale * 1.0
    assert abs(buf.mask.sum() / side ** 2 - 1) < 0.03
    # a rotated view of the cube (three faces) covers a hexagon of known area
    d = np.array([1.0, 1.0, 1.0])
    cam = orthographic_camera(m.vertices, d, size=(200, 200))
    buf = rasterize(m.vertices, m.faces, cam)
    hexagon = np.sqrt(3) * cam.scale ** 2    # projection of a unit cube along a diagonal
    assert abs(buf.mask.sum() / hexagon - 1) < 0.03


def test_sphere_depth_matches_analytic(sphere):
    V, F = sphere
    cam = orthographic_camera(V, (0, 0, 1), size=(101, 101))
    buf = rasterize(V, F, cam)
    _, d0 = cam.project(np.zeros((1, 3)))
    assert abs(buf.depth[50, 50] - (d0[0] - 1.0)) < 2e-3
    # everywhere inside the disk: depth = d0 - sqrt(1 - rho^2)
    rows, cols = np.mgrid[0:101, 0:101]
    rho = np.hypot(cols - 50, rows - 50) / cam.scale
    inner = rho < 0.9
    assert np.all(buf.mask[inner])
    assert np.abs(buf.depth[inner] - (d0[0] - np.sqrt(1 - rho[inner] ** 2))).max() < 5e-3
    assert np.all(np.isinf(buf.depth[~buf.mask]))
    assert np.all(buf.face_id[~buf.mask] == -1)


def test_face_id_contains_the_ray_hit(sphere):
    V, F = sphere
    cam = orthographic_camera(V, (0.2, 0.1, 1), size=(81, 81))
    buf = rasterize(V, F, cam)
    rows, cols = np.nonzero(buf.mask)
    o, d = cam.ray(np.stack([cols, rows], axis=1))
    hit = o + buf.depth[rows, cols][:, None] * d
    tri = F[buf.face_id[rows, cols]]
    b, dist = _point_in_triangle(hit, V[tri[:, 0]], V[tri[:, 1]], V[tri[:, 2]])
    assert dist.max() < 1e-9
    assert b.min() > -1e-6
    assert np.allclose(b, buf.bary[rows, cols], atol=1e-6)
    # and the centre pixel's triangle faces the camera (front surface, not the back)
    f = buf.face_id[40, 40]
    n = np.cross(V[F[f, 1]] - V[F[f, 0]], V[F[f, 2]] - V[F[f, 0]])
    assert n @ cam.direction < 0


def test_surface_points_reproject_and_lie_on_rays(lps):
    V, F = lps
    cam = orthographic_camera(V, (0.5, 0.2, 1.0), size=(160, 200))
    buf = rasterize(V, F, cam)
    P = surface_points(V, F, buf)
    m = buf.mask
    assert m.sum() > 0.2 * m.size
    assert np.all(np.isnan(P[~m])) and np.all(np.isfinite(P[m]))
    rows, cols = np.nonzero(m)
    px, depth = cam.project(P[m])
    assert np.abs(px - np.stack([cols, rows], axis=1)).max() < 0.5
    assert np.allclose(depth, buf.depth[m])
    o, d = cam.ray(np.stack([cols, rows], axis=1))
    assert np.allclose(o + buf.depth[m][:, None] * d, P[m], atol=1e-9)


def test_nearer_surface_wins_whatever_the_order():
    quad = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0.0]])
    V = np.vstack([quad, quad * [0.5, 0.5, 1] + [0, 0, 1]])   # small square in front
    F = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    cam = orthographic_camera(V, (0, 0, 1), size=(41, 41))
    for order in (F, F[::-1]):
        buf = rasterize(V, order, cam)
        ids = np.asarray(order)[buf.face_id[20, 20]]
        assert set(ids) <= {4, 5, 6, 7}
        assert set(np.asarray(order)[buf.face_id[2, 2]]) <= {0, 1, 2, 3}


def test_shared_edges_leave_no_gaps():
    # a square split along its diagonal, pixel centres lying exactly on the
    # diagonal and on the outer edges: every pixel inside must be covered
    quad = np.array([[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0.0]])
    F = np.array([[0, 1, 2], [0, 2, 3]])
    cam = Camera(view=look_at((5, 5, 5), (5, 5, 0), (0, 1, 0)), scale=1.0,
                 center=np.zeros(2), width=11, height=11)
    buf = rasterize(quad, F, cam)
    assert buf.mask.all()
    # a fan of thin triangles around a centre: all covered, none twice wrong
    k = 37
    ang = np.linspace(0, 2 * np.pi, k, endpoint=False)
    V = np.vstack([[0, 0, 0], np.stack([np.cos(ang), np.sin(ang), 0 * ang], 1)])
    F = np.stack([np.zeros(k, int), 1 + np.arange(k), 1 + (np.arange(k) + 1) % k], 1)
    cam = orthographic_camera(V, (0, 0, 1), size=(121, 121), margin=0.0)
    buf = rasterize(V, F, cam)
    rows, cols = np.mgrid[0:121, 0:121]
    rho = np.hypot(cols - 60, rows - 60) / cam.scale
    assert buf.mask[rho < 0.98 * np.cos(np.pi / k)].all()


def test_degenerate_empty_and_disconnected_meshes():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 2, 0], [np.nan, 0, 0], [1, 1, 0]])
    F = np.array([[0, 1, 2], [0, 0, 1], [0, 5, 3], [1, 3, 4]])  # ok, repeated, collinear, nan
    cam = orthographic_camera(V[:4], (0, 0, 1), size=(30, 30))
    buf = rasterize(V, F, cam)
    assert set(np.unique(buf.face_id)) == {-1, 0}
    img = shade(V, F, buf)
    assert img.shape == (30, 30, 3) and img.dtype == np.uint8
    # no faces
    buf = rasterize(V, np.zeros((0, 3), int), cam)
    assert not buf.mask.any() and np.isinf(buf.depth).all()
    assert (shade(V, np.zeros((0, 3), int), buf) == 255).all()
    assert np.isnan(surface_points(V, np.zeros((0, 3), int), buf)).all()
    # mesh entirely outside the image
    far = rasterize(V[:3] + 100, F[:1], cam)
    assert not far.mask.any()
    # many disconnected parts
    parts = [trimesh.creation.icosphere(1, radius=0.1).apply_translation([i % 10, i // 10, 0])
             for i in range(100)]
    m = trimesh.util.concatenate(parts)
    cam = orthographic_camera(m.vertices, (0, 0, 1), size=(200, 200))
    buf = rasterize(m.vertices, m.faces, cam)
    part_of_face = np.repeat(np.arange(100), len(parts[0].faces))
    assert len(np.unique(part_of_face[buf.face_id[buf.mask]])) == 100


def test_bad_input_raises():
    cam = Camera(view=np.eye(4), scale=1.0, center=np.zeros(2), width=4, height=4)
    with pytest.raises(AutobonesError):
        rasterize(np.zeros((3, 2)), [[0, 1, 2]], cam)
    with pytest.raises(AutobonesError):
        rasterize(np.zeros((3, 3)), [[0, 1, 3]], cam)
    with pytest.raises(AutobonesError):
        orthographic_camera(np.zeros((3, 3)), (0, 0, 1), size=(0, 10))


# --------------------------------------------------------------------------- shading

def test_vertex_colors_show_up(sphere):
    V, F = sphere
    C = np.where(V[:, :1] > 0, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])  # +X blue, -X red
    cam = orthographic_camera(V, (0, 0, 1), size=(64, 64))
    buf = rasterize(V, F, cam)
    img = shade(V, F, buf, vertex_colors=C).astype(int)
    right, left = img[32, 45], img[32, 18]       # +X is image right in a front view
    assert right[2] > 100 and right[0] < 10 and right[1] < 10
    assert left[0] > 100 and left[2] < 10 and left[1] < 10
    assert (img[0, 0] == 255).all()              # white background
    grey = shade(V, F, buf)
    assert np.all(grey[buf.mask][:, 0] == grey[buf.mask][:, 2])


def test_shading_is_lambert_and_two_sided(sphere):
    V, F = sphere
    cam = orthographic_camera(V, (0, 0, 1), size=(101, 101))
    buf = rasterize(V, F, cam)
    img = shade(V, F, buf, vertex_colors=np.ones((len(V), 3)), light_dir=(0, 0, 1), ambient=0.2)
    assert img[50, 50, 0] >= 253                 # facing the light
    edge = img[50, 50 + int(0.97 * cam.scale), 0]
    assert edge < 0.45 * 255                     # nearly edge-on: close to ambient
    flipped = shade(V, F[:, ::-1], rasterize(V, F[:, ::-1], cam),
                    vertex_colors=np.ones((len(V), 3)), light_dir=(0, 0, 1), ambient=0.2)
    assert np.abs(flipped.astype(int) - img).max() <= 1
    back = shade(V, F, buf, vertex_colors=np.ones((len(V), 3)), light_dir=(0, 0, -1), ambient=0.2)
    assert np.abs(back.astype(int) - img).max() <= 1


# --------------------------------------------------------------------------- 2-D and views

def test_draw_points_and_segments():
    img = np.full((50, 60, 3), 255, np.uint8)
    out = draw_points(img, [[10, 20], [np.nan, 3]], labels=["a", "b"], color=(255, 0, 0))
    assert (img == 255).all()                    # input untouched
    assert tuple(out[20, 10]) == (255, 0, 0)     # x = column, y = row
    out = draw_segments(out, [[0, 40]], [[59, 40]], color=(0, 0, 255), width=1)
    assert tuple(out[40, 30]) == (0, 0, 255)


def test_render_views_and_png(lps, tmp_path):
    V, F = lps
    img = render_views(V, F, views=("front", "side", "three_quarter"), size=(96, 128),
                       points=[[0, 0, 3.0]], point_labels=["nose tip"],
                       segments=[[[0, 0, 0], [0, 3, 0]]])
    assert img.shape == (128, 288, 3) and img.dtype == np.uint8
    front = img[:, :96]
    # the head is roughly left-right symmetric in the front view
    cover = (front < 250).any(axis=2)
    cols = np.nonzero(cover)[1]
    assert abs(cols.mean() - 47.5) < 3
    path = tmp_path / "views.png"
    save_png(path, img)
    from PIL import Image
    assert np.array_equal(np.asarray(Image.open(path)), img)
    with pytest.raises(AutobonesError):
        save_png(tmp_path / "x.png", img.astype(float))


def test_large_mesh_renders():
    a = trimesh.creation.icosphere(subdivisions=6)                     # 81920 faces
    b = trimesh.creation.icosphere(subdivisions=5, radius=0.5).apply_translation([1.2, 0, 0.5])
    m = trimesh.util.concatenate([a, b])
    assert len(m.faces) >= 100_000
    cam = orthographic_camera(m.vertices, (0, 0, 1), size=(800, 800))
    buf = rasterize(m.vertices, m.faces, cam)
    assert isinstance(buf, RenderBuffers)
    img = shade(m.vertices, m.faces, buf)
    assert img.shape == (800, 800, 3)
    assert buf.mask.sum() > 0.3 * 800 * 800


def test_unit_vector_keeps_the_direction_and_refuses_non_vectors():
    from autobones.render.camera import unit_vector

    v = unit_vector([3.0, -4.0, 12.0], "v")
    assert np.isclose(np.linalg.norm(v), 1.0) and np.allclose(v * 13.0, [3.0, -4.0, 12.0])
    for bad in ([0, 0, 0], [1, np.nan, 0], [1, 2]):
        with pytest.raises(AutobonesError, match="v must"):
            unit_vector(bad, "v")


def test_image_size_takes_a_pair_of_positive_ints():
    from autobones.render.camera import image_size

    assert image_size((64.0, 32)) == (64, 32)
    for bad in ((0, 4), (4,), "ab", None):
        with pytest.raises(AutobonesError, match="image size"):
            image_size(bad)


def test_batch_size_does_not_change_the_depth_buffer(sphere, monkeypatch):
    """Rasterising in many small batches covers the same pixels at the same depths as in one."""
    import importlib

    raster = importlib.import_module("autobones.render.raster")
    V, F = sphere
    cam = orthographic_camera(V, (0.3, 0.2, 1.0), size=(96, 80))
    whole = rasterize(V, F, cam)
    monkeypatch.setattr(raster, "_BATCH", 257)
    pieces = rasterize(V, F, cam)
    assert np.array_equal(whole.mask, pieces.mask) and np.array_equal(whole.depth, pieces.depth)
