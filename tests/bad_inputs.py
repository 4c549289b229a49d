"""A corpus of bad and hostile inputs, generated (never committed as binaries) for the batch tests.

Every case is a small file (or a mesh plus a landmark file) built from the robot head of
``tests/data`` or from nothing, with what the batch must do with it:

- ``expect="failed"``: one clear message naming the file and containing ``needle``, no
  output file, the other files of the batch still finish;
- ``expect="ok"``: a valid if unusual mesh that must rig (non-manifold edges, inconsistent
  winding, 40 parts, a 10^6 scale, far from the origin, an ``mtllib`` pointing outside its
  folder, which the OBJ reader never opens).

``write_mesh_corpus(folder)`` and ``write_landmark_corpus(folder)`` write the cases and
return ``{file name: Case}``.
"""
from __future__ import annotations

import json
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from shared_data import ROOT, data

ROBOT = "misc/robot_head_neutral.obj"
ROBOT_LANDMARKS = ROOT / "tests" / "landmarks" / "robot_head_neutral.landmarks.json"


@dataclass
class Case:
    expect: str              # "failed" or "ok"
    needle: str = ""         # a word the one-line message must contain (lower case)
    why: str = ""            # the decision, for the README's table


def robot():
    """(V, F) of the shared robot head (1742 vertices, metres-ish units, +Y up)."""
    V, F = [], []
    for line in data(ROBOT).read_text().splitlines():
        if line.startswith("v "):
            V.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("f "):
            F.append([int(t.split("/")[0]) - 1 for t in line.split()[1:]])
    F = [(f[0], f[k], f[k + 1]) for f in F for k in range(1, len(f) - 1)]
    return np.array(V), np.array(F, dtype=np.int64)


def obj_bytes(V, F, header=""):
    lines = [header] if header else []
    lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(V, dtype=float).tolist()]
    lines += ["f " + " ".join(str(int(i) + 1) for i in f) for f in F]
    return ("\n".join(lines) + "\n").encode()


def ply_binary(V, F, claim_vertices=None, claim_faces=None):
    nv = len(V) if claim_vertices is None else claim_vertices
    nf = len(F) if claim_faces is None else claim_faces
    head = (f"ply\nformat binary_little_endian 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\n"
            f"property float z\nelement face {nf}\nproperty list uchar int vertex_indices\nend_header\n").encode()
    body = np.asarray(V, dtype="<f4").tobytes()
    body += b"".join(struct.pack("<B3i", 3, *map(int, f)) for f in F)
    return head + body


def ply_ascii(V, F):
    head = (f"ply\nformat ascii 1.0\nelement vertex {len(V)}\nproperty float x\nproperty float y\nproperty float z\n"
            f"element face {len(F)}\nproperty list uchar int vertex_indices\nend_header\n")
    rows = [f"{x} {y} {z}" for x, y, z in V] + [f"3 {a} {b} {c}" for a, b, c in F]
    return (head + "\n".join(rows) + "\n").encode()


def mesh_cases():
    """{file name: (bytes, Case)} for place mode."""
    rng = np.random.default_rng(5)
    V, F = robot()
    out = {}

    def add(name, content, expect, needle="", why=""):
        out[name] = (content, Case(expect, needle, why))

    # not a mesh at all
    add("empty.obj", b"", "failed", "empty", "nothing to read")
    add("random_obj.obj", rng.bytes(4096), "failed", "", "random bytes: no vertex lines, or lines that are not numbers")
    add("random_ply.ply", rng.bytes(4096), "failed", "ply", "random bytes, no PLY header")
    add("random_stl.stl", rng.bytes(4096), "failed", "not a valid stl", "random bytes: a binary STL's size does "
        "not match its triangle count, and they are not text starting with 'solid'")
    add("random_glb.glb", rng.bytes(4096), "failed", "glb", "random bytes, no glTF magic")
    add("random_off.off", rng.bytes(4096), "failed", "not a valid off", "random bytes, no OFF header")
    add("text_as_numbers.obj", b"v a b c\nv 1 2 3\nv 0 1 0\nf 1 2 3\n", "failed", "obj",
        "a vertex line whose coordinates are not numbers")
    # truncated files
    full = obj_bytes(V, F)
    cut = full[: full.index(b"\nv ", len(full) // 5) + 8]  # ends inside a vertex line: "v 0.12"
    add("truncated_obj.obj", cut.rsplit(b" ", 2)[0] + b"\n", "failed", "",
        "cut in the vertex block: a vertex line with too few coordinates, and no faces")
    add("truncated_faces.obj", full[: full.index(b"\nf ") + 1], "failed", "no faces",
        "cut before the first face: a point cloud")
    pb = ply_binary(V, F)
    add("truncated_ply.ply", pb[: len(pb) // 2], "failed", "ply", "binary PLY cut in half: the data is shorter than the header says")
    pa = ply_ascii(V, F)
    add("truncated_ascii.ply", pa[: len(pa) // 3], "failed", "ply", "ASCII PLY cut in the vertex list")
    # bad numbers
    Vn = V.copy()
    Vn[17, 1] = np.nan
    add("nan.obj", obj_bytes(Vn, F), "failed", "nan", "a NaN coordinate")
    Vi = V.copy()
    Vi[3, 0] = np.inf
    add("inf.obj", obj_bytes(Vi, F), "failed", "infinite", "an infinite coordinate")
    # degenerate geometry
    Fz = F.copy()
    Fz[:, 2] = Fz[:, 1]
    add("zero_area.obj", obj_bytes(V, Fz), "failed", "zero area", "every face has two equal corners")
    add("cloud_ply.ply", b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                     b"end_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n", "failed", "point cloud", "vertices, no faces")
    add("cloud_obj.obj", obj_bytes(V, np.zeros((0, 3), int)), "failed", "no faces", "vertices, no faces")
    add("one_triangle.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "failed", "faces", "a single triangle")
    add("flat.obj", obj_bytes(V * [1, 1, 0], F), "failed", "flat", "all z = 0: no volume")
    m = 500
    strip = np.linspace(0.0, 1.0, m)[:, None] * [0.3, 0.7, 0.9] + [0.1, 0.2, 0.3]  # on one slanted line
    add("collinear_strip.obj", obj_bytes(strip, [[i, i + 1, i + 2] for i in range(m - 2)]), "failed", "zero area",
        "498 triangles with their corners on one line (total area ~1e-16, not exactly 0): no surface")
    # a few vertices far from the rest decide the bounding box, and with it the frame and every tolerance
    size = float(np.linalg.norm(np.ptp(V, axis=0)))
    for tag, far in (("1e9", [1e9, 1e9, 1e9]), ("1e7", [1e7, -1e7, 1e7])):
        add(f"stray_triangle_{tag}.obj", obj_bytes(np.vstack([V, far]), np.vstack([F, [[F[0, 0], F[0, 1], len(V)]]])),
            "failed", "outlier", f"the head plus one triangle to a vertex at {tag}")
    for tag, k in (("1e3", 1e3), ("1e5", 1e5)):
        tip = V.mean(axis=0) + [0.0, k * size, 0.0]
        add(f"spike_{tag}.obj", obj_bytes(np.vstack([V, tip]), np.vstack([F, [[F[0, 0], F[0, 1], len(V)]]])),
            "failed", "outlier", f"one spike triangle {tag} head sizes long")
    # bad indices
    add("huge_index.obj", obj_bytes(V, F) + b"f 1 2 99999999999999\n", "failed", "out of range",
        "a face index far beyond the vertex count")
    add("negative_index.obj", obj_bytes(V, F) + b"f -99999 1 2\n", "failed", "out of range",
        "a relative index before the first vertex")
    add("zero_index.obj", obj_bytes(V, F) + b"f 0 1 2\n", "failed", "index 0", "OBJ indices start at 1")
    # headers that claim far more than the file holds: refused, never allocated
    add("claims_4g_vertices_ply.ply", ply_binary(V[:4], F[:4] % 4, claim_vertices=4_000_000_000), "failed", "ply",
        "a PLY header claiming 4e9 vertices (48 GB) in a 1 kB file")
    add("claims_huge_stl.stl", b"\0" * 80 + struct.pack("<I", 0xFFFFFFF0) + b"\0" * 100, "failed", "stl",
        "a binary STL header claiming 4e9 triangles (200 GB)")
    add("claims_huge_off.off", b"OFF\n2000000000 2000000000 0\n0 0 0\n1 0 0\n", "failed", "off",
        "an OFF header claiming 2e9 vertices")
    # valid if unusual: must rig
    fin = np.array([[F[0, 0], F[0, 1], len(V)]])
    add("non_manifold.obj", obj_bytes(np.vstack([V, V[F[0, 2]] + [0, 0, 0.3]]), np.vstack([F, fin])), "ok",
        why="an extra face on an existing edge (3 faces on one edge): a valid mesh")
    Fw = F.copy()
    Fw[::2] = Fw[::2, ::-1]
    add("inconsistent_winding.obj", obj_bytes(V, Fw), "ok", why="every other face flipped: geometry is unchanged")
    parts_V, parts_F, off = [], [], 0
    for chunk in np.array_split(np.arange(len(F)), 40):  # 40 unwelded parts of the same surface
        used, inv = np.unique(F[chunk], return_inverse=True)
        parts_V.append(V[used])
        parts_F.append(inv.reshape(-1, 3) + off)
        off += len(used)
    add("forty_parts.obj", obj_bytes(np.vstack(parts_V), np.vstack(parts_F)), "ok",
        why="40 disconnected parts (the head cut in 40 unwelded pieces): every vertex gets weights")
    add("scale_1e6.obj", obj_bytes(V * 1e6, F), "ok", why="any unit: the pipeline works in head sizes")
    add("far_from_origin.obj", obj_bytes(V + [3.0e4, -2.0e4, 1.0e4], F), "ok",
        why="10^4 head sizes from the origin: float64 keeps the shape")
    add("mtllib_outside.obj", obj_bytes(V, F, header="mtllib ../../../../etc/passwd\nusemtl x"), "ok",
        why="mtllib is never opened: the OBJ reader reads only v and f lines")
    return out


def landmark_cases():
    """{stem: (landmark file name suffix, bytes, Case)} for transfer mode on the robot head."""
    lm = json.loads(ROBOT_LANDMARKS.read_text())["landmarks"]
    out = {}

    def contract(d):
        return json.dumps({"format": "autobones-landmarks/1", "landmarks": d}, indent=1).encode()

    def add(stem, content, expect, needle="", why="", suffix=".landmarks.json"):
        out[stem] = (suffix, content, Case(expect, needle, why))

    add("lm_good", contract(lm), "ok", why="the robot's own landmarks")
    bad = dict(lm)
    bad["nose_tip"] = bad.pop("pronasale")
    add("lm_unknown", contract(bad), "failed", "unknown landmark", "a name outside the contract")
    text = contract(lm).decode().replace('"menton"', '"nasion"', 1)
    add("lm_duplicate", text.encode(), "failed", "twice", "the same name twice")
    mirrored = {(k[:-1] + ("r" if k.endswith("_l") else "l")) if k[-2:] in ("_l", "_r") else k: v
                for k, v in lm.items()}
    add("lm_mirrored", contract(mirrored), "failed", "swapped", "every _l exchanged with its _r")
    P = np.array(list(lm.values()))
    d = P[1] - P[0]
    line = {k: (P[0] + d * (i + 1) / len(lm)).tolist() for i, k in enumerate(lm)}
    add("lm_one_line", contract(line), "failed", "one line", "all landmarks on one line")
    add("lm_millimetres", contract({k: [c * 1000 for c in v] for k, v in lm.items()}), "failed", "units",
        "millimetres for a mesh in metres (x1000)")
    add("lm_off_surface", contract({k: [v[0], v[1], v[2] + 3.0] for k, v in lm.items()}), "failed",
        "far from the mesh", "every landmark 3 units in front of the face")
    add("lm_empty", b"", "failed", "empty", "an empty landmark file")
    add("lm_garbage", b"<point name=\"vertex\" x=\"1\" y=\"2\" z=\"3\"/> <<<&&&", "failed", "", "a broken .pp",
        suffix=".pp")
    add("lm_missing", None, "failed", "no face found",
        "no landmark file beside a robot: automatic landmarks find no face there")
    return out


def write_mesh_corpus(folder):
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    cases = {}
    for name, (content, case) in mesh_cases().items():
        (folder / name).write_bytes(content)
        cases[name] = case
    return cases


def write_landmark_corpus(folder):
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    head = data(ROBOT).read_bytes()
    cases = {}
    for stem, (suffix, content, case) in landmark_cases().items():
        (folder / f"{stem}.obj").write_bytes(head)
        if content is not None:
            (folder / f"{stem}{suffix}").write_bytes(content)
        cases[f"{stem}.obj"] = case
    return cases


def crash_on_crash(input_path, output_path, options):
    """``rig_one``, except that a worker given a file named ``crash.*`` dies at once (as on a segfault)."""
    import os

    from autobones.batch import rig_one

    if os.path.basename(input_path).startswith("crash."):
        os._exit(139)
    return rig_one(input_path, output_path, options)
