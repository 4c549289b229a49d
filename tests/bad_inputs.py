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

``command_cases()`` (issue #33) are single commands given a hostile file argument (a device, a
FIFO, a folder, a file over its size or row limit, JSON nested 100k deep, a newline in a name),
bad options, or a batch whose output tree links into its input; every one must end as ``expect="refused"``: one line on stderr containing ``needle``,
exit code 2, nothing written, the inputs untouched, and no wait on a FIFO.
``write_command_case(folder, name, rig)`` makes the files and returns the argument list.

``view_cases()`` (issue #33 item 9) are requests to ``autobones view`` on ``write_view_folder``: no token or a
wrong one is 403, a file of the folder that is not a rig shown (or its sidecar) is 404 even with the token.
"""
from __future__ import annotations

import hashlib
import json
import os
import stat
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
    add("one_triangle.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "failed", "only 1 face;", "a single triangle")
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
    width = float(np.ptp(V[:, 0]))
    add("two_heads.obj", obj_bytes(np.vstack([V, V + [1.3 * width, 0.0, 0.0]]), np.vstack([F, F + len(V)])), "failed",
        "one head per file", "two heads side by side (rigged as one, the frame is found across both)")
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
    add("inside_out.obj", obj_bytes(V, F[:, ::-1]), "ok",
        why="every triangle wound inward (a negative-scale export): rigged outward, written as given")
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
    add("too_far_from_origin.obj", obj_bytes(V + [3.0e6, 0.0, 0.0], F), "failed", "from the origin",
        why="10^6 head sizes from the origin: a glb's float32 positions would snap its vertices together")
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


# The arguments of each command case: {rig} a copy of a saved rig in the case's folder, {head} the
# robot mesh there, {file} the bad file the case makes, {out} an output path that must not appear.
_MEGA = 1024 ** 2


def _capture(rows, full=True):
    """A Live Link Face CSV: its real header and ``rows`` frames (frame-number timecodes), all zero;
    ``full=False``: one field per frame row (the row limit is counted before any row is parsed)."""
    from autobones.arkit.names import ARKIT_NAMES, CAPTURE_ANGLES, capture_column

    cols = [capture_column(n) for n in ARKIT_NAMES] + list(CAPTURE_ANGLES)
    head = ",".join(["Timecode", "BlendShapeCount"] + cols) + "\n"
    tail = ("," + str(len(ARKIT_NAMES)) + ",0" * len(cols)) if full else ""
    return (head + "".join(f"{i}{tail}\n" for i in range(rows))).encode()


def _deep(n=100_000):
    return b"[" * n + b"]" * n


def _deep_glb():
    """A glb header and one JSON chunk nested 100k deep."""
    chunk = _deep()
    return b"glTF" + struct.pack("<II", 2, 20 + len(chunk)) + struct.pack("<I4s", len(chunk), b"JSON") + chunk


def command_cases():
    """{name: (args, what {file} is, Case)}: ``what`` is a function giving the bytes to write, ``"fifo"``, ``"folder"``,
    ``("sparse", n)`` (a sparse file of n bytes: over a limit without using the disk), a fixed path
    such as ``/dev/zero``, ``("sidecar", f)`` / ``("glb", f)`` (the rig's own file replaced by ``f()``),
    ``("name", file name, bytes or None)``, ``("batch_link", "folder" | "file")`` ({file} an input folder
    holding ``sub/head.obj``, {out} an output folder whose ``sub`` links to the input's ``sub``, or whose
    ``sub/head.rig.glb`` links to ``head.obj``) or None (no file)."""
    pose = ["pose", "{rig}", "-o", "{out}.obj", "--definitions", "{file}"]
    animate = ["animate", "{rig}", "-o", "{out}.glb", "--capture", "{file}"]
    lm = ["landmarks", "{head}", "-o", "{out}.landmarks.json", "--from", "{file}"]
    out = {}

    def add(name, args, what, needle, why):
        out[name] = (args, what, Case("refused", needle, why))

    add("definitions_dev_zero", pose, "/dev/zero", "device",
        "pose --definitions /dev/zero: refused from stat, never read (was: grew to 24 GB, killed by the kernel)")
    add("definitions_fifo", pose, "fifo", "fifo", "a FIFO no one writes to: refused, never opened (was: blocked forever)")
    add("definitions_folder", pose, "folder", "folder", "a folder given as the definitions")
    add("definitions_over_size", pose, ("sparse", 65 * _MEGA), "64 mb limit",
        "a 65 MB definitions file: over the 64 MB limit for JSON (AUTOBONES_MAX_FILE_MB raises it)")
    add("definitions_deep", pose, _deep, "nested 100000 levels",
        "JSON nested 100k deep: refused by a scan before json.loads (was: RecursionError traceback)")
    add("definitions_newline_name", pose, ("name", "x\ny.json", b"{}"), "x\\ny.json",
        "a newline in the file name: the name is written as its repr, the message stays one line")
    add("sidecar_deep", ["pose", "{rig}", "-o", "{out}.obj"], ("sidecar", lambda: b'{"format": ' + _deep() + b"}"),
        "nested 100001 levels", "the rig's sidecar nested 100k deep (was: RecursionError traceback)")
    add("glb_json_deep", ["pose", "{rig}", "-o", "{out}.obj"], ("glb", _deep_glb), "nested 100000 levels deep",
        "the rig's glb with its JSON chunk nested 100k deep: the depth scan of io/files.py runs on it too "
        "(was: RecursionError traceback)")
    add("capture_dev_zero", animate, "/dev/zero", "device",
        "animate --capture /dev/zero: refused from stat (was: MemoryError traceback)")
    add("capture_fifo", animate, "fifo", "fifo", "a FIFO as the capture: refused, never opened (was: blocked forever)")
    add("capture_over_size", animate, ("sparse", 65 * _MEGA), "64 mb limit", "a 65 MB capture CSV")
    add("capture_1m_frames", animate, lambda: _capture(1_000_000), "64 mb limit",
        "a 1M-frame capture CSV (126 MB): over the 64 MB limit, refused from stat (was: 5 GB read)")
    add("capture_1m_short_rows", animate, lambda: _capture(1_000_000, full=False), "more than 200000 frames",
        "a 1M-row CSV of one field per row (7 MB, under the size limit): refused at row 200,001 while read, "
        "before any row is parsed")
    add("capture_250k_frames", animate, lambda: _capture(250_000), "more than 200000 frames",
        "250k real frames (31 MB, under the size limit): over the 200k-frame limit (55 min at 60 fps)")
    add("landmarks_dev_zero", lm, "/dev/zero", "device", "landmarks --from /dev/zero")
    add("landmarks_fifo", lm, "fifo", "fifo", "landmarks --from a FIFO: refused, never opened")
    add("landmarks_over_size", lm, ("sparse", 17 * _MEGA), "16 mb limit", "a 17 MB landmark file: over 16 MB")
    add("mesh_newline_name", ["place", "{file}", "-o", "{out}.glb"], ("name", "a\nb.obj", b"v 0 0 0\n"),
        "a\\nb.obj", "a mesh whose name holds a newline (a message of io/mesh.py): the CLI writes each control "
        "character as its escape, so the line stays one")
    add("mesh_1e200_warnings", ["place", "{file}", "-o", "{out}.glb", "--density", "sparse"],
        ("name", "big.obj", None), "coordinates reach",
        "the robot at x1e200: refused by the scale check before numpy overflows (its RuntimeWarnings would be held "
        "and dropped before the one-line error)")
    batch = ["batch", "{file}", "-o", "{out}", "--density", "sparse", "--force"]
    add("batch_output_subfolder_linked_into_input", batch, ("batch_link", "folder"), "inside the input folder",
        "batch IN -o OUT --force where OUT/sub links to IN/sub: every output resolved first, refused (was: rigs "
        "written inside IN, IN/sub/scan.glb replaced by its own rig)")
    add("batch_output_file_linked_to_input", batch, ("batch_link", "file"), "inside the input folder",
        "batch IN -o OUT --force where OUT/sub/head.rig.glb links to the input IN/sub/head.obj: refused")
    # argparse's own errors: one line and the command's --help (was: the usage block, 2-7 lines)
    add("argparse_missing_value", ["place", "--density"], None, "(see autobones place --help)",
        "an option without its value")
    add("argparse_unknown_option", ["pose", "{rig}", "--bogus"], None, "(see autobones pose --help)",
        "an option the command does not have")
    add("argparse_bad_choice", ["transfer", "{head}", "--symmetric", "maybe"], None, "(see autobones transfer --help)",
        "a value outside the choices")
    add("argparse_missing_argument", ["animate", "{rig}", "-o", "{out}.glb"], None, "--capture",
        "a required option missing")
    add("place_rig_without_landmarks", ["place", "{head}", "-o", "{out}.glb", "--rig", "{head}"], None, "--landmarks",
        "place --rig without --landmarks: the rig is used only with landmarks (was: ignored, exit 0)")
    add("no_command", [], None, "no command given", "autobones alone: one line on stderr, exit 2 (was: the help on "
        "stdout, exit 2); autobones --help prints the help, exit 0")
    tampered_cases(add)
    bad_value_cases(add)
    return out


def _edit(rig, change):
    """``("edit", rig, change)``: the sidecar of rig ``"r"`` (placed) or ``"t"`` (transferred, with ARKit
    shapes) read as JSON, ``change(meta)`` applied (it edits the dict in place, or returns the new text)."""
    return ("edit", rig, change)


def _nan_weights(arrays):
    arrays["weights"] = arrays["weights"].copy()
    arrays["weights"][3, 0] = np.nan


def _set(path, value):
    """A change setting ``meta[k1][k2]...`` (``path`` a tuple of keys / indices) to ``value``."""
    def change(meta):
        node = meta
        for k in path[:-1]:
            node = node[k]
        node[path[-1]] = value
    return change


def _definitions(change):
    """The shipped definitions with ``change(doc)`` applied (in place, or returning the new text), as bytes."""
    def make():
        from autobones.generic_rig import expressions_path

        doc = json.loads(Path(expressions_path()).read_text())
        text = change(doc)
        return (text if isinstance(text, str) else json.dumps(doc)).encode()
    return make


def tampered_cases(add):
    """Issue #33 item 5: a rig's sidecar (or definitions) edited into a value autobones never writes.
    Each was a traceback, an allocation of what the file claimed, or NaN; each is one line naming the key."""
    pose_r = ["pose", "{rig}", "-o", "{out}.obj"]
    pose_t = ["pose", "{trig}", "--au", "12=1", "-o", "{out}.obj"]
    add("sidecar_labels_out_of_int8", pose_r, _edit("r", _set(("labels", 5), 300)), "labels holds 300",
        "a label of 300 (int8 holds -128..127; the labels are 0..2): refused by the schema (was: OverflowError)")
    add("sidecar_vertex_count_infinity", pose_r,
        _edit("r", lambda m: json.dumps(m).replace(f'"vertex_count": {m["vertex_count"]}', '"vertex_count": Infinity')),
        "non-finite number (infinity)", "vertex_count Infinity: the JSON reader refuses NaN and Infinity, which "
        "autobones never writes (was: OverflowError traceback)")
    add("sidecar_vertex_count_1e12", pose_r, _edit("r", _set(("vertex_count",), 10 ** 12)),
        "vertex_count is 1000000000000", "vertex_count 10^12: refused before anything is allocated (was: an "
        "attempt to allocate 931 GiB)")
    add("sidecar_landmarks_list", pose_t, _edit("t", lambda m: m.update(landmarks=list(m["landmarks"].values()))),
        "landmarks is a list", "landmarks as a list of points (was: AttributeError traceback)")
    add("sidecar_muscles_string", pose_t, _edit("t", _set(("muscles",), "zygomaticus")), "muscles is the string",
        "muscles as a string (was: TypeError traceback)")
    add("sidecar_frame_2x2", pose_r, _edit("r", _set(("frame", "rotation"), [[1.0, 0.0], [0.0, 1.0]])),
        "frame.rotation is a list of 2", "a 2x2 frame rotation (was: ValueError traceback from matmul)")
    add("sidecar_head_size_0", pose_r, _edit("r", _set(("frame", "head_size"), 0)), "frame.head_size is 0",
        "head_size 0 (every length is divided by it)")
    add("sidecar_facial_mask_out_of_range", pose_r, _edit("r", _set(("facial_mask",), [10 ** 9])),
        "facial_mask holds 1000000000", "a facial-mask index past the vertices (was: IndexError traceback)")
    lots = _set(("action_units", "12", "muscles", "zygomaticus_major"), "lots")
    add("definitions_au_lots", pose_t + ["--definitions", "{file}"], _definitions(lots),
        "action_units.12.muscles.zygomaticus_major is the string 'lots'",
        "pose --definitions with an AU's muscle weight \"lots\" (was: ValueError traceback)")
    add("sidecar_definitions_au_lots", pose_t, _edit("t", lambda m: lots(m["expressions"]["definitions"])),
        "expressions.definitions.action_units.12", "the definitions a transferred rig's sidecar keeps, the same edit")
    add("npz_weights_nan", ["export", "{rig}", "-o", "{out}.usda"], ("npz", "r", _nan_weights), "npz weights hold 1 nan",
        "a NaN skin weight in the rig's .weights.npz: load_rig refuses it, so no writer gets it")
    add("export_proc", ["export", "{rig}", "-o", "/proc/autobones-x.usda"], None, "cannot write in /proc",
        "export -o /proc/...: the temporary file cannot be made there (was: FileNotFoundError traceback)")


def bad_value_cases(add):
    """Issue #33 item 6: inputs that wrote infinities, NaN or collapsed triangles with exit 0: each refused
    in one line naming the value (and the writers refuse anything non-finite as the last line of defence)."""
    add("mesh_scale_1e150", ["place", "{file}", "-o", "{out}.glb", "--density", "sparse"],
        ("name", "big.obj", 1e150), "coordinates reach 4.48e+150",
        "the robot at x1e150: beyond 1e18, a glb's float32 positions would be -inf (was: written, exit 0)")
    add("mesh_scale_1e-40", ["place", "{file}", "-o", "{out}.glb", "--density", "sparse"],
        ("name", "tiny.obj", 1e-40), "4.1e-40 across",
        "the robot at x1e-40: below 1e-18 across, every triangle has zero area in float32 (was: written, exit 0)")
    add("pose_au_1e308", ["pose", "{trig}", "--au", "12=1e308", "-o", "{out}.glb"], None,
        "au 12: 1e+308 is outside [-10, 10]",
        "an AU at 1e308 (every position infinite): intensities within +-10 (1 is the unit's full action)")
    add("capture_weight_1e308", ["animate", "{trig}", "-o", "{out}.glb", "--capture", "{file}"],
        lambda: _capture(3).replace(b",52,0,", b",52,1e308,", 1), "'1e308' is outside [-1, 2]",
        "a capture weight of 1e308 (infinite float32 keys): ARKit weights run 0..1, [-1, 2] accepted")
    add("definitions_nan_smoothing", ["pose", "{trig}", "--au", "12=1", "-o", "{out}.obj", "--definitions", "{file}"],
        _definitions(lambda d: json.dumps(d).replace('"smoothing": 0.012', '"smoothing": NaN')),
        "non-finite number (nan)", "model.smoothing NaN (was: 2,941 NaN vertices written, exit 0)")
    add("build_rig_centimetres", ["build-rig", "{head}", "--landmarks", "{file}", "-o", "{out}"],
        ("name", "cm.landmarks.json", _scaled_landmarks(100.0)), "centimetres",
        "build-rig with the robot's landmarks x100: the unit and surface check of transfer (was: a rig 226 m off)")


def _scaled_landmarks(k):
    doc = json.loads(ROBOT_LANDMARKS.read_text())
    doc["landmarks"] = {n: [c * k for c in p] for n, p in doc["landmarks"].items()}
    return json.dumps(doc).encode()


def write_command_case(folder, name, rig, transferred=None):
    """Make command case ``name``'s files in ``folder`` (the placed rig ``rig`` copied in as r.glb and its
    sidecars, the ``transferred`` rig (with ARKit shapes) as t.glb, the robot as head.obj) and return its
    argument list."""
    import shutil

    args, what, _ = command_cases()[name]
    folder = Path(folder)
    for stem, src_rig in (("r", rig), ("t", transferred)):
        if src_rig is None:
            continue
        src_rig = Path(src_rig)
        for src in (src_rig, src_rig.with_name(src_rig.stem + ".rig.json"),
                    src_rig.with_name(src_rig.stem + ".weights.npz")):
            shutil.copy(src, folder / src.name.replace(src_rig.stem, stem, 1))
    (folder / "head.obj").write_bytes(data(ROBOT).read_bytes())
    file = folder / "bad"
    if callable(what):  # made only when used: the captures take ~1 s to build
        file.write_bytes(what())
    elif what == "fifo":
        import os

        os.mkfifo(file)
    elif what == "folder":
        file.mkdir()
    elif isinstance(what, str):
        file = Path(what)
    elif what and what[0] == "sparse":
        with open(file, "wb") as fh:
            fh.truncate(what[1])
    elif what and what[0] == "edit":  # the rig's sidecar edited
        side = folder / f"{what[1]}.rig.json"
        meta = json.loads(side.read_text())
        text = what[2](meta)
        side.write_text(text if isinstance(text, str) else json.dumps(meta))
    elif what and what[0] == "npz":  # the rig's weights file edited
        npz = folder / f"{what[1]}.weights.npz"
        with np.load(npz) as z:
            arrays = {k: z[k] for k in z.files}
        what[2](arrays)
        np.savez_compressed(npz, **arrays)
    elif what and what[0] in ("sidecar", "glb"):  # the rig's own file replaced
        (folder / ("r.rig.json" if what[0] == "sidecar" else "r.glb")).write_bytes(what[1]())
    elif what and what[0] == "batch_link":  # {file} is the input folder, {out} the output folder
        file.mkdir()
        (file / "sub").mkdir()
        (file / "sub" / "head.obj").write_bytes(data(ROBOT).read_bytes())
        (folder / "out").mkdir()
        if what[1] == "folder":
            (folder / "out" / "sub").symlink_to(file / "sub", target_is_directory=True)
        else:
            (folder / "out" / "sub").mkdir()
            (folder / "out" / "sub" / "head.rig.glb").symlink_to(file / "sub" / "head.obj")
    elif what and what[0] == "name":
        file = folder / what[1]
        if what[2] is None or isinstance(what[2], float):  # the robot at x1e200, or at the scale given
            V, F = robot()
            file.write_bytes(obj_bytes(V * (what[2] or 1e200), F))
        else:
            file.write_bytes(what[2])
    return [a.format(rig=folder / "r.glb", trig=folder / "t.glb", head=folder / "head.obj", file=file, out=folder / "out")
            for a in args]


def view_cases():
    """{name: (target, status, Case)} (issue #33 item 9): requests to ``autobones view`` on the folder
    ``write_view_folder`` makes, ``{token}`` replaced by the server's token and ``{wrong}`` by another of the
    same length. ``expect="refused"``: the status given, nothing of the file in the answer;
    ``expect="ok"``: 200, the file's own bytes. The connection cases (100 idle sockets, a slowloris
    client) are tests of their own in tests/test_view_limits.py."""
    out = {}

    def add(name, target, status, why):
        out[name] = (target, status, Case("refused" if status != 200 else "ok", str(status), why))

    add("view_no_token_page", "/", 403, "the page without the token (was: 200, any local user could open it)")
    add("view_no_token_api", "/api/batch", 403, "the batch listing without the token (was: 200)")
    add("view_no_token_file", "/files/robot.rig.glb", 403, "a rig without the token (was: 200)")
    add("view_wrong_token", "/{wrong}/files/robot.rig.glb", 403, "a guessed token of the right length")
    add("view_token_not_first", "/files/{token}/robot.rig.glb", 403, "the token elsewhere than the first segment")
    add("view_other_file", "/{token}/files/notes.txt", 404,
        "a file of the folder that is not a rig, with the token (was: 200: every non-hidden file was served)")
    add("view_report_file", "/{token}/files/batch_report.json", 404,
        "the batch report as a file (the page reads it through /api/batch; it names the input folder)")
    add("view_input_copy", "/{token}/files/sub/head.obj", 404, "a mesh left in a sub-folder")
    add("view_unlisted_rig", "/{token}/files/extra.rig.glb", 404, "an autobones rig the report does not list")
    add("view_unlisted_rig_api", "/{token}/api/rig?path=extra.rig.glb", 404, "the same rig's facts through the API")
    add("view_unlisted_thumb", "/{token}/api/thumb?path=extra.rig.glb", 404, "the same rig's thumbnail")
    add("view_traversal", "/{token}/files/../secret.txt", 403, "a file outside the folder, with the token")
    add("view_rig", "/{token}/files/robot.rig.glb", 200, "a rig the page shows")
    add("view_sidecar", "/{token}/files/robot.rig.json", 200, "its sidecar")
    add("view_weights", "/{token}/files/robot.weights.npz", 200, "its full weight matrix")
    return out


def write_view_folder(folder, rig):
    """``folder/rigs``: what ``view_cases`` are asked of. A batch report listing ``robot.rig.glb`` (the rig
    ``rig`` copied in, its sidecars too, named as a batch names them), ``extra.rig.glb`` (the same rig, not
    listed), ``notes.txt``, ``sub/head.obj``, and ``folder/secret.txt`` beside it. Returns the rigs folder."""
    import shutil

    from autobones.rig import sidecar_paths

    rigs = Path(folder) / "rigs"
    (rigs / "sub").mkdir(parents=True)
    side, npz = sidecar_paths(rig)
    for stem in ("robot", "extra"):
        for src, name in ((rig, f"{stem}.rig.glb"), (side, f"{stem}.rig.json"), (npz, f"{stem}.weights.npz")):
            shutil.copy(src, rigs / name)
    report = {"format": "autobones-batch-report/1", "input": "/in", "output": str(rigs),
              "counts": {"ok": 1, "failed": 0, "skipped": 0},
              "files": [{"input": "robot.obj", "output": "robot.rig.glb", "status": "ok"}]}
    (rigs / "batch_report.json").write_text(json.dumps(report))
    (rigs / "notes.txt").write_text("private notes\n")
    (rigs / "sub" / "head.obj").write_bytes(data(ROBOT).read_bytes())
    (Path(folder) / "secret.txt").write_text("secret\n")
    return rigs


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


def api_cases():
    """Issue #33 item 8: {name: (call, needle, why)}: ``call(ctx)`` calls a public entry point with a wrong
    type, shape or value, and must raise AutobonesError (a ValueError) whose message contains ``needle``
    (the argument's name). ``ctx``: ``V``, ``F`` (the robot), ``lm`` (its landmark dict), ``rig`` (its
    transferred Rig) and ``defs`` (a copy of the shipped definitions)."""
    import autobones

    nan = float("nan")
    inf = float("inf")

    def smoothing_nan(c):
        c.defs["model"]["smoothing"] = nan
        return autobones.ExpressionModel(c.defs).fit(c.rig)

    return {
        "place_ragged_faces": (lambda c: autobones.place((c.V, [[0, 1, 2], [1, 2]])), "faces",
                               "faces as a ragged list (was: ValueError from numpy, or silently truncated)"),
        "place_fractional_faces": (lambda c: autobones.place((c.V, c.F + 0.5)), "whole vertex indices",
                                   "faces of 0.5, 1.5...: refused, never cut to 0, 1 by astype"),
        "place_text_vertices": (lambda c: autobones.place((c.V.astype(str), c.F)), "vertices",
                                "vertices as strings"),
        "transfer_landmarks_list": (lambda c: autobones.transfer((c.V, c.F), landmarks=list(c.lm.values())),
                                    "landmarks", "landmarks as a list of points: no names to go by"),
        "transfer_landmark_nan": (lambda c: autobones.transfer((c.V, c.F), landmarks={**c.lm, "vertex": [nan, 0, 0]}),
                                  "vertex", "a landmark with a NaN coordinate"),
        "transfer_rig_42": (lambda c: autobones.transfer((c.V, c.F), landmarks=c.lm, rig=42), "rig:",
                            "rig=42 (was: AttributeError)"),
        "load_rig_none": (lambda c: autobones.load_rig(None), "path:", "load_rig(None) (was: TypeError)"),
        "load_mesh_number": (lambda c: autobones.load_mesh(3.5), "path:", "load_mesh(3.5) (was: TypeError)"),
        "detect_frame_fractional_faces": (lambda c: autobones.detect_frame(c.V, c.F + 0.5), "F:",
                                          "detect_frame with fractional faces (was: IndexError)"),
        "detect_frame_flat_list": (lambda c: autobones.detect_frame([1.0, 2.0, 3.0], c.F), "V:",
                                   "detect_frame with three numbers as V (was: IndexError)"),
        "detect_frame_face_out_of_range": (lambda c: autobones.detect_frame(c.V, c.F + len(c.V)), "F:",
                                           "face indices past the vertices"),
        "pose_head_inf": (lambda c: c.rig.pose(head_deg=[inf, 0, 0]), "head_deg",
                          "pose(head_deg=[inf, 0, 0]) (was: NaN vertices returned)"),
        "pose_au_1e308": (lambda c: c.rig.pose(au={12: 1e308}), "au 12", "an AU at 1e308 (was: inf vertices)"),
        "pose_au_list": (lambda c: c.rig.pose(au=[12]), "au:", "au as a list"),
        "pose_gaze_shape": (lambda c: c.rig.pose(gaze=[1.0, 2.0, 3.0]), "gaze", "gaze of 3 angles"),
        "pose_jaw_text": (lambda c: c.rig.pose(jaw_deg="wide"), "jaw_deg", "jaw_deg a string"),
        "expression_model_fit_42": (lambda c: autobones.ExpressionModel().fit(42), "rig:",
                                    "ExpressionModel().fit(42) (was: AttributeError)"),
        "expression_model_definitions_42": (lambda c: autobones.ExpressionModel(42).fit(c.rig), "definitions",
                                            "ExpressionModel(42)"),
        "expression_model_nan_smoothing": (smoothing_nan, "model.smoothing is nan",
                                           "definitions given as a dict with NaN smoothing (was: NaN vertices)"),
        "build_rig_landmarks_list": (lambda c: autobones.build_rig((c.V, c.F), [[0.0, 0.0, 0.0]]), "landmarks",
                                     "build_rig with a list of points"),
        "build_rig_centimetres": (lambda c: autobones.build_rig((c.V, c.F), {k: [x * 100 for x in v]
                                                                         for k, v in c.lm.items()}), "centimetres",
                                  "build_rig with landmarks x100: the unit check of transfer"),
        "labelled_rig_load_none": (lambda c: autobones.LabelledRig.load(None), "folder:", "LabelledRig.load(None)"),
        "save_path_none": (lambda c: c.rig.save(None), "path:", "rig.save(None)"),
        "place_rig_42": (lambda c: autobones.place((c.V, c.F), landmarks=c.lm, rig=42), "rig:",
                         "place(rig=42) (was: AttributeError)"),
        "transfer_control_points_text": (lambda c: autobones.transfer((c.V, c.F), landmarks=c.lm, control_points="x"),
                                         "control_points", "control_points='x' (was: TypeError)"),
        "pose_arkit_list": (lambda c: c.rig.pose(arkit=[1.0]), "arkit:", "arkit weights as a list (was: "
                            "AttributeError)"),
        "skeleton_flat_heads": (lambda c: autobones.Skeleton(["a"], [-1], [[0.0, 0.0]], [[0.0, 0.0, 1.0]]), "heads",
                                "a Skeleton with 2-D heads (was: a bare AssertionError)"),
        "skeleton_parent_after_child": (lambda c: autobones.Skeleton(["a", "b"], [-1, 1], [[0.0] * 3] * 2,
                                                                     [[0.0, 0.0, 1.0]] * 2), "parents",
                                        "a bone that is its own parent"),
    }


def snapshot(folder):
    """Every entry under ``folder``, links not followed: a regular file's SHA-256, a link's target,
    else its type (a FIFO is never opened). Two equal snapshots: nothing written, changed or added."""
    out = {}
    for root, dirs, files in os.walk(folder):
        for name in dirs + files:
            p = os.path.join(root, name)
            mode = os.lstat(p).st_mode
            if stat.S_ISLNK(mode):
                out[os.path.relpath(p, folder)] = "-> " + os.readlink(p)
            elif stat.S_ISREG(mode):
                out[os.path.relpath(p, folder)] = hashlib.sha256(Path(p).read_bytes()).hexdigest()
            else:
                out[os.path.relpath(p, folder)] = stat.S_IFMT(mode)
    return out
