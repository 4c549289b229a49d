"""Rebuild tests/data from the shared data set (``../shared/data`` beside the project) and check it.

    python tests/data/make_test_data.py [path/to/shared/data]

For each family folder (``ict``, ``menpo3d``, ``mediapipe``, ``misc``, ``zoo``) it writes ``meshes.npz``:

- OBJ files: the ``v`` lines as an (n, 3) array, float32 when every value read back from numpy's
  shortest float32 repr equals the file's float64 value bit for bit (true of every file written with
  6-7 significant digits), float64 otherwise; the ``f`` lines as polygons (first index of each corner,
  0-based), each distinct face list stored once as ``<topology>/sizes`` (uint8) and ``<topology>/index``
  (int32) and named by ``<file>/topology``. Texture coordinates, materials and comments are dropped.
- the binary PLY: its float32 vertices, uchar colours, triangles and header comments, as they are.

Landmark files (``*.landmarks.json``) and the ICT licence are copied unchanged. Then every file is
written back out by ``shared_data.mesh_bytes`` and compared with the original through
``autobones.io.mesh.load_mesh`` (and trimesh for the files the tests load with trimesh): vertices and
faces must be identical.
"""
import hashlib
import shutil
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

# What the tests read (grep data(" in tests/*.py, the SMALL list and _variants of test_batch.py, the
# KNOWN table of test_orient.py, and every */*.landmarks.json that test_landmarks.py reads).
FILES = {
    "ict": ["generic_neutral_mesh.obj", "identity000.obj", "identity001.obj", "identity002.obj", "jawOpen.obj", "mouthSmile_L.obj",
            "generic_neutral_mesh.landmarks.json", "identity000.landmarks.json", "identity001.landmarks.json",
            "identity002.landmarks.json", "LICENSE"],
    "menpo3d": ["james.obj", "template.ply", "james.landmarks.json", "template.landmarks.json"],
    "mediapipe": ["canonical_face_model.obj"],
    "misc": ["LeePerrySmith.obj", "demosthenes-low-res.obj", "fran_cut.obj", "fsaverage_head.obj", "goathead.obj",
             "robot_head_neutral.obj", "robot_head_Angry.obj", "robot_head_Sad.obj", "robot_head_Surprised.obj"],
}
# the one zoo head whose licence allows carrying it (Apache-2.0, VTK data): the jaw tests' cow
# (its landmarks are in tests/landmarks/, outside the folders test_landmarks.py sweeps)
FILES["zoo"] = ["cowHead.obj"]
TRIMESH_LOADED = ["misc/LeePerrySmith.obj", "misc/robot_head_Sad.obj"]  # test_render.py, test_batch.py


def read_obj(path):
    verts, sizes, index = [], [], []
    with open(path, "rb") as fh:
        for raw in fh:
            if raw[:2] == b"v ":
                verts.append([float(t) for t in raw.split()[1:4]])
            elif raw[:2] == b"f ":
                idx = [int(t.split(b"/")[0]) for t in raw.split()[1:]]
                assert min(idx) > 0, f"{path}: negative OBJ indices are not supported here"
                sizes.append(len(idx))
                index.extend(i - 1 for i in idx)
    return np.array(verts, dtype=np.float64), np.array(sizes, dtype=np.uint8), np.array(index, dtype=np.int32)


def float32_is_exact(V):
    V32 = V.astype(np.float32)
    back = np.array([float(str(x)) for x in V32.ravel()]).reshape(V.shape)
    return back.tobytes() == V.tobytes()


def read_ply(path):
    raw = Path(path).read_bytes()
    end = raw.index(b"end_header\n") + len(b"end_header\n")
    head = raw[:end].decode("ascii").splitlines()
    expect = ["property float x", "property float y", "property float z", "property uchar red",
              "property uchar green", "property uchar blue", "property uchar alpha",
              "property list uchar int vertex_indices"]
    assert [h for h in head if h.startswith("property")] == expect and "format binary_little_endian 1.0" in head, head
    nv = int(next(h for h in head if h.startswith("element vertex")).split()[2])
    nf = int(next(h for h in head if h.startswith("element face")).split()[2])
    verts = np.frombuffer(raw, dtype=[("xyz", "<f4", (3,)), ("rgba", "u1", (4,))], count=nv, offset=end)
    faces = np.frombuffer(raw, dtype=[("n", "u1"), ("idx", "<i4", (3,))], count=nf, offset=end + verts.nbytes)
    assert (faces["n"] == 3).all() and end + verts.nbytes + faces.nbytes == len(raw)
    comments = [h[len("comment "):] for h in head if h.startswith("comment ")]
    return verts["xyz"].copy(), verts["rgba"].copy(), faces["idx"].copy(), comments


def build(shared):
    report = []
    for family, names in FILES.items():
        out = HERE / family
        out.mkdir(exist_ok=True)
        arrays, topologies = {}, {}
        for name in names:
            src = shared / family / name
            if not name.endswith((".obj", ".ply")):
                shutil.copyfile(src, out / name)
                continue
            if name.endswith(".ply"):
                V, rgba, F, comments = read_ply(src)
                arrays.update({f"{name}/vertices": V, f"{name}/rgba": rgba, f"{name}/faces": F,
                               f"{name}/comments": np.array(comments)})
                report.append((f"{family}/{name}", "float32 (the PLY's own type)"))
                continue
            V, sizes, index = read_obj(src)
            key = hashlib.sha256(sizes.tobytes() + index.tobytes()).hexdigest()
            if key not in topologies:
                topologies[key] = tname = f"topology{len(topologies)}"
                arrays[f"{tname}/sizes"], arrays[f"{tname}/index"] = sizes, index
            exact = float32_is_exact(V)
            arrays[f"{name}/vertices"] = V.astype(np.float32) if exact else V
            arrays[f"{name}/topology"] = np.array(topologies[key])
            naive = np.abs(V.astype(np.float32).astype(np.float64) - V).max()
            report.append((f"{family}/{name}", ("float32" if exact else "float64")
                           + f" (plain float32 cast would move values by up to {naive:.3g})"))
        np.savez_compressed(out / "meshes.npz", **arrays)
    return report


def check(shared):
    import trimesh

    from autobones.io.mesh import load_mesh
    from shared_data import data

    worst = 0.0
    for family, names in FILES.items():
        for name in names:
            if not name.endswith((".obj", ".ply")):
                assert (HERE / family / name).read_bytes() == (shared / family / name).read_bytes()
                continue
            orig, made = shared / family / name, data(f"{family}/{name}")
            V0, F0 = load_mesh(orig)
            V1, F1 = load_mesh(made)
            assert V0.dtype == V1.dtype and F0.dtype == F1.dtype and F0.tobytes() == F1.tobytes(), name
            worst = max(worst, float(np.abs(V0 - V1).max()))
            assert V0.tobytes() == V1.tobytes(), f"{family}/{name}: vertices differ"
            same_bytes = orig.read_bytes() == made.read_bytes()
            print(f"{family}/{name}: load_mesh V, F identical ({len(V0)} v, {len(F0)} f)"
                  + (", file byte-identical" if same_bytes else ""))
            if f"{family}/{name}" in TRIMESH_LOADED:
                m0, m1 = (trimesh.load(p, process=False) for p in (orig, made))
                assert np.asarray(m0.vertices).tobytes() == np.asarray(m1.vertices).tobytes()
                assert np.asarray(m0.faces).tobytes() == np.asarray(m1.faces).tobytes()
                print(f"  trimesh.load(process=False): V, F identical")
    print(f"max |V(original) - V(written)| over all meshes: {worst}")


if __name__ == "__main__":
    shared = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT.parent / "shared" / "data"
    for rel, how in build(shared):
        print(f"{rel}: {how}")
    check(shared)
    size = sum(f.stat().st_size for f in HERE.rglob("*") if f.is_file())
    print(f"tests/data: {size / 1e6:.2f} MB")
