"""autobones.io.mesh: vertex order kept, polygons fanned, bad files refused with one clear error."""
import os

import numpy as np
import pytest
import trimesh

from autobones.errors import AutobonesError
from autobones.io.mesh import check_mesh, load_mesh

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


QUAD = ["v 0 0 0", "v 1 0 0", "v 1 1 0", "v 0 1 0", "v 0 0 1", "f 1 2 3 4", "f 1 2 5", "f 1 4 5"]


@pytest.mark.parametrize("spell", ["tab after the keyword", "tabs between numbers", "indented",
                                   "some lines indented", "byte order mark", "continued lines"])
def test_obj_lines_are_read_whatever_their_whitespace(tmp_path, spell):
    """Every ``v`` and ``f`` line counts however an exporter spaces it: a line skipped for its whitespace
    left half a head's triangles out of the rig, with no word said."""
    lines = list(QUAD)
    if spell == "tab after the keyword":
        lines = [ln.replace(" ", "\t", 1) for ln in lines]
    elif spell == "tabs between numbers":
        lines = [ln.replace(" ", "\t") if i % 2 else ln for i, ln in enumerate(lines)]
    elif spell == "indented":
        lines = ["  " + ln for ln in lines]
    elif spell == "some lines indented":
        lines = [" \t" + ln if i in (1, 6) else ln for i, ln in enumerate(lines)]
    elif spell == "continued lines":
        lines = [ln.replace(" ", " \\\n", 1) if ln.startswith("f") else ln for ln in lines]
    text = "\n".join(lines) + "\n"
    p = tmp_path / "q.obj"
    p.write_bytes((b"\xef\xbb\xbf" if spell == "byte order mark" else b"") + text.encode())
    V, F = load_mesh(p)
    assert V.shape == (5, 3) and V[2].tolist() == [1, 1, 0]
    assert F.tolist() == [[0, 1, 2], [0, 2, 3], [0, 1, 4], [0, 3, 4]]


def test_obj_token_that_is_not_a_number_is_named_with_its_line(tmp_path):
    p = tmp_path / "bad.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x3\n")
    with pytest.raises(AutobonesError, match=r"bad.obj:4: 'x3' is not a vertex index"):
        load_mesh(p)


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


@pytest.mark.parametrize("ext", [".ply", ".off"])
def test_a_text_mesh_cut_short_is_called_cut_short(tmp_path, ext):
    """An ASCII PLY or OFF cut inside a face row was refused with numpy's own words ("setting an array element
    with a sequence"), which name no cause."""
    p = tmp_path / f"s{ext}"
    trimesh.creation.icosphere(2).export(p, **({"encoding": "ascii"} if ext == ".ply" else {}))
    text = p.read_bytes()
    p.write_bytes(text[: int(len(text) * 0.9)])
    with pytest.raises(AutobonesError, match="cut short or corrupt|truncated or corrupt"):
        load_mesh(p)


def test_missing_file():
    with pytest.raises(AutobonesError, match="no such file"):
        load_mesh("/nonexistent/head.obj")


def test_a_folder_is_named_a_folder(tmp_path):
    (tmp_path / "head.obj").mkdir()     # even with a mesh's name
    for p in (tmp_path, tmp_path / "head.obj"):
        with pytest.raises(AutobonesError, match="a folder, not a mesh file"):
            load_mesh(p)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
def test_a_fifo_is_named_a_fifo_and_not_read(tmp_path):
    """A named pipe given as the head (or a rig) is refused as what it is, before anything opens it
    (opening one blocks until a writer comes); "no such file" sent users looking for a typo."""
    from autobones.io.rig_files import load_rig

    fifo = tmp_path / "head.obj"
    os.mkfifo(fifo)
    with pytest.raises(AutobonesError, match="a FIFO .named pipe., not a regular file; the head mesh must be a file"):
        load_mesh(fifo)
    glb = tmp_path / "rig.glb"
    os.mkfifo(glb)
    with pytest.raises(AutobonesError, match="a FIFO .named pipe., not a regular file; the rig must be a file"):
        load_rig(glb)


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


# ---------------------------------------------------------------------------------------------
# issue 13: bad input that got through

@pytest.mark.parametrize("name,content", [
    ("noise.stl", bytes(range(256)) * 16),
    ("noise.off", bytes(range(256)) * 16),
    ("solid_noise.stl", b"solid x\n" + bytes(range(128, 256)) * 64),
    ("late_noise.off", b"OFF\n3 1 0\n" + b"# pad\n" * 1000 + bytes(range(128, 256)) * 40),
])
def test_garbage_stl_off_is_a_format_error_without_charset_normalizer(tmp_path, monkeypatch, name, content):
    """trimesh guesses the encoding of non-UTF-8 text with an optional module; without it the reason
    given was 'No module named charset_normalizer'. The loader says what is wrong with the file."""
    import sys

    monkeypatch.setitem(sys.modules, "charset_normalizer", None)  # as if not installed
    p = tmp_path / name
    p.write_bytes(content)
    with pytest.raises(AutobonesError) as err:
        load_mesh(p)
    msg = str(err.value)
    assert name in msg and "not a valid " + name[-3:].upper() in msg and "charset" not in msg and "Module" not in msg


@pytest.mark.parametrize("ext", [".off", ".stl"])
def test_valid_stl_off_still_load_without_charset_normalizer(tmp_path, monkeypatch, ext):
    import sys

    monkeypatch.setitem(sys.modules, "charset_normalizer", None)
    m = trimesh.creation.icosphere(2)
    m.export(tmp_path / f"s{ext}")
    V, F = load_mesh(tmp_path / f"s{ext}")
    assert len(F) == len(m.faces)


def _robot():
    return load_mesh(data("misc/robot_head_neutral.obj"))


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e6])
def test_outlier_rule_is_scale_free(scale):
    """A spike reaching 2 sizes of the rest is refused at any unit; the head alone, and a spike of a
    fifth of its size (a horn, an ear), are not."""
    from autobones.io.mesh import check_mesh

    V, F = _robot()
    V = V * scale
    size = np.ptp(V, axis=0).max()
    check_mesh(V, F)
    top = V[np.argmax(V[:, 1])]
    for reach, ok in ((0.2, True), (2.0, False)):
        W = np.vstack([V, top + [0.0, reach * size, 0.0]])
        G = np.vstack([F, [[F[0, 0], F[0, 1], len(V)]]])
        if ok:
            check_mesh(W, G)
        else:
            with pytest.raises(AutobonesError, match="outlier.*vertex 1742"):
                check_mesh(W, G, name="spiky")


def test_degenerate_faces_refused_whatever_their_count():
    from autobones.io.mesh import check_mesh

    t = np.linspace(0, 1, 100)[:, None]
    line = t * [0.3, 0.7, 0.9] + t ** 2 * 1e-15  # rounding-level bends only
    F = [[i, i + 1, i + 2] for i in range(98)]
    with pytest.raises(AutobonesError, match="zero area"):
        check_mesh(line, F)


def test_outputs_are_renamed_all_or_nothing(tmp_path, monkeypatch):
    """A rename that fails in the middle puts back the files that were there and removes the new ones."""
    import os

    from autobones.io.atomic import replace_all, temp_beside

    targets = [tmp_path / "x.glb", tmp_path / "x.rig.json", tmp_path / "x.weights.npz"]
    for t in targets[:2]:
        t.write_text("old " + t.name)
    staged = []
    for t in targets:
        fd, tmp = temp_beside(t)
        os.write(fd, b"new")
        os.close(fd)
        staged.append((tmp, t))
    real = os.replace
    calls = []

    def flaky(src, dst):
        calls.append(dst)
        if str(dst) == str(targets[2]):
            raise OSError(28, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(os, "replace", flaky)
    with pytest.raises(AutobonesError, match="x.weights.npz: cannot write"):
        replace_all(staged, "the rig")
    monkeypatch.setattr(os, "replace", real)
    assert sorted(os.listdir(tmp_path)) == ["x.glb", "x.rig.json"]
    assert [t.read_text() for t in targets[:2]] == ["old x.glb", "old x.rig.json"]


def test_strict_json_writes_null_for_undefined_values():
    import json

    from autobones.io.jsonable import strict_dumps

    doc = {"a": float("nan"), "b": [1, np.float64(np.inf), (2.5, -np.inf)], "c": np.float64(0.1), "d": "NaN"}
    text = strict_dumps(doc, indent=1)
    assert json.loads(text) == {"a": None, "b": [1, None, [2.5, None]], "c": 0.1, "d": "NaN"}
    assert strict_dumps({"x": [0.1, 2, "y"]}) == json.dumps({"x": [0.1, 2, "y"]})


def _with_triangles(V, F, corners):
    """``(V, F)`` plus one triangle per (3, 3) block of ``corners``, appended at the end."""
    corners = np.asarray(corners, dtype=np.float64).reshape(-1, 3)
    return np.vstack([V, corners]), np.vstack([F, len(V) + np.arange(len(corners)).reshape(-1, 3)])


def _far_triangle(V, reach):
    size = float(np.ptp(V, axis=0).max())
    p = V.mean(axis=0) + reach * size * np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    return p + 0.02 * size * np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e6])
def test_a_small_far_part_is_a_stray_in_any_unit(scale):
    """One triangle 10 head sizes away: dropped (and no outlier) at any unit; the same triangle
    half a head size away is part of the head; a connected spike is still refused."""
    from autobones.io.mesh import check_mesh, stray_parts

    V, F = _robot()
    V = V * scale
    W, G = _with_triangles(V, F, _far_triangle(V, 10.0))
    with pytest.raises(AutobonesError, match="outlier"):
        check_mesh(W, G)                       # callers that do not drop strays still refuse them
    check_mesh(W, G, strays=True)
    body = stray_parts(W, G)
    assert body is not None and body.record["parts"] == 1 and body.record["vertices"] == 3
    assert np.array_equal(body.index, np.arange(len(V))) and np.array_equal(body.F, F)
    assert 0 < body.record["area_fraction"] < 0.01
    near = V[np.argmax(V[:, 1])] + [0.0, 0.5 * np.ptp(V, axis=0).max(), 0.0]
    assert stray_parts(*_with_triangles(V, F, near + 0.02 * scale * np.eye(3))) is None
    top = V[np.argmax(V[:, 1])]
    spike = (np.vstack([V, top + [0.0, 2.0 * np.ptp(V, axis=0).max(), 0.0]]),
             np.vstack([F, [[F[0, 0], F[0, 1], len(V)]]]))
    assert stray_parts(*spike) is None
    with pytest.raises(AutobonesError, match="outlier"):
        check_mesh(*spike, strays=True)


def test_many_far_parts_are_a_mess_and_refused():
    """Far parts holding more than 1% of the area (two sheets half a head wide) are not strays: the
    outlier error stands."""
    from autobones.io.mesh import check_mesh, stray_parts
    from autobones.geometry.areas import triangle_areas

    V, F = _robot()
    size = float(np.ptp(V, axis=0).max())
    centres = V.mean(axis=0) + size * np.array([[6.0, 0.0, 0.0], [0.0, -7.0, 5.0]])
    tris = centres[:, None, :] + 0.5 * size * np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    W, G = _with_triangles(V, F, tris)
    assert triangle_areas(W, G)[len(F):].sum() > 0.01 * triangle_areas(W, G).sum()
    assert stray_parts(W, G) is None
    with pytest.raises(AutobonesError, match="outlier"):
        check_mesh(W, G, strays=True)


def test_an_unwelded_head_is_one_body():
    """Every triangle on its own vertices: parts join through shared positions, only the far one drops."""
    from autobones.io.mesh import stray_parts

    V, F = _robot()
    U, G = V[F.ravel()], np.arange(3 * len(F)).reshape(-1, 3)
    W, H = _with_triangles(U, G, _far_triangle(V, 10.0))
    body = stray_parts(W, H)
    assert body is not None and body.record["parts"] == 1 and len(body.index) == len(U)


def test_place_rigs_a_head_with_a_stray_triangle(caplog):
    """The stray's vertices weigh 1 on the root bone, the rest is the head's own rig, vertex count and
    order unchanged; one warning and the sidecar say so."""
    import logging

    import autobones

    V, F = _robot()
    W, G = _with_triangles(V, F, _far_triangle(V, 10.0))
    plain = autobones.place((V, F), density="sparse")
    with caplog.at_level(logging.WARNING, logger="autobones"):
        rig = autobones.place((W, G), density="sparse")
    assert rig.weights.shape == (len(W), plain.weights.shape[1]) and np.array_equal(rig.vertices, W)
    assert np.abs(rig.weights[:len(V)] - plain.weights).max() < 1e-12
    root = rig.skeleton.names.index("neck")
    assert np.array_equal(rig.weights[len(V):], np.eye(rig.weights.shape[1])[[root] * 3])
    assert not rig.facial_mask[len(V):].any() and len(rig.labels) == len(W)
    said = [r.getMessage() for r in caplog.records if "dropped" in r.getMessage()]
    assert len(said) == 1 and "dropped 1 small part far from the head (3 vertices, 1 faces" in said[0], said
    side = rig.sidecar()
    assert side["options"]["dropped_parts"]["vertices"] == 3 and side["options"]["dropped_parts"]["weighted_to"] == "neck"
    assert side["vertex_count"] == len(W)


def test_the_head_rigged_without_its_stray_parts_keeps_its_file_name(tmp_path, caplog):
    """The body rigged apart from a stray part (or a hat) goes through ``place`` again: every message
    of that run names the file (the robot's front, a close call, was said of "mesh")."""
    import logging

    import autobones
    from autobones.io.obj import write_obj

    W, G = _with_triangles(*_robot(), _far_triangle(_robot()[0], 10.0))
    path = tmp_path / "robot_and_a_stray.obj"
    write_obj(str(path), W, G)
    with caplog.at_level(logging.WARNING, logger="autobones"):
        rig = autobones.place(str(path), density="sparse")
    said = [r.getMessage() for r in caplog.records]
    assert rig.source == path.name and len(said) == 2, said
    assert all(m.startswith(path.name + ": ") for m in said) and "close call" in said[0] and "dropped" in said[1]


@pytest.mark.parametrize("command", ["place", "transfer"])
def test_a_head_wearing_a_hat_is_rigged_as_the_bare_head(command):
    """A lump set on the head (a ball of 0.15 head sizes on the goat's crown, a separate part) turned
    the goat's frame 113 degrees and, rigged with the head, moved ``place``'s joints 0.07 head sizes.
    It is left out of the rig (``io.parts.worn_parts``) and weighted as the skin nearest it: the head's
    own rig bit for bit, the hat riding the crown; the sidecar's ``worn_parts`` says so."""
    from scipy.spatial import cKDTree

    import autobones
    from autobones.io.landmarks import read_landmarks
    from shared_data import ROOT

    V, F = load_mesh(data("misc/goathead.obj"))
    bare_frame = autobones.detect_frame(V, F)
    C = bare_frame.to_canonical(V)
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.15)
    hat = bare_frame.from_canonical(np.asarray(ball.vertices) + C[np.argmax(C[:, 1])] + [0.0, 0.12, 0.0])
    W, G = np.vstack([V, hat]), np.vstack([F, np.asarray(ball.faces) + len(V)])
    if command == "place":
        rig_of = lambda mesh: autobones.place(mesh, density="sparse")  # noqa: E731
    else:
        marks = read_landmarks(ROOT / "tests" / "landmarks" / "goathead.landmarks.json")
        rig_of = lambda mesh: autobones.transfer(mesh, marks)  # noqa: E731
    bare, worn = rig_of((V, F)), rig_of((W, G))
    assert np.array_equal(worn.weights[:len(V)], bare.weights) and np.array_equal(worn.vertices, W)
    assert np.array_equal(worn.skeleton.heads, bare.skeleton.heads)
    near = cKDTree(V).query(hat)[1]
    assert np.array_equal(worn.weights[len(V):], bare.weights[near])
    assert worn.options["worn_parts"]["parts"] == 1 and worn.options["worn_parts"]["vertices"] == len(hat)


def test_several_heads_in_one_file_are_refused(tmp_path):
    """Two heads side by side are one head per file, refused with one line (rigged as one, the frame
    came out lying down); a second large part touching the head (a body modelled apart, a hat) is not."""
    from autobones.io.mesh import check_mesh, default_head

    V, F = default_head()
    width = float(np.ptp(V[:, 0]))
    for gap, refused in ((0.3 * width, True), (0.0, False)):
        V2 = np.vstack([V, V + [width + gap, 0.0, 0.0]])
        F2 = np.vstack([F, F + len(V)])
        if refused:
            with pytest.raises(AutobonesError, match=r"2 separate parts of head size stand apart \(50%, 50% of the "
                                                     r"area.*one head per file"):
                check_mesh(V2, F2, name="lineup")
        else:
            assert check_mesh(V2, F2, name="lineup")[0].shape == (2 * len(V), 3)


@pytest.mark.parametrize("offset", [1e4, 1e6])
def test_a_head_too_far_from_the_origin_for_float32_is_refused_with_the_cure(tmp_path, offset):
    """A 0.2 m head 1e6 m out was written to the glb on a 0.06 m grid (31 distinct positions of 8,838) with
    exit 0; 1e4 m out, 1,969 vertices snapped together. 1e3 m out it rounds by 3 % of an edge: rigged."""
    V, F = load_mesh(data("menpo3d/james.obj"))
    V = (V - V.mean(axis=0)) * (0.2 / np.ptp(V, axis=0).max())
    with pytest.raises(AutobonesError, match=r"from the origin.*snap together.*move it near the origin"):
        check_mesh(V + offset, F, "far.obj")
    check_mesh(V + 1e3, F, "near.obj")
