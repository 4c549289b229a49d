"""``python tools/rig_snapshot.py compare OLD_DIR NEW_DIR``: compare two rig snapshots by content.

Every file under either snapshot (except jobs.json, provenance.json, _logs/, _inputs/) is
compared with its namesake, by content:

- ``.glb``: the GLB container is parsed (JSON chunk + BIN chunk); every accessor is read as a
  numpy array (dtype, shape, values) and paired with its namesake by what it holds (POSITION,
  indices, a morph target...) when that is unambiguous, else by index; the glTF JSON is
  compared recursively (nodes' names, translations, rotations, children, skins, meshes, morph
  target names in ``meshes[].extras.targetNames``, accessor count/type/min/max...) except the byte
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

Snapshots are written by ``python tools/rig_snapshot.py run`` (the folder layout and ``jobs.json``
are described there); the glb/obj readers are in ``snapshot_readers.py``.

Dependencies: numpy only.
"""
from __future__ import annotations

import json
import math
import os
import sys

import numpy as np

# tools/ is not a package: the readers are a sibling file, found through this folder
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from snapshot_readers import bbox_diagonal, mesh_vertices, read_glb, read_obj  # noqa: E402

SKIP_TOP = {"jobs.json", "provenance.json", "_logs", "_inputs"}
IGNORED_KEYS = {"time", "seconds", "timings", "finished", "started", "elapsed", "host", "pid",
                "autobones_version"}
GLB_LAYOUT_KEYS = {"bufferViews", "buffers"}
GLB_ACCESSOR_LAYOUT_KEYS = {"bufferView", "byteOffset"}


def files_under(root, top):
    """Relative paths of the files under ``root`` (relative to ``top``)."""
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames.sort()
        for f in sorted(filenames):
            yield os.path.relpath(os.path.join(dirpath, f), top)


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
    """Compare the snapshots ``args.old`` and ``args.new``: print the table and the offenders; exit code 0 or 1."""
    old, new = os.path.abspath(args.old), os.path.abspath(args.new)
    jobs_old, jobs_new = _load_jobs(old), _load_jobs(new)
    rows, offenders, ignored = _compare_files(old, new, jobs_old or jobs_new, args)
    # exit codes of the jobs
    for name in sorted(set(jobs_old) | set(jobs_new)):
        ra, rb = jobs_old.get(name, {}).get("exit_code", "missing"), jobs_new.get(name, {}).get("exit_code", "missing")
        if ra != rb:
            offenders.append((f"jobs.json:{name}", f"exit code {ra} (old) vs {rb} (new)", []))
    return _report(rows, offenders, ignored, args)


def _snapshot_files(old, new):
    """Relative paths of the files of either snapshot, except SKIP_TOP (jobs.json, provenance.json, _logs, _inputs)."""
    files = set()
    for root in (old, new):
        for top in sorted(os.listdir(root)):
            if top in SKIP_TOP:
                continue
            p = os.path.join(root, top)
            files.update(files_under(p, root) if os.path.isdir(p) else [top])
    return files


def _compare_files(old, new, jobs, args):
    """``(rows, offenders, ignored)``: one table row per file, the files out of tolerance, what was ignored."""
    files = _snapshot_files(old, new)
    rows, offenders, ignored, cache = [], [], set(), {}
    sizes = {rel: _head_size(rel, old if os.path.exists(os.path.join(old, rel)) else new, jobs,
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
    return rows, offenders, ignored


def _report(rows, offenders, ignored, args):
    """Print the table, the totals and the offenders; exit code 1 when there are offenders, else 0."""
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
