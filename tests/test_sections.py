"""autobones.geometry.sections: points along a mesh's sections by parallel planes."""
import numpy as np
import trimesh

from autobones.geometry.sections import section_points


def test_a_box_section_is_its_outline_sampled_at_the_spacing():
    box = trimesh.creation.box(extents=(2.0, 1.0, 3.0))
    P = section_points(box.vertices, box.faces, 0, [0.25], 0.01)
    assert np.abs(P[:, 0] - 0.25).max() < 1e-12                        # on the plane
    on_edge = np.isclose(np.abs(P[:, 1]), 0.5) | np.isclose(np.abs(P[:, 2]), 1.5)
    assert on_edge.all()                                              # on the box's outline
    assert np.abs(P[:, 1]).max() <= 0.5 + 1e-12 and np.abs(P[:, 2]).max() <= 1.5 + 1e-12
    # the outline is covered: every 1% of its perimeter (8 units) has a point within the spacing
    t = np.linspace(0, 1, 801)[:-1]
    corners = np.array([[0.5, 1.5], [-0.5, 1.5], [-0.5, -1.5], [0.5, -1.5], [0.5, 1.5]])
    length = np.r_[0, np.cumsum(np.linalg.norm(np.diff(corners, axis=0), axis=1))]
    s = t * length[-1]
    Q = np.stack([np.interp(s, length, corners[:, k]) for k in range(2)], axis=1)
    gap = np.linalg.norm(Q[:, None] - P[None, :, 1:], axis=2).min(axis=1)
    assert gap.max() <= 0.005 + 1e-9


def test_the_same_surface_split_1_to_4_has_the_same_sections():
    """The profile a chin is read from must follow the surface, not its tessellation: the front-most point
    of every 1% height bin of a section agrees on a capsule and on it split 1-to-4 (the same surface)."""
    cap = trimesh.creation.capsule(height=1.0, radius=0.4, count=(9, 9))
    V, F = cap.vertices, cap.faces
    Vs, Fs = trimesh.remesh.subdivide(V, F)
    planes = np.linspace(-0.03, 0.03, 5)
    fronts = []
    for P in (section_points(V, F, 0, planes, 0.0025), section_points(Vs, Fs, 0, planes, 0.0025)):
        k = np.floor((P[:, 2] + 1.0) / 0.01).astype(int)
        front = np.full(k.max() + 2, -np.inf)
        np.maximum.at(front, k, P[:, 1])
        fronts.append(front)
    n = min(len(fronts[0]), len(fronts[1]))
    a, b = fronts[0][:n], fronts[1][:n]
    both = np.isfinite(a) & np.isfinite(b)
    assert both.sum() > 50
    assert np.abs(a[both] - b[both]).max() < 2e-3
    assert (np.isfinite(a) == np.isfinite(b)).mean() > 0.95


def test_no_plane_through_the_mesh_gives_no_points():
    box = trimesh.creation.box()
    assert section_points(box.vertices, box.faces, 0, [5.0], 0.01).shape == (0, 3)
    assert section_points(box.vertices, np.empty((0, 3), int), 0, [0.0], 0.01).shape == (0, 3)
