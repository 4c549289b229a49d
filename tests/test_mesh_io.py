"""autobones.io.mesh: vertex order kept, polygons fanned, bad files refused with one clear error."""
import numpy as np
import pytest
import trimesh

from autobones.errors import AutobonesError
from autobones.io.mesh import load_mesh

from shared_data import data


def _obj_vertices(path):
    return np.array([[float(t) for t in line.split()[1:4]]
                     for line in open(path) if line.startswith("v ")])


def test_obj_keeps_every_vertex_in_file_order_despite_uv_seams():
    path = data("ict/generic_neutral_mesh.obj")
    V, F = load_mesh(path)
    assert V.shape == (26719, 3)
    np.testing.assert_array_equal(V, _obj_vertices(path))
    # trimesh's default loader would split at UV seams: we must not
    assert len(trimesh.load(path, force="mesh").vertices) != len(V)
    assert F.shape == (52220, 3)


def test_quads_are_fanned_into_triangles(tmp_path):
    p = tmp_path / "quad.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n"
                 "f 1/1/1 2/2/2 3/3/3 4/4/4\nf 1 2 5\nf -1 -2 -3\nf 1 4 5\n")
    V, F = load_mesh(p)
    assert F.tolist() == [[0, 1, 2], [0, 2, 3], [0, 1, 4], [4, 3, 2], [0, 3, 4]]


def test_ply_keeps_vertex_order():
    V, F = load_mesh(data("menpo3d/template.ply"))
    assert V.shape == (53349, 3) and F.shape == (106111, 3)


@pytest.mark.parametrize("ext", [".ply", ".off", ".stl", ".glb"])
def test_other_formats_round_trip(tmp_path, ext):
    m = trimesh.creation.icosphere(2)
    p = tmp_path / f"s{ext}"
    m.export(p)
    V, F = load_mesh(p)
    if ext == ".stl":  # STL stores no shared vertices: compare the triangles' corners
        np.testing.assert_allclose(np.sort(V[F].reshape(-1, 3), axis=0), np.sort(m.vertices[m.faces].reshape(-1, 3), axis=0), atol=1e-6)
    else:
        np.testing.assert_allclose(V, m.vertices, atol=1e-6)
        np.testing.assert_array_equal(F, m.faces)


BAD = {
    "empty.obj": b"",
    "garbage.obj": bytes(range(256)) * 20,
    "garbage.ply": b"\x00\xffnot a ply at all\x13\x37" * 50,
    "nan.obj": b"v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n",
    "inf.obj": b"v 0 0 0\nv 1 0 0\nv 0 inf 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n",
    "points.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n",
    "triangle.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "flat.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 2 0\nf 1 2 3\nf 2 4 3\nf 3 4 5\nf 1 2 5\n",
    "badindex.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 99\nf 1 3 4\nf 2 3 4\n",
    "zeroindex.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
    "text.obj": b"hello, I am not a mesh\n",
    "truncated.ply": b"ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\nproperty float y\nproperty float z\nelement face 10\nproperty list uchar int vertex_indices\nend_header\n\x00\x00",
    "unknown.xyz3": b"v 0 0 0\n",
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_files_raise_one_clear_error(tmp_path, name):
    p = tmp_path / name
    p.write_bytes(BAD[name])
    with pytest.raises(AutobonesError) as err:
        load_mesh(p)
    msg = str(err.value)
    assert name in msg and "\n" not in msg


def test_missing_file():
    with pytest.raises(AutobonesError, match="no such file"):
        load_mesh("/nonexistent/head.obj")


def test_outputs_are_not_owner_only(tmp_path):
    """Outputs are written to a temporary file and renamed; they get the usual mode under the
    umask (mkstemp alone would leave them readable by their owner only)."""
    import os
    import stat

    import autobones
    from autobones.io.landmarks import read_landmarks, write_landmarks
    from autobones.landmarks.preview import save_preview
    from autobones.generic_rig import default_head_path

    old = os.umask(0o022)
    try:
        rig = autobones.place(density="sparse")
        written = rig.save(tmp_path / "head.glb")
        lm = read_landmarks(os.path.join(os.path.dirname(default_head_path()), "default_head.landmarks.json"))
        write_landmarks(tmp_path / "head.landmarks.json", lm)
        save_preview(tmp_path / "head.png", rig.vertices, rig.faces, lm)
    finally:
        os.umask(old)
    for f in [*written, tmp_path / "head.landmarks.json", tmp_path / "head.png"]:
        assert stat.S_IMODE(os.stat(f).st_mode) == 0o644, f


@pytest.mark.parametrize("ext", [".obj", ".glb"])
def test_posed_mesh_round_trips_in_vertex_order(tmp_path, ext):
    """``autobones pose``'s writer: vertex i of the file is vertex i given (OBJ to 9 digits, GLB float32)."""
    from autobones.io.posed import write_posed_mesh

    rng = np.random.default_rng(0)
    m = trimesh.creation.icosphere(2)
    order = rng.permutation(len(m.vertices))  # a vertex order no loader would make up
    V = m.vertices[order] * 37.0 + rng.normal(size=3)
    F = np.argsort(order)[m.faces]
    path = write_posed_mesh(tmp_path / f"posed{ext}", V, F, comment="a\ntwo-line comment")
    W, G = load_mesh(path)
    np.testing.assert_array_equal(G, F)
    if ext == ".obj":
        np.testing.assert_allclose(W, V, rtol=1e-8, atol=0)
        assert open(path).readline() == "# a two-line comment\n"
    else:
        np.testing.assert_array_equal(W, V.astype(np.float32))


def test_posed_mesh_refuses_other_formats(tmp_path):
    from autobones.io.posed import write_posed_mesh

    with pytest.raises(AutobonesError, match=r"\.obj or \.glb"):
        write_posed_mesh(tmp_path / "x.stl", np.zeros((3, 3)), [[0, 1, 2]])
    assert not (tmp_path / "x.stl").exists()
