#!/usr/bin/env python
"""Snapshot the CLI's outputs on the shared heads, and compare two snapshots: a refactor check.

A refactor must not change behaviour. This tool runs a fixed list of ``autobones`` CLI jobs
(place, transfer, pose, landmarks, batch, build-rig) on the shared heads with the OLD code and
with the NEW code, and compares every file written, by content, to 1e-10 of the head size.

Usage (from the repository root)::

    # 1. the old code (a git worktree of the reference commit, e.g. /work/baseline at 94329a9)
    python tools/rig_snapshot.py run /work/snapshots/old --expect-src /work/baseline \\
        --cli "env PYTHONPATH=/work/baseline python -c 'import sys; from cli.main import main; sys.exit(main())'"
    # 2. the new code (the installed console script, or python -m autobones once it exists)
    python tools/rig_snapshot.py run /work/snapshots/new --expect-src /work/main --cli autobones
    # 3. compare: a table, exit 0 when every file agrees within 1e-10 of its head size, 1 otherwise
    python tools/rig_snapshot.py compare /work/snapshots/old /work/snapshots/new

``run OUTDIR --cli PREFIX``
    PREFIX is split with shlex and the job's arguments appended (no shell). Every job runs in its
    own folder ``OUTDIR/<job>/`` (the current directory of the CLI, so default output names are
    exercised too); its stdout/stderr go to ``OUTDIR/_logs/<job>.out|.err``; the batch jobs' input
    folder is ``OUTDIR/_inputs/``. ``OUTDIR/jobs.json`` records each job's name, argv, exit code,
    expected exit code, wall seconds and the input mesh (for the head size). Jobs run one after
    the other; a failing job is recorded and the run goes on (a pose job whose transfer failed
    fails too). OUTDIR must be new or empty, or an earlier snapshot (it has ``jobs.json`` or ``provenance.json``):
    that is deleted first. Exit code 0 when every job exited as expected, 1 otherwise.

    Which code ran: before the jobs, ``PREFIX --version`` is run once with ``PYTHONVERBOSE=1``;
    the interpreter's import trace names the file each module was loaded from, so the check goes
    through exactly the same prefix (env, bootstrap, console script) as the jobs. The files of
    ``autobones`` and ``cli.main`` are written to ``OUTDIR/provenance.json`` and printed;
    ``--expect-src DIR`` stops the run when ``autobones`` was not imported from under DIR.

    Shadowing: this machine has an editable install of /work/main (a ``__editable__...finder``
    appended to ``sys.meta_path`` by a .pth file). ``PYTHONPATH=/work/baseline`` still wins,
    because ``PYTHONPATH`` entries are searched by the normal ``PathFinder``, which comes before the
    editable finder in ``sys.meta_path``; checked (provenance.json of the old snapshot names
    /work/baseline/autobones/__init__.py and /work/baseline/cli/main.py). Batch worker processes
    inherit the environment, so they import the same code. Beware the current folder: ``python -c``
    puts it FIRST on sys.path, before PYTHONPATH, so the old prefix run from /work/main imports
    /work/main's ``cli`` (found while writing this tool). Every job, and the check, therefore runs
    in a folder under OUTDIR, never in a source tree. Were it ever shadowed, a bootstrap that
    puts the tree first and drops the editable finders would do::

        --cli "python -c 'import sys; sys.path.insert(0, \\"/work/baseline\\"); \\
               sys.meta_path[:] = [f for f in sys.meta_path if \\"editable\\" not in repr(f)]; \\
               from cli.main import main; sys.exit(main())'"

    (plus PYTHONPATH for the batch's worker processes).

    Inputs: the heads under ``--data`` (default ``<repo>/../shared/data``), and the frozen
    reference files under ``--ref`` (default: this checkout): the goat and robot landmark files
    (``tests/landmarks/``) and the default head + landmarks for ``build-rig``
    (``generic_rig/default_head.obj``, ``.landmarks.json``). Both snapshots must use the same
    ``--data`` and ``--ref`` so the inputs are the same bytes.

    build-rig: ``generic_rig/build_default_rig.py`` calls ``build_rig(V, F, landmarks)`` on the
    default head and then sets two metadata strings (``rig.units``, ``rig.frame``) before
    ``rig.save``; the CLI job ``build-rig default_head.obj --landmarks default_head.landmarks.json
    -o rig/`` is the same computation without those two strings (so its rig.json is not
    byte-equal to ``generic_rig/default/rig.json``, but old and new CLI outputs are comparable).

``compare OLD_DIR NEW_DIR``
    Every file under either snapshot (except jobs.json, provenance.json, _logs/, _inputs/) is
    compared with its namesake, by content:

    - ``.glb``: the GLB container is parsed (JSON chunk + BIN chunk); every accessor is read as a
      numpy array and compared by index (dtype, shape, values); the glTF JSON is compared
      recursively (nodes' names, translations, rotations, children, skins, meshes, morph target
      names in ``meshes[].extras.targetNames``, accessor count/type/min/max...) except the byte
      layout (``bufferViews``, ``buffers``, accessors' ``bufferView``/``byteOffset``) and
      ``asset.generator`` (trimesh writes its version there for posed glbs).
    - ``.json`` (``.rig.json``, landmark files, ``batch_report.json``, build-rig's ``rig.json``):
      recursive; the same keys, strings equal, numbers (and numeric lists, as arrays) within the
      tolerance, NaN equal to NaN. Ignored, as run-dependent: keys named ``time``, ``seconds``,
      ``timings``, ``finished``, ``started``, ``elapsed``, ``host``, ``pid``,
      ``autobones_version``; and strings that are absolute paths on both sides (a path inside the
      snapshot is compared relative to the snapshot's root; other absolute paths, such as the
      batch report's ``input``/``output`` folders, are ignored). ``batch_report.json`` so keeps
      ``counts``, ``options``, ``options_hash``, per-file ``status``, ``error``, ``vertices``...
    - ``.npz``: every array (same names, dtype, shape, values).
    - ``.obj``: the numbers of the ``v`` and ``f`` lines (comment lines are ignored).
    - anything else: bytes.

    Head size: the bounding-box diagonal of the job's input mesh (jobs.json ``head``); for a job
    without one (the default head, batch) the vertices of the file itself (glb POSITION, npz
    ``vertices``, obj ``v``) or of a sibling with the same stem, else the largest head size of
    the job's other files (``batch_report.json``). A file agrees when
    max |old - new| <= 1e-10 * head size (``--tol``); structural differences (missing file or
    key, shape, dtype, string) count as infinite. The job exit codes of the two jobs.json must
    agree as well. Exit 0 when everything agrees, 1 otherwise (the offenders are listed).

Dependencies: numpy only (the GLB container is parsed by hand).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import re
import shlex
import shutil
import struct
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
DEFAULT_DATA = os.path.normpath(os.path.join(REPO, "..", "shared", "data"))
DEFAULT_REF = REPO  # this checkout; pass the same --ref to both runs

SKIP_TOP = {"jobs.json", "provenance.json", "_logs", "_inputs"}
IGNORED_KEYS = {"time", "seconds", "timings", "finished", "started", "elapsed", "host", "pid",
                "autobones_version"}
GLB_LAYOUT_KEYS = {"bufferViews", "buffers"}
GLB_ACCESSOR_LAYOUT_KEYS = {"bufferView", "byteOffset"}


# ---------------------------------------------------------------------------------------------
# jobs

def job_list(data, ref):
    """``[(name, args, head_mesh_or_None, expected_exit_code)]``; args relative to OUTDIR/<name>/."""
    ict = os.path.join(data, "ict")
    menpo = os.path.join(data, "menpo3d")
    misc = os.path.join(data, "misc")
    tl = os.path.join(ref, "tests", "landmarks")
    gr = os.path.join(ref, "generic_rig")
    ict0, ict1, ict2 = (os.path.join(ict, f"identity00{i}.obj") for i in range(3))
    james = os.path.join(menpo, "james.obj")
    lps = os.path.join(misc, "LeePerrySmith.obj")
    goat = os.path.join(misc, "goathead.obj")
    robot = os.path.join(misc, "robot_head_neutral.obj")
    fran = os.path.join(misc, "fran_cut.obj")
    lm = {"ict1": os.path.join(ict, "identity001.landmarks.json"),
          "ict2": os.path.join(ict, "identity002.landmarks.json"),
          "james": os.path.join(menpo, "james.landmarks.json"),
          "goat": os.path.join(tl, "goathead.landmarks.json"),
          "robot": os.path.join(tl, "robot_head_neutral.landmarks.json")}
    tr = {k: os.path.join("..", f"transfer_{k}", f"{k}.glb") for k in ("ict2", "ict1", "james", "goat", "robot")}
    jobs = [
        ("place_default", ["place"], None, 0),  # default output name default_head.rig.glb
        ("place_default_dense", ["place", "--density", "dense", "-o", "default_head_dense.glb"], None, 0),
        ("place_ict0", ["place", ict0, "-o", "ict0.glb"], ict0, 0),
        ("place_james", ["place", james, "-o", "james.glb"], james, 0),
        ("place_james_dense", ["place", james, "--density", "dense", "-o", "james_dense.glb"], james, 0),
        ("place_lps", ["place", lps, "-o", "lps.glb"], lps, 0),
        ("place_goat", ["place", goat, "-o", "goat.glb"], goat, 0),
        ("place_robot", ["place", robot, "-o", "robot.glb"], robot, 0),
        ("place_fran", ["place", fran, "-o", "fran.glb"], fran, 0),
        ("place_landmarks_ict2", ["place", ict2, "--landmarks", lm["ict2"], "-o", "ict2.glb"], ict2, 0),
        ("transfer_ict2", ["transfer", ict2, "--landmarks", lm["ict2"], "--expressions", "-o", "ict2.glb"], ict2, 0),
        ("transfer_ict1", ["transfer", ict1, "--landmarks", lm["ict1"], "--expressions", "-o", "ict1.glb"], ict1, 0),
        ("transfer_james", ["transfer", james, "--landmarks", lm["james"], "--expressions", "-o", "james.glb"],
         james, 0),
        ("transfer_goat", ["transfer", goat, "--landmarks", lm["goat"], "--expressions", "-o", "goat.glb"], goat, 0),
        ("transfer_robot", ["transfer", robot, "--landmarks", lm["robot"], "--expressions", "-o", "robot.glb"],
         robot, 0),
        ("transfer_ict0_auto", ["transfer", ict0, "-o", "ict0.glb"], ict0, 0),  # landmarks found by MediaPipe
        ("pose_ict2_fear", ["pose", tr["ict2"], "--expression", "fear", "-o", "fear.obj"], ict2, 0),
        ("pose_goat_happiness", ["pose", tr["goat"], "--expression", "happiness", "-o", "happiness.obj"], goat, 0),
        ("pose_james_au12L_gaze", ["pose", tr["james"], "--au", "12L=1", "--gaze", "20,0", "-o", "smirk.obj"],
         james, 0),
        ("pose_robot_jaw_au43", ["pose", tr["robot"], "--jaw", "10", "--au", "43=1", "-o", "jaw.obj"], robot, 0),
        ("pose_ict1_happiness_glb", ["pose", tr["ict1"], "--expression", "happiness", "-o", "happiness.glb"],
         ict1, 0),
        ("landmarks_lps", ["landmarks", lps, "-o", "lps.landmarks.json"], lps, 0),
        ("landmarks_james", ["landmarks", james, "-o", "james.landmarks.json"], james, 0),
        ("landmarks_ict0", ["landmarks", ict0, "-o", "ict0.landmarks.json"], ict0, 0),
        ("landmarks_goat_from", ["landmarks", goat, "--from", lm["goat"]], goat, 0),  # default name goathead.landmarks.json
        ("batch_place", ["batch", os.path.join("..", "_inputs", "batch_heads"), "-o", "out", "--jobs", "1"], None, 0),
        ("batch_transfer", ["batch", os.path.join("..", "_inputs", "batch_heads"), "-o", "out", "--transfer"], None, 0),
        ("build_rig_default", ["build-rig", os.path.join(gr, "default_head.obj"), "--landmarks",
                               os.path.join(gr, "default_head.landmarks.json"), "-o", "rig"],
         os.path.join(gr, "default_head.obj"), 0),
    ]
    batch_inputs = [(goat, "goathead.obj"), (lm["goat"], "goathead.landmarks.json"),
                    (robot, "robot_head_neutral.obj"), (lm["robot"], "robot_head_neutral.landmarks.json")]
    return jobs, batch_inputs


def provenance(prefix, env, cwd):
    """Run ``PREFIX --version`` with PYTHONVERBOSE=1 in ``cwd`` and read from the import trace where modules
    came from (``cwd`` matters: ``python -c`` puts the current folder first on sys.path)."""
    e = dict(env, PYTHONVERBOSE="1")
    p = subprocess.run(prefix + ["--version"], capture_output=True, text=True, env=e, timeout=300, cwd=cwd)
    found = {}
    pats = {"autobones": r"autobones[/\\]__init__\.py", "cli.main": r"cli[/\\]main\.py"}
    for line in p.stderr.splitlines():
        for mod, pat in pats.items():
            if mod in found:
                continue
            # "# /x/autobones/__pycache__/__init__.cpython-311.pyc matches /x/autobones/__init__.py"
            # or "# code object from /x/autobones/__init__.py" (no cache; quoted in some versions)
            m = re.search(r"matches (\S*" + pat + r")\s*$", line) or re.search(r"code object from '?(\S*?" + pat + r")'?\s*$",
                                                                               line)
            if m:
                found[mod] = os.path.realpath(m.group(1))
    return {"prefix": prefix, "version_output": p.stdout.strip(), "exit_code": p.returncode,
            "modules": found}


def cmd_run(args):
    prefix = shlex.split(args.cli)
    out = os.path.abspath(args.outdir)
    data, ref = os.path.abspath(args.data), os.path.abspath(args.ref)
    if os.path.exists(out) and os.listdir(out):
        if not any(os.path.exists(os.path.join(out, f)) for f in ("jobs.json", "provenance.json")):
            print(f"rig_snapshot: {out} is not empty and not a snapshot (no jobs.json); refusing to overwrite",
                  file=sys.stderr)
            return 2
        shutil.rmtree(out)
    os.makedirs(os.path.join(out, "_logs"), exist_ok=True)
    env = dict(os.environ)

    prov = provenance(prefix, env, cwd=os.path.join(out, "_logs"))
    with open(os.path.join(out, "provenance.json"), "w", encoding="utf-8") as fh:
        json.dump(prov, fh, indent=1)
    print(f"code: {prov['version_output'] or '(no --version output)'}; "
          + ", ".join(f"{k} from {v}" for k, v in prov["modules"].items()))
    if args.expect_src:
        src = os.path.realpath(args.expect_src)
        got = prov["modules"].get("autobones")
        if got is None or os.path.commonpath([src, got]) != src:
            print(f"rig_snapshot: autobones was imported from {got}, not from under {src}; stopping",
                  file=sys.stderr)
            return 2

    jobs, batch_inputs = job_list(data, ref)
    if args.only:
        keep = set(args.only.split(","))
        jobs = [j for j in jobs if j[0] in keep]
    bdir = os.path.join(out, "_inputs", "batch_heads")
    os.makedirs(bdir, exist_ok=True)
    for src, name in batch_inputs:
        shutil.copyfile(src, os.path.join(bdir, name))

    records, t_all = [], time.perf_counter()
    for name, jargs, head, expect in jobs:
        cwd = os.path.join(out, name)
        os.makedirs(cwd, exist_ok=True)
        argv = prefix + jargs
        t = time.perf_counter()
        with open(os.path.join(out, "_logs", name + ".out"), "w") as so, \
                open(os.path.join(out, "_logs", name + ".err"), "w") as se:
            try:
                rc = subprocess.run(argv, cwd=cwd, stdout=so, stderr=se, env=env, timeout=args.timeout).returncode
            except subprocess.TimeoutExpired:
                rc = "timeout"
        dt = time.perf_counter() - t
        rec = {"name": name, "argv": argv, "cwd": cwd, "exit_code": rc, "expected_exit_code": expect,
               "seconds": round(dt, 2), "head": head, "outputs": sorted(_files(cwd, cwd))}
        records.append(rec)
        flag = "ok" if rc == expect else "UNEXPECTED"
        print(f"{name:28s} exit {rc!s:>7s} {dt:7.1f} s  {flag}  ({len(rec['outputs'])} files)", flush=True)
        _write_jobs(out, prov, records, time.perf_counter() - t_all, partial=True)
    total = time.perf_counter() - t_all
    _write_jobs(out, prov, records, total, partial=False)
    bad = [r["name"] for r in records if r["exit_code"] != r["expected_exit_code"]]
    print(f"{len(records)} jobs in {total:.1f} s; " + (f"unexpected exit codes: {', '.join(bad)}" if bad else
                                                       "every exit code as expected"))
    return 1 if bad else 0


def _write_jobs(out, prov, records, total, partial):
    doc = {"format": "rig-snapshot-jobs/1", "cli": prov["prefix"], "modules": prov["modules"],
           "complete": not partial, "total_seconds": round(total, 2), "jobs": records}
    with open(os.path.join(out, "jobs.json"), "w", encoding="utf-8") as fh:
        json.dump(doc, fh, indent=1)


def _files(root, top):
    """Relative paths of the files under ``root`` (relative to ``top``)."""
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames.sort()
        for f in sorted(filenames):
            yield os.path.relpath(os.path.join(dirpath, f), top)


# ---------------------------------------------------------------------------------------------
# readers

GLTF_COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
GLTF_TYPES = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}


def read_glb(path):
    """``(gltf_json, [accessor arrays])`` of a binary glTF file (container parsed by hand).

    Deliberately not ``autobones.io.gltf.read_glb``: the checker must not share code with the
    writer it checks, and must read files written by any version of autobones."""
    with open(path, "rb") as fh:
        b = fh.read()
    magic, version, length = struct.unpack_from("<III", b, 0)
    if magic != 0x46546C67:
        raise ValueError(f"{path}: not a GLB file")
    pos, doc, bin_chunk = 12, None, b""
    while pos + 8 <= min(length, len(b)):
        clen, ctype = struct.unpack_from("<II", b, pos)
        chunk = b[pos + 8:pos + 8 + clen]
        if ctype == 0x4E4F534A:
            doc = json.loads(chunk.decode("utf-8"))
        elif ctype == 0x004E4942:
            bin_chunk = chunk
        pos += 8 + clen
    arrays = []
    for acc in doc.get("accessors", []):
        dt = np.dtype(GLTF_COMPONENTS[acc["componentType"]]).newbyteorder("<")
        k, n = GLTF_TYPES[acc["type"]], acc["count"]
        a = np.zeros((n, k), dtype=dt)
        if "bufferView" in acc:
            bv = doc["bufferViews"][acc["bufferView"]]
            if bv.get("buffer", 0) != 0:
                raise ValueError(f"{path}: external buffers are not supported")
            start = bv.get("byteOffset", 0) + acc.get("byteOffset", 0)
            stride = bv.get("byteStride") or k * dt.itemsize
            if stride == k * dt.itemsize:
                a = np.frombuffer(bin_chunk, dtype=dt, count=n * k, offset=start).reshape(n, k).copy()
            else:
                rows = [np.frombuffer(bin_chunk, dtype=dt, count=k, offset=start + i * stride) for i in range(n)]
                a = np.array(rows, dtype=dt).reshape(n, k)
        if "sparse" in acc:
            sp = acc["sparse"]
            ibv, vbv = doc["bufferViews"][sp["indices"]["bufferView"]], doc["bufferViews"][sp["values"]["bufferView"]]
            idt = np.dtype(GLTF_COMPONENTS[sp["indices"]["componentType"]]).newbyteorder("<")
            idx = np.frombuffer(bin_chunk, dtype=idt, count=sp["count"],
                                offset=ibv.get("byteOffset", 0) + sp["indices"].get("byteOffset", 0))
            val = np.frombuffer(bin_chunk, dtype=dt, count=sp["count"] * k,
                                offset=vbv.get("byteOffset", 0) + sp["values"].get("byteOffset", 0))
            a[idx.astype(np.int64)] = val.reshape(-1, k)
        arrays.append(a)
    return doc, arrays


def glb_positions(path):
    doc, arrays = read_glb(path)
    for mesh in doc.get("meshes", []):
        for prim in mesh.get("primitives", []):
            if "POSITION" in prim.get("attributes", {}):
                return arrays[prim["attributes"]["POSITION"]].astype(np.float64)
    return None


def read_obj(path):
    """``(v (n, 3) float64, f list of int tuples)``: numbers only, comments and other lines ignored."""
    V, F = [], []
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            if line.startswith("v "):
                V.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                F.append(tuple(int(t.split("/")[0]) for t in line.split()[1:]))
    return np.array(V, dtype=np.float64).reshape(-1, 3), F


def mesh_vertices(path):
    ext = os.path.splitext(path)[1].lower()
    if ext == ".obj":
        return read_obj(path)[0]
    if ext == ".glb":
        return glb_positions(path)
    if ext == ".npz":
        with np.load(path, allow_pickle=False) as z:
            return z["vertices"].astype(np.float64) if "vertices" in z.files else None
    return None


def bbox_diagonal(V):
    if V is None or len(V) == 0:
        return None
    V = np.asarray(V, dtype=np.float64)
    return float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))


# ---------------------------------------------------------------------------------------------
# comparison

class Diff:
    """What a comparison found: arrays compared, bit identity, max abs difference, problems."""

    def __init__(self):
        self.n = 0
        self.identical = True
        self.max_abs = 0.0
        self.problems = []  # (where, what, abs difference or inf)
        self.ignored = set()

    def numbers(self, where, a, b):
        """Compare two numeric arrays (any dtype)."""
        self.n += 1
        a, b = np.asarray(a), np.asarray(b)
        if a.shape != b.shape:
            return self.structure(where, f"shape {a.shape} vs {b.shape}")
        if a.dtype != b.dtype:
            # a dtype change is structural for arrays read from binary files (glb, npz)
            if not (a.dtype.kind in "biuf" and b.dtype.kind in "biuf" and where.startswith("json")):
                return self.structure(where, f"dtype {a.dtype} vs {b.dtype}")
        if a.dtype.kind not in "biufc" or b.dtype.kind not in "biufc":
            if not np.array_equal(a, b):
                return self.structure(where, "values differ (non-numeric)")
            return
        if a.dtype == b.dtype and a.tobytes() == b.tobytes():
            return
        self.identical = False
        fa, fb = a.astype(np.float64), b.astype(np.float64)
        nan_a, nan_b = np.isnan(fa), np.isnan(fb)
        if (nan_a != nan_b).any():
            return self.structure(where, f"NaN at {int((nan_a != nan_b).sum())} different places")
        inf_mismatch = np.isinf(fa) | np.isinf(fb)
        if (fa[inf_mismatch] != fb[inf_mismatch]).any():
            return self.structure(where, "infinite values differ")
        ok = ~(nan_a | inf_mismatch)
        d = np.abs(fa[ok] - fb[ok])
        m = float(d.max()) if d.size else 0.0
        if m > 0:
            i = int(np.argmax(np.where(ok, np.abs(np.nan_to_num(fa - fb, nan=0.0, posinf=0.0, neginf=0.0)), -1)))
            self.problems.append((where, f"max |diff| {m:.3g} at flat index {i} of {a.size}", m))
        elif a.dtype == b.dtype:
            self.problems.append((where, "equal values, different bits (e.g. -0.0 vs 0.0)", 0.0))
        else:
            self.problems.append((where, f"equal values, dtype {a.dtype} vs {b.dtype}", 0.0))
        self.max_abs = max(self.max_abs, m)

    def structure(self, where, what):
        self.identical = False
        self.max_abs = math.inf
        self.problems.append((where, what, math.inf))


def _numeric_list(x):
    """A (nested) list of numbers (not bools) of a regular shape -> float/int array, else None."""
    if not isinstance(x, list) or not x:
        return None
    try:
        a = np.array(x)
    except (ValueError, TypeError):
        return None
    if a.dtype == object or a.dtype.kind not in "if":
        return None
    # np.array turns [1, True] into ints; require genuine numbers
    flat = x
    while flat and isinstance(flat[0], list):
        flat = [y for z in flat for y in z]
    if any(isinstance(y, bool) or not isinstance(y, (int, float)) for y in flat):
        return None
    return a


def compare_json(a, b, diff, where, roots):
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            w = f"{where}.{k}"
            if k in IGNORED_KEYS:
                diff.ignored.add(k)
                continue
            if k not in a or k not in b:
                diff.structure(w, "key only in " + ("new" if k not in a else "old"))
                continue
            compare_json(a[k], b[k], diff, w, roots)
        return
    if isinstance(a, list) and isinstance(b, list):
        na, nb = _numeric_list(a), _numeric_list(b)
        if na is not None and nb is not None:
            diff.numbers(where, na, nb)
            return
        if len(a) != len(b):
            diff.structure(where, f"list length {len(a)} vs {len(b)}")
            return
        for i, (x, y) in enumerate(zip(a, b)):
            compare_json(x, y, diff, f"{where}[{i}]", roots)
        return
    if isinstance(a, bool) or isinstance(b, bool) or a is None or b is None:
        if a is not b and a != b or type(a) is not type(b):
            diff.structure(where, f"{a!r} vs {b!r}")
        return
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        diff.numbers(where, np.array([a]), np.array([b]))
        return
    if isinstance(a, str) and isinstance(b, str):
        if a == b:
            return
        if os.path.isabs(a) and os.path.isabs(b):
            ra, rb = _under(a, roots[0]), _under(b, roots[1])
            if ra is not None and rb is not None:
                if ra != rb:
                    diff.structure(where, f"path {ra!r} vs {rb!r} (inside the snapshots)")
                return
            diff.ignored.add("absolute paths")
            return
        diff.structure(where, f"{a[:60]!r} vs {b[:60]!r}")
        return
    diff.structure(where, f"type {type(a).__name__} vs {type(b).__name__}")


def _under(p, root):
    p, root = os.path.realpath(p), os.path.realpath(root)
    return os.path.relpath(p, root) if os.path.commonpath([p, root]) == root else None


def compare_file(kind, pa, pb, roots):
    diff = Diff()
    if kind == "glb":
        da, aa = read_glb(pa)
        db, ab = read_glb(pb)
        if len(aa) != len(ab):
            diff.structure("accessors", f"{len(aa)} vs {len(ab)} accessors")
        na, nb = _accessor_names(da, len(aa)), _accessor_names(db, len(ab))
        # pair accessors by what they hold (POSITION, indices, a morph target...) when that is
        # unambiguous, so two writers that order their accessors differently still compare
        by_name = sorted(na) == sorted(nb) and len(set(na)) == len(na)
        pairs = [(i, nb.index(n)) for i, n in enumerate(na)] if by_name else list(zip(range(len(aa)), range(len(ab))))
        for i, j in pairs:
            diff.numbers(f"accessor[{i}] {na[i]}", aa[i], ab[j])
        ja, jb = _glb_json_for_compare(da, na if by_name else None), _glb_json_for_compare(db, nb if by_name else None)
        n = diff.n
        compare_json(ja, jb, diff, "json", roots)
        diff.n = n + 1  # the glTF JSON (nodes, skins, morph target names...) counts as one item
    elif kind == "json":
        with open(pa, encoding="utf-8") as fh:
            ja = json.load(fh)
        with open(pb, encoding="utf-8") as fh:
            jb = json.load(fh)
        compare_json(ja, jb, diff, "json", roots)
    elif kind == "npz":
        with np.load(pa, allow_pickle=False) as za, np.load(pb, allow_pickle=False) as zb:
            for k in sorted(set(za.files) | set(zb.files)):
                if k not in za.files or k not in zb.files:
                    diff.structure(k, "array only in " + ("new" if k not in za.files else "old"))
                    continue
                diff.numbers(k, za[k], zb[k])
    elif kind == "obj":
        va, fa = read_obj(pa)
        vb, fb = read_obj(pb)
        diff.numbers("v", va, vb)
        diff.n += 1
        if fa != fb:
            diff.structure("f", f"faces differ ({len(fa)} vs {len(fb)} faces)")
        diff.ignored.add("obj comments")
    else:
        diff.n = 1
        with open(pa, "rb") as fh:
            ba = fh.read()
        with open(pb, "rb") as fh:
            bb = fh.read()
        if ba != bb:
            diff.structure("bytes", f"bytes differ ({len(ba)} vs {len(bb)} bytes)")
    return diff


def _accessor_name(doc, i):
    for mesh in doc.get("meshes", []):
        for prim in mesh.get("primitives", []):
            for k, v in prim.get("attributes", {}).items():
                if v == i:
                    return k
            if prim.get("indices") == i:
                return "indices"
            names = mesh.get("extras", {}).get("targetNames", [])
            for t, target in enumerate(prim.get("targets", [])):
                for k, v in target.get("attributes", target).items():
                    if v == i:
                        return f"target {names[t] if t < len(names) else t} {k}"
    for s in doc.get("skins", []):
        if s.get("inverseBindMatrices") == i:
            return "inverseBindMatrices"
    return ""


def _accessor_names(doc, n):
    """What each of the ``n`` accessors holds (``#i`` where the glTF JSON does not say)."""
    return [_accessor_name(doc, i) or f"#{i}" for i in range(n)]


def _glb_json_for_compare(doc, names=None):
    """The glTF JSON without byte layout; with ``names``, accessor indices replaced by what they hold."""
    d = json.loads(json.dumps({k: v for k, v in doc.items() if k not in GLB_LAYOUT_KEYS}))
    accessors = [{k: v for k, v in a.items() if k not in GLB_ACCESSOR_LAYOUT_KEYS} for a in doc.get("accessors", [])]
    if names is None:
        d["accessors"] = accessors
    else:
        d["accessors"] = dict(zip(names, accessors))
        for mesh in d.get("meshes", []):
            for prim in mesh.get("primitives", []):
                prim["attributes"] = {k: names[v] for k, v in prim.get("attributes", {}).items()}
                if "indices" in prim:
                    prim["indices"] = names[prim["indices"]]
                for target in prim.get("targets", []):
                    for k in list(target):
                        target[k] = names[target[k]]
        for skin in d.get("skins", []):
            if "inverseBindMatrices" in skin:
                skin["inverseBindMatrices"] = names[skin["inverseBindMatrices"]]
    if isinstance(d.get("asset"), dict):
        d["asset"] = {k: v for k, v in d["asset"].items() if k != "generator"}
    return d


def file_kind(rel):
    low = rel.lower()
    for ext, kind in ((".glb", "glb"), (".json", "json"), (".npz", "npz"), (".obj", "obj")):
        if low.endswith(ext):
            return kind
    return "bytes"


def _load_jobs(root):
    p = os.path.join(root, "jobs.json")
    if not os.path.exists(p):
        return {}
    with open(p, encoding="utf-8") as fh:
        return {j["name"]: j for j in json.load(fh)["jobs"]}


def _head_size(rel, root, jobs, cache):
    """Bounding-box diagonal of the job's input mesh, else of this file's vertices, else a sibling's."""
    job = rel.split(os.sep)[0]
    head = jobs.get(job, {}).get("head")
    candidates = []
    if head:
        candidates.append(head if os.path.isabs(head) else os.path.join(root, job, head))
    path = os.path.join(root, rel)
    candidates.append(path)
    stem = path
    for suffix in (".rig.json", ".weights.npz", ".landmarks.json", ".glb", ".obj", ".npz", ".json"):
        if stem.lower().endswith(suffix):
            stem = stem[:-len(suffix)]
            break
    candidates += [stem + ".glb", stem + ".weights.npz", stem + ".obj", os.path.join(os.path.dirname(path), "mesh.obj")]
    for c in candidates:
        if c in cache:
            if cache[c] is not None:
                return cache[c], c
            continue
        size = None
        if os.path.isfile(c):
            try:
                size = bbox_diagonal(mesh_vertices(c))
            except Exception:  # noqa: BLE001 - a file we cannot read gives no size; the next candidate may
                size = None
        cache[c] = size
        if size:
            return size, c
    return None, None


def cmd_compare(args):
    old, new = os.path.abspath(args.old), os.path.abspath(args.new)
    files = set()
    for root in (old, new):
        for top in sorted(os.listdir(root)):
            if top in SKIP_TOP:
                continue
            p = os.path.join(root, top)
            files.update(_files(p, root) if os.path.isdir(p) else [top])
    jobs_old, jobs_new = _load_jobs(old), _load_jobs(new)
    rows, offenders, ignored, cache = [], [], set(), {}
    sizes = {rel: _head_size(rel, old if os.path.exists(os.path.join(old, rel)) else new, jobs_old or jobs_new,
                             cache)[0] for rel in files}
    job_size = {}
    for rel, size in sizes.items():
        job = rel.split(os.sep)[0]
        if size:
            job_size[job] = max(job_size.get(job, 0.0), size)
    for rel in sorted(files):
        kind = file_kind(rel)
        pa, pb = os.path.join(old, rel), os.path.join(new, rel)
        size = sizes[rel] or job_size.get(rel.split(os.sep)[0])  # e.g. batch_report.json: the job's largest head
        if not os.path.exists(pa) or not os.path.exists(pb):
            where = "old" if os.path.exists(pa) else "new"
            rows.append((rel, kind, 0, "no", "missing", "inf", size))
            offenders.append((rel, f"only in {where}", []))
            continue
        try:
            d = compare_file(kind, pa, pb, (old, new))
        except Exception as exc:  # noqa: BLE001 - an unreadable file is an offender, the rest goes on
            rows.append((rel, kind, 0, "no", "error", "inf", size))
            offenders.append((rel, f"could not compare: {type(exc).__name__}: {exc}", []))
            continue
        ignored |= d.ignored
        rel_diff = d.max_abs / size if size else (0.0 if d.max_abs == 0 else math.inf)
        rows.append((rel, kind, d.n, "yes" if d.identical else "no", f"{d.max_abs:.3g}", f"{rel_diff:.3g}", size))
        if rel_diff > args.tol or math.isinf(d.max_abs):
            offenders.append((rel, f"max |diff| {d.max_abs:.3g} = {rel_diff:.3g} of head size {size}", d.problems))
        elif not d.identical and args.verbose:
            offenders_note = "; ".join(f"{w}: {what}" for w, what, _ in d.problems[:3])
            print(f"note: {rel} within tolerance but not bit-identical: {offenders_note}")
    # exit codes of the jobs
    for name in sorted(set(jobs_old) | set(jobs_new)):
        ra, rb = jobs_old.get(name, {}).get("exit_code", "missing"), jobs_new.get(name, {}).get("exit_code", "missing")
        if ra != rb:
            offenders.append((f"jobs.json:{name}", f"exit code {ra} (old) vs {rb} (new)", []))

    w = max([len(r[0]) for r in rows] + [4])
    print(f"{'file':{w}s}  {'kind':5s} {'n':>5s}  {'bit-identical':13s} {'max abs diff':>12s} {'/ head size':>11s}"
          f"  {'head size':>10s}")
    for rel, kind, n, ident, m, r, size in rows:
        print(f"{rel:{w}s}  {kind:5s} {n:5d}  {ident:13s} {m:>12s} {r:>11s}  "
              f"{(f'{size:.4g}' if size else '?'):>10s}")
    n_ident = sum(r[3] == "yes" for r in rows)
    print(f"\n{len(rows)} files, {n_ident} bit-identical, {sum(r[2] for r in rows)} arrays compared; "
          f"tolerance {args.tol:g} of the head size")
    print("ignored as run-dependent: keys " + ", ".join(sorted(IGNORED_KEYS)) + "; glb byte layout (bufferViews, "
          "buffers, accessor bufferView/byteOffset) and asset.generator; absolute paths outside the snapshots; "
          "obj comments" + (f" (seen here: {', '.join(sorted(ignored))})" if ignored else ""))
    if offenders:
        print(f"\nOFFENDERS ({len(offenders)}):")
        for rel, why, problems in offenders:
            print(f"  {rel}: {why}")
            for where, what, _ in problems[:args.max_details]:
                print(f"      {where}: {what}")
            if len(problems) > args.max_details:
                print(f"      ... {len(problems) - args.max_details} more")
        return 1
    print("everything agrees")
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(description="Snapshot the autobones CLI's outputs on the shared heads; compare two "
                                             "snapshots (see the module docstring).")
    sub = ap.add_subparsers(dest="mode", required=True)
    r = sub.add_parser("run", help="run the jobs, write every output under OUTDIR")
    r.add_argument("outdir", metavar="OUTDIR")
    r.add_argument("--cli", default="autobones", help='command prefix of the CLI (default "autobones")')
    r.add_argument("--expect-src", metavar="DIR", help="stop unless autobones is imported from under DIR")
    r.add_argument("--data", default=DEFAULT_DATA, help=f"shared heads folder (default {DEFAULT_DATA})")
    r.add_argument("--ref", default=DEFAULT_REF,
                   help=f"frozen reference tree for the goat/robot landmark files and the default head of build-rig "
                        f"(default {DEFAULT_REF})")
    r.add_argument("--only", metavar="NAMES", help="comma-separated job names to run (default: all)")
    r.add_argument("--timeout", type=float, default=1800, help="seconds per job (default 1800)")
    c = sub.add_parser("compare", help="compare two snapshots")
    c.add_argument("old", metavar="OLD_DIR")
    c.add_argument("new", metavar="NEW_DIR")
    c.add_argument("--tol", type=float, default=1e-10, help="allowed max difference / head size (default 1e-10)")
    c.add_argument("--max-details", type=int, default=8, help="problems listed per offending file (default 8)")
    c.add_argument("-v", "--verbose", action="store_true", help="also note files within tolerance but not identical")
    args = ap.parse_args(argv)
    return cmd_run(args) if args.mode == "run" else cmd_compare(args)


if __name__ == "__main__":
    sys.exit(main())
