"""Automatic landmarks (issue #7): accuracy, invariance, transfer with them, time, heads with no face.

Run by hand, not by the tests::

    python benchmarks/landmarks.py            # everything, ~5 minutes on 2 cores
    python benchmarks/landmarks.py --quick    # 3 heads, 4 orientations, 2 transfer pairs
    python benchmarks/landmarks.py --time [--baseline REV]   # issue #14: seconds per head, ~4 minutes
    /tmp/dlibvenv/bin/python benchmarks/landmarks.py --dlib   # + dlib's 68-point predictor

Data: ``../shared/data``: ICT ``generic_neutral_mesh`` and ``identity000..002``
(26,719 vertices, centimetres, +Y up, facing +Z), menpo3d ``template.ply``
(53,349 vertices, arbitrary ~2e5 units) and ``james.obj`` (6,393 vertices, a
scan), each with the 27 iBUG-derived contract landmarks the source published
(``NAME.landmarks.json``). Goat, koala and robot (``misc/``) have no human face.

Method: :class:`autobones.landmarks.detect.LandmarkDetector` on the mesh as loaded, its
frame from :func:`autobones.orient.detect_frame` (found once per head and shared by
every configuration). Configurations measured in the same run:

- ``default``: 5 views (front, +-30 yaw, +-15 pitch), geometric refinement;
- ``front only``: ``views=((0, 0),)``; ``no refine``: ``refine=False``;
  ``front, no refine``: both (the bare 2-D detector lifted to the surface);
- with ``--dlib``: the same pipeline with dlib's HOG face detector (CNN/MMOD
  fallback when HOG finds nothing) and its 68-point shape predictor from
  ``face-recognition-models`` (:class:`Dlib68` below; contract names from the
  iBUG-68 table :data:`autobones.io.landmarks.IBUG68`), default and front only.

Metric: error of a detected name = distance to the published point / the
published outer-eye-corner distance (exocanthion_l - exocanthion_r), in %, over
the names present in both (dropped names are listed, not scored). Targets
(issue #7): mean <= 3 % (pooled over heads and names) and every name <= 8 %
(read as: each name's mean over the heads; single head x name errors above 8 %
are counted too).

Invariance: ICT ``generic_neutral_mesh`` in each of the 24 proper axis-aligned
rotations and scaled x1000, through :func:`autobones.detect_landmarks`
(orientation found automatically); its landmarks mapped back to the original
frame vs the unrotated unscaled run, in % of ex-ex. Plus ``identity001`` in
millimetres facing -X (must come back with no flag and no drop). Also, beyond
the issue, a few arbitrary rotations (the frame is then estimated, not permuted).

Transfer: as ``benchmarks/transfer.py``: for each ordered ICT pair (A, B) a
labelled rig is placed on A (with A's published landmarks) and carried onto B
with ``autobones.transfer`` three times: with the published landmarks of both
(the reference), with ``landmarks=None`` (the pipeline's automatic landmarks: the
detector runs on B and on the rig's own skin, so its biases cancel), and with B's
detected landmarks (``default``) against A's published ones. Correspondence
error = generic vertex i's point on B vs B's vertex i, % of B's published ex-ex,
mean over all vertices (and over the skin, the largest part). Target: automatic
within 0.3 % (of ex-ex) of published.

Time: wall seconds per head for ``default`` (the detector model is loaded by a
warm-up call first, its time printed apart), split into frame (orientation),
render (rasterise + shade + surface points), 2-D (the detector on the pictures),
refine, and other (lift, combine, snap). Target: <= 3 s for a 30k-vertex head on
this 2-core machine. No timing is asserted.

``--assist [--variants as-is,rot1,x1000,dec5k] [--heads A,B] [--detected]`` (issue #35): assisted landmarks,
five names given from each landmarked head's file and the rest proposed (:mod:`landmarks_assist`);
``--detected``: on a human face the detector's names replace the fit's, as ``landmarks --assist`` does.
``--refit [--variants ...]`` (issue #35 part 3): the detected landmarks of the human heads against the
generic head's fit from them, read off with a calibration held out by source family (measured; not shipped).

``--time`` (issue #14: <= 1.5 s per head after the model load): ``autobones.detect_landmarks``
(orientation included) on the six heads above, LeePerrySmith, demosthenes and demosthenes
Loop-subdivided twice (133,887 vertices, a bust scan's density), median of three calls per head
in a fresh process after a warm-up call. With ``--baseline REV`` the same worker runs on
commit REV's code (``git archive``, laid out as installed) in alternation with this checkout's,
twice each, so both are measured in the same minutes on the same host; the ratio is per head.
"""
from __future__ import annotations

import argparse
import contextlib
import importlib.metadata
import itertools
import os
import platform
import subprocess
import time
from pathlib import Path

import numpy as np

import autobones
import autobones.landmarks.detect as detect_mod
from autobones.landmarks.detect import LandmarkDetector
from autobones.errors import AutobonesError
from autobones.io.landmarks import IBUG68, NAMES, read_landmarks
from autobones.io.mesh import load_mesh
from autobones.orient import detect_frame

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
HEADS = {  # name: (mesh, published landmarks), relative to DATA
    "ict neutral": ("ict/generic_neutral_mesh.obj", "ict/generic_neutral_mesh.landmarks.json"),
    "ict identity000": ("ict/identity000.obj", "ict/identity000.landmarks.json"),
    "ict identity001": ("ict/identity001.obj", "ict/identity001.landmarks.json"),
    "ict identity002": ("ict/identity002.obj", "ict/identity002.landmarks.json"),
    "menpo3d template": ("menpo3d/template.ply", "menpo3d/template.landmarks.json"),
    "menpo3d james": ("menpo3d/james.obj", "menpo3d/james.landmarks.json"),
}
QUICK_HEADS = ["ict neutral", "ict identity001", "menpo3d james"]
ICT = ["ict neutral", "ict identity000", "ict identity001", "ict identity002"]
NO_FACE = {"goat": "misc/goathead.obj", "koala": "misc/koala_low_resolution.obj",
           "robot": "misc/robot_head_neutral.obj"}
FRONT = ((0.0, 0.0),)


# ---------------------------------------------------------------------------
# dlib's 68-point predictor, as a detector for the same pipeline


class Dlib68:
    """dlib's 68-point shape predictor as a detector: image (H, W, 3) uint8 -> (68, 2) pixels or None.

    The face box comes from dlib's HOG frontal face detector (upsampled once); when it
    finds nothing, from the CNN (MMOD) detector. Both models and the predictor come from
    ``face-recognition-models``. ``points`` is the contract's iBUG-68 table (palpebrale
    = mean of the two lid points, stomion = mean of 62 and 66). dlib's part positions are
    whole pixels (its pixel centres are at integers, as in :mod:`autobones.render`).
    """

    points = IBUG68

    def __init__(self, upsample=1):
        import dlib
        import face_recognition_models as models

        self.upsample = upsample
        self.hog = dlib.get_frontal_face_detector()
        self.cnn = dlib.cnn_face_detection_model_v1(models.cnn_face_detector_model_location())
        self.predictor = dlib.shape_predictor(models.pose_predictor_model_location())
        self.calls = {"hog": 0, "cnn": 0, "none": 0}

    def __call__(self, image):
        image = np.ascontiguousarray(image)
        rects = list(self.hog(image, self.upsample))
        if rects:
            self.calls["hog"] += 1
        else:
            rects = [d.rect for d in self.cnn(image, self.upsample)]
            self.calls["cnn" if rects else "none"] += 1
        if not rects:
            return None
        box = max(rects, key=lambda r: r.width() * r.height())
        shape = self.predictor(image, box)
        return np.array([[p.x, p.y] for p in shape.parts()], dtype=np.float64)


# ---------------------------------------------------------------------------
# instrumentation: time the stages of LandmarkDetector.detect without changing it


class Clock:
    """Seconds per stage, added up by the wrapped functions."""

    def __init__(self):
        self.t = {"render": 0.0, "2-D": 0.0, "refine": 0.0}

    def wrap(self, key, fn):
        def timed(*a, **k):
            t0 = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                self.t[key] += time.perf_counter() - t0
        return timed


@contextlib.contextmanager
def timed_stages(clock):
    """Wrap the rendering functions and ``refine`` that :mod:`autobones.landmarks.detect` looks up at call time."""
    saved = {k: getattr(detect_mod, k) for k in ("rasterize", "shade", "surface_points", "refine")}
    try:
        for k in ("rasterize", "shade", "surface_points"):
            setattr(detect_mod, k, clock.wrap("render", saved[k]))
        detect_mod.refine = clock.wrap("refine", saved["refine"])
        yield clock
    finally:
        for k, v in saved.items():
            setattr(detect_mod, k, v)


class TimedDetector:
    """A detector wrapper adding the time of its calls to ``clock.t['2-D']``."""

    def __init__(self, inner, clock):
        self.inner, self.clock, self.points = inner, clock, inner.points

    def __call__(self, image):
        t0 = time.perf_counter()
        try:
            return self.inner(image)
        finally:
            self.clock.t["2-D"] += time.perf_counter() - t0


# ---------------------------------------------------------------------------


def errors(found, truth):
    """name -> error in % of the published ex-ex, over names in both."""
    unit = np.linalg.norm(truth["exocanthion_l"] - truth["exocanthion_r"])
    return {n: 100 * float(np.linalg.norm(np.asarray(found[n]) - truth[n])) / unit
            for n in NAMES if n in found and n in truth}


def run_config(detector, mesh, frame, **options):
    clock = Clock()
    det = LandmarkDetector(detector=TimedDetector(detector, clock), **options)
    with timed_stages(clock):
        t0 = time.perf_counter()
        lm = det.detect(*mesh, frame=frame)
        total = time.perf_counter() - t0
    return lm, total, clock.t


def small(x):
    """A percentage, with an exponent when it rounds to zero."""
    return f"{x:.3f}" if x == 0 or x >= 5e-4 else f"{x:.1e}"


def fmt_names(d, limit=4):
    if not d:
        return "-"
    names = list(d)
    return ", ".join(names[:limit]) + (f" +{len(names) - limit}" if len(names) > limit else "")


def proper_rotations():
    """The 24 axis-aligned rotations (signed permutation matrices with det +1), identity first."""
    out = []
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1, -1), repeat=3):
            R = np.zeros((3, 3))
            R[range(3), perm] = signs
            if np.linalg.det(R) > 0:
                out.append(R)
    out.sort(key=lambda R: -np.trace(R))
    return out


def axis_name(R, canonical):
    """Input axis that canonical direction ``canonical`` (ICT frame) points along after ``R``."""
    v = R @ np.asarray(canonical, dtype=np.float64)
    i = int(np.argmax(np.abs(v)))
    return ("+" if v[i] > 0 else "-") + "xyz"[i]


def rig_on(V, F, lm):
    """As benchmarks/transfer.py: a sparse placed rig with a smooth field and 12 regions."""
    from sklearn.cluster import KMeans

    from autobones.labelled_rig import LabelledRig

    placed = autobones.place((V, F), density="sparse")
    fields = {"scalar": np.sin(V[:, 1] / 8) + 0.5 * np.cos(V[:, 0] / 6) + V[:, 2] / 20,
              "region": KMeans(12, n_init=2, random_state=0).fit_predict(V).astype(np.int64)}
    return LabelledRig(vertices=V, faces=F, landmarks=lm, skeleton=placed.skeleton, weights=placed.weights,
                       fields=fields, labels={"region": [f"r{i}" for i in range(12)]})


def version(pkg):
    try:
        return importlib.metadata.version(pkg)
    except importlib.metadata.PackageNotFoundError:
        return None


TIME_HEADS = {**{h: m for h, (m, _) in HEADS.items()}, "LeePerrySmith": "misc/LeePerrySmith.obj",
              "demosthenes": "misc/demosthenes-low-res.obj", "demosthenes loop x2": "misc/demosthenes-low-res.obj"}


def time_worker(paths):
    """In a fresh process: median of three ``detect_landmarks`` calls per mesh, after a warm-up call
    (the model load). Prints one JSON object, mesh path -> seconds."""
    import json

    meshes = {p: load_mesh(p) for p in paths}
    autobones.detect_landmarks(meshes[paths[0]])
    out = {"autobones": str(Path(autobones.__file__).parent)}
    for p, mesh in meshes.items():
        ts = []
        for _ in range(3):
            t0 = time.perf_counter()
            autobones.detect_landmarks(mesh)
            ts.append(time.perf_counter() - t0)
        out[p] = float(np.median(ts))
    print(json.dumps(out))


def baseline_tree(rev, tmp):
    """Commit ``rev``'s package laid out as installed (cli/ and generic_rig/ inside autobones/), under
    ``tmp``; returns the folder to put on PYTHONPATH."""
    import tarfile
    import io

    blob = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "autobones", "cli", "generic_rig"],
                          capture_output=True, check=True).stdout
    with tarfile.open(fileobj=io.BytesIO(blob)) as tar:
        tar.extractall(tmp, filter="data")
    for sub in ("cli", "generic_rig"):
        os.replace(os.path.join(tmp, sub), os.path.join(tmp, "autobones", sub))
    return tmp


def time_heads(baseline=None):
    """Issue #14's landmark timing table (see the module docstring)."""
    import json
    import sys
    import tempfile

    import trimesh

    with tempfile.TemporaryDirectory() as tmp:
        paths = {}
        for h, rel in TIME_HEADS.items():
            if h.endswith("loop x2"):
                V, F = load_mesh(DATA / rel)
                V, F = trimesh.remesh.subdivide_loop(V, F, iterations=2)
                paths[h] = os.path.join(tmp, "loop2.obj")
                trimesh.Trimesh(V, F, process=False).export(paths[h])
            else:
                paths[h] = str(DATA / rel)
        sizes = {h: len(load_mesh(p)[0]) for h, p in paths.items()}
        runs = {"this checkout": None}
        if baseline:
            runs[baseline] = baseline_tree(baseline, os.path.join(tmp, "base"))
        got = {k: [] for k in runs}
        for _ in range(2):
            for label, pypath in runs.items():
                env = dict(os.environ, **({"PYTHONPATH": pypath} if pypath else {}))
                proc = subprocess.run([sys.executable, __file__, "--time-worker", *paths.values()],
                                      capture_output=True, text=True, env=env, cwd=tmp)
                if proc.returncode:
                    raise SystemExit(f"{label}: {proc.stderr.strip().splitlines()[-1]}")
                out = json.loads(proc.stdout.strip().splitlines()[-1])
                where = out.pop("autobones")
                if pypath and not where.startswith(pypath):
                    raise SystemExit(f"the baseline worker imported autobones from {where}, not {pypath}")
                got[label].append(out)
    print(f"\n## Time per head, `detect_landmarks` with orientation, after the model load (median of 3 calls; "
          f"two fresh processes per code, alternating)\n")
    labels = list(runs)
    head = "| head | vertices | " + " | ".join(f"{l} s" for l in labels) + (" | ratio |" if baseline else "")
    print(head)
    print("|---|---:|" + "---:|" * len(labels) + ("---:|" if baseline else ""))
    for h, p in paths.items():
        secs = [min(r[p] for r in got[l]) for l in labels]
        ratio = f" | {secs[0] / secs[1]:.2f}x |" if baseline else ""
        print(f"| {h} | {sizes[h]:,} | " + " | ".join(f"{s:.2f}" for s in secs) + ratio)
    print("\n(each figure: the faster of the two processes' medians; target <= 1.5 s per head)")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="3 heads, 4 orientations, 2 transfer pairs")
    ap.add_argument("--dlib", action="store_true", help="also dlib's 68-point predictor (needs dlib-bin and "
                                                        "face-recognition-models)")
    ap.add_argument("--size", type=int, default=384, help="picture size of the detector (default 384, as LandmarkDetector)")
    ap.add_argument("--time", action="store_true", help="issue #14's timing table only (seconds per head)")
    ap.add_argument("--baseline", metavar="REV", help="with --time: also time commit REV in the same minutes")
    ap.add_argument("--time-worker", nargs="+", metavar="MESH", help=argparse.SUPPRESS)
    ap.add_argument("--assist", action="store_true", help="issue #35: assisted landmarks from 5 given names on every "
                                                          "landmarked head (benchmarks/landmarks_assist.py)")
    ap.add_argument("--variants", default="as-is", help="with --assist: comma-separated copies (as-is, rot1..rot6, "
                                                        "x1000, x0.001, dec5k, remesh)")
    ap.add_argument("--heads", help="with --assist: comma-separated head names (default: all)")
    ap.add_argument("--reading", default="held-out", choices=("held-out", "shipped", "own"),
                    help="with --assist: where names are read off the generic (see landmarks_assist.py)")
    ap.add_argument("--detected", action="store_true",
                    help="with --assist: as `landmarks --assist` does, the detector's names on a human face")
    ap.add_argument("--refit", action="store_true", help="issue #35 part 3: detected landmarks vs the generic's "
                                                         "fit from them, on the human heads (with --variants)")
    args = ap.parse_args(argv)
    if args.refit:
        import landmarks_assist

        t0 = time.perf_counter()
        landmarks_assist.refit_run(tuple(args.variants.split(",")))
        print(f"\ntotal wall time {time.perf_counter() - t0:.0f} s")
        return 0
    if args.assist:
        import landmarks_assist

        t0 = time.perf_counter()
        landmarks_assist.run(tuple(args.variants.split(",")), args.heads.split(",") if args.heads else None,
                             args.reading, detected="auto" if args.detected else None)
        print(f"\ntotal wall time {time.perf_counter() - t0:.0f} s")
        return 0
    if args.time_worker:
        return time_worker(args.time_worker)
    if args.time:
        return time_heads(args.baseline)
    wall0 = time.perf_counter()
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    # name the code measured: the commit, and whether the package imported differs from it
    if subprocess.run(["git", "-C", str(ROOT), "diff", "--quiet", "HEAD", "--", "autobones"]).returncode:
        commit += " + uncommitted changes under autobones/"
    if not Path(detect_mod.__file__).resolve().is_relative_to(ROOT):
        commit += f" (autobones imported from {Path(autobones.__file__).parent})"
    print(f"# autobones {commit}, mediapipe {version('mediapipe')}, dlib {version('dlib-bin') or version('dlib')}; "
          f"{platform.machine()} {platform.processor() or ''}, {os.cpu_count()} cores, Python {platform.python_version()}")
    heads = QUICK_HEADS if args.quick else list(HEADS)
    meshes = {h: load_mesh(DATA / HEADS[h][0]) for h in heads}
    truth = {h: read_landmarks(DATA / HEADS[h][1]) for h in heads}

    mediapipe = detect_mod.MediaPipeFaceMesh()
    t0 = time.perf_counter()
    LandmarkDetector(detector=mediapipe).detect(*meshes[heads[0]])
    print(f"warm-up (MediaPipe model load + one detection, discarded): {time.perf_counter() - t0:.2f} s")
    configs = [("default", mediapipe, {}), ("front only", mediapipe, {"views": FRONT}),
               ("no refine", mediapipe, {"refine": False}),
               ("front, no refine", mediapipe, {"views": FRONT, "refine": False})]
    dlib_det = None
    if args.dlib:
        try:
            dlib_det = Dlib68()
        except ImportError as exc:
            print(f"--dlib: cannot import dlib / face_recognition_models ({exc}); skipped")
        if dlib_det is not None:
            t0 = time.perf_counter()
            LandmarkDetector(detector=dlib_det).detect(*meshes[heads[0]])
            print(f"warm-up (dlib models load + one detection, discarded): {time.perf_counter() - t0:.2f} s")
            configs += [("dlib", dlib_det, {}), ("dlib front only", dlib_det, {"views": FRONT}),
                        ("dlib front, no refine", dlib_det, {"views": FRONT, "refine": False})]

    # ---- accuracy ----------------------------------------------------------
    res = {}       # (config, head) -> dict
    frames = {}
    for h in heads:
        t0 = time.perf_counter()
        frames[h] = detect_frame(*meshes[h])
        t_frame = time.perf_counter() - t0
        for cname, det, opts in configs:
            try:
                lm, total, st = run_config(det, meshes[h], frames[h], size=args.size, **opts)
            except AutobonesError as exc:
                res[cname, h] = {"failed": str(exc)}
                print(f"  {cname:22s} {h:17s} FAILED: {exc}", flush=True)
                continue
            e = errors(lm, truth[h])
            res[cname, h] = {"lm": lm, "err": e, "time": total, "stages": st, "frame": t_frame}
            worst = max(e, key=e.get)
            print(f"  {cname:22s} {h:17s} mean {np.mean(list(e.values())):5.2f}%  max {e[worst]:5.2f}% ({worst})  "
                  f"{len(e)} scored, dropped {fmt_names(lm.dropped)}, flagged {fmt_names(lm.flagged)}  "
                  f"{total:.2f} s", flush=True)

    def pooled(cname):
        rows = [res[cname, h] for h in heads if "err" in res.get((cname, h), {})]
        return [v for r in rows for v in r["err"].values()]

    def per_name(cname):
        out = {}
        for n in NAMES:
            v = [(res[cname, h]["err"][n], h) for h in heads
                 if "err" in res.get((cname, h), {}) and n in res[cname, h]["err"]]
            if v:
                out[n] = (np.mean([x for x, _ in v]), max(v), len(v))
        return out

    print("\n## Accuracy per head (default: 5 views, refinement; % of the published ex-ex)\n")
    print("| head | vertices | scored | mean % | max % (name) | dropped | flagged | frame s | render s | 2-D s "
          "| refine s | other s | detect s | frame + detect s |")
    print("|---|---:|---:|---:|---|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for h in heads:
        r = res["default", h]
        if "err" not in r:
            print(f"| {h} | {len(meshes[h][0]):,} | 0 | - | failed: {r['failed'][:60]} | | | | | | | | | |")
            continue
        e, st = r["err"], r["stages"]
        worst = max(e, key=e.get)
        other = r["time"] - sum(st.values())
        print(f"| {h} | {len(meshes[h][0]):,} | {len(e)} | {np.mean(list(e.values())):.2f} | {e[worst]:.2f} ({worst}) "
              f"| {fmt_names(r['lm'].dropped)} | {fmt_names(r['lm'].flagged)} | {r['frame']:.2f} | {st['render']:.2f} "
              f"| {st['2-D']:.2f} | {st['refine']:.2f} | {other:.2f} | {r['time']:.2f} | {r['frame'] + r['time']:.2f} |")

    names_table = {c: per_name(c) for c, _, _ in configs}
    cols = [c for c, _, _ in configs]
    print("\n## Accuracy per name (mean over heads, % of ex-ex; default also max over heads)\n")
    nheads = {c: sum("err" in res[c, h] for h in heads) for c in cols}
    print("| name | heads | default mean | default max (head) | " + " | ".join(
        f"{c} mean" + (f" ({nheads[c]} of {len(heads)} heads)" if nheads[c] < len(heads) else "") for c in cols[1:]) + " |")
    print("|---|---:|---:|---|" + "---:|" * (len(cols) - 1))
    for n in NAMES:
        if n not in names_table["default"]:
            continue
        m, (mx, mh), k = names_table["default"][n]
        rest = " | ".join(f"{names_table[c][n][0]:.2f}" if n in names_table[c] else "-" for c in cols[1:])
        print(f"| {n} | {k} | {m:.2f} | {mx:.2f} ({mh}) | {rest} |")

    print("\n## Accuracy per configuration (same run)\n")
    print("| configuration | " + " | ".join(heads) + " | heads | pooled mean % | ratio to default (same heads) "
          "| worst name (mean) | head x name > 8 % | dropped (total) | flagged (total) | median s | mean <= 3 % "
          "| every name <= 8 % |")
    print("|---|" + "---:|" * len(heads) + "---:|---:|---:|---|---:|---:|---:|---:|---|---|")
    for c in cols:
        pm = pooled(c)
        if not pm:
            print(f"| {c} | " + " | ".join("fail" for _ in heads) + " | 0 | - | - | - | - | - | - | - | - | - |")
            continue
        pn = names_table[c]
        wn = max(pn, key=lambda n: pn[n][0])
        per_head = " | ".join(f"{np.mean(list(res[c, h]['err'].values())):.2f}" if "err" in res[c, h] else "fail"
                              for h in heads)
        ok = [res[c, h] for h in heads if "err" in res[c, h]]
        same = [h for h in heads if "err" in res[c, h] and "err" in res["default", h]]
        base = np.mean([v for h in same for v in res["default", h]["err"].values()]) if same else np.nan
        mine = np.mean([v for h in same for v in res[c, h]["err"].values()]) if same else np.nan
        drop = sum(len(r["lm"].dropped) for r in ok)
        flag = sum(len(r["lm"].flagged) for r in ok)
        secs = np.median([r["time"] for r in ok])
        every = all(v[0] <= 8.0 for v in pn.values())
        print(f"| {c} | {per_head} | {len(ok)} | {np.mean(pm):.2f} | {mine / base:.2f} | {wn} {pn[wn][0]:.2f} "
              f"| {sum(v > 8 for v in pm)} of {len(pm)} | {drop} | {flag} | {secs:.2f} "
              f"| {'MET' if np.mean(pm) <= 3 else 'NOT MET'} ({np.mean(pm):.2f}) "
              f"| {'MET' if every else 'NOT MET'} (worst {pn[wn][0]:.2f}) |")
    if dlib_det is not None:
        print(f"\n(dlib face boxes: {dlib_det.calls['hog']} pictures by HOG, {dlib_det.calls['cnn']} by the CNN "
              f"fallback, {dlib_det.calls['none']} with no face)")

    # ---- invariance --------------------------------------------------------
    V0, F0 = load_mesh(DATA / HEADS["ict neutral"][0])
    ref = autobones.detect_landmarks((V0, F0))
    unit = np.linalg.norm(read_landmarks(DATA / HEADS["ict neutral"][1])["exocanthion_l"]
                          - read_landmarks(DATA / HEADS["ict neutral"][1])["exocanthion_r"])
    rots = proper_rotations()
    if args.quick:
        rots = [rots[i] for i in (0, 5, 11, 17)]
    print(f"\n## Invariance: ICT neutral rotated (24 proper axis-aligned rotations{' - quick: 4' if args.quick else ''}) "
          f"and scaled x1000, mapped back, vs the unrotated unit-scale run (% of ex-ex)\n")
    print("| # | up | front | found up | found front | names | mean % | max % (name) | dropped | flagged | s |")
    print("|---:|---|---|---|---|---:|---:|---|---|---|---:|")
    diffs, bad = [], 0
    for i, R in enumerate(rots):
        V = 1000.0 * V0 @ R.T
        t0 = time.perf_counter()
        try:
            lm = autobones.detect_landmarks((V, F0))
        except AutobonesError as exc:
            print(f"| {i + 1} | {axis_name(R, (0, 1, 0))} | {axis_name(R, (0, 0, 1))} | - | - | 0 | - | "
                  f"failed: {str(exc)[:50]} | | | |")
            bad += 1
            continue
        secs = time.perf_counter() - t0
        back = {n: (np.asarray(p) / 1000.0) @ R for n, p in lm.items()}
        d = {n: 100 * float(np.linalg.norm(back[n] - ref[n])) / unit for n in ref if n in back}
        diffs += list(d.values())
        worst = max(d, key=d.get)
        same = set(ref) == set(lm)
        bad += not same or d[worst] > 1.0
        print(f"| {i + 1} | {axis_name(R, (0, 1, 0))} | {axis_name(R, (0, 0, 1))} | {lm.frame.up} | "
              f"{lm.frame.front} | {len(d)}{'' if same else ' (differs)'} | {small(np.mean(list(d.values())))} | "
              f"{small(d[worst])} ({worst}) | {fmt_names(lm.dropped)} | {fmt_names(lm.flagged)} | {secs:.2f} |",
              flush=True)
    if diffs:
        print(f"\nover {len(rots)} orientations: mean difference {small(np.mean(diffs))} %, max {small(np.max(diffs))} % "
              f"of ex-ex; orientations with a different name set or a difference > 1 %: {bad}")

    # not asked by the issue: rotations off the axes, where the frame finder's estimate (not a
    # permutation of the same numbers) decides what the pictures show
    from scipy.spatial.transform import Rotation

    turns = Rotation.random(2 if args.quick else 4, random_state=0).as_matrix()
    print("\narbitrary rotations (scipy Rotation.random, seed 0), x1000: ", end="")
    out = []
    for R in turns:
        try:
            lm = autobones.detect_landmarks((1000.0 * V0 @ R.T, F0))
        except AutobonesError as exc:
            out.append(f"failed ({str(exc)[:40]})")
            continue
        back = {n: (np.asarray(p) / 1000.0) @ R for n, p in lm.items()}
        d = {n: 100 * float(np.linalg.norm(back[n] - ref[n])) / unit for n in ref if n in back}
        worst = max(d, key=d.get)
        out.append(f"{np.mean(list(d.values())):.2f} % mean, {d[worst]:.2f} % max ({worst}), {len(d)} names, "
                   f"{len(lm.flagged)} flagged")
    print("; ".join(out))

    # a head in millimetres facing -X
    Vi, Fi = load_mesh(DATA / HEADS["ict identity001"][0])
    Ti = read_landmarks(DATA / HEADS["ict identity001"][1])
    R = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])     # +Z (face) -> -X
    Vm = 10.0 * Vi @ R.T                                                    # centimetres -> millimetres
    Tm = {n: 10.0 * R @ p for n, p in Ti.items()}
    t0 = time.perf_counter()
    lm = autobones.detect_landmarks((Vm, Fi))
    secs = time.perf_counter() - t0
    e = errors(lm, Tm)
    worst = max(e, key=e.get)
    print(f"\nICT identity001 in millimetres facing -X: found up {lm.frame.up}, front {lm.frame.front}; "
          f"{len(lm)} names, dropped {fmt_names(lm.dropped)}, flagged {fmt_names(lm.flagged)}; unit (ex-ex) "
          f"{lm.unit:.1f} mm; error vs published {np.mean(list(e.values())):.2f} % mean, {e[worst]:.2f} % max "
          f"({worst}); {secs:.2f} s -> {'OK' if not lm.flagged and not lm.dropped and lm.frame.front == '-x' else 'NOT OK'}")

    # ---- transfer ----------------------------------------------------------
    from autobones.geometry.topology import mesh_parts

    ict = [h for h in ICT if h in heads]
    pairs = list(itertools.permutations(ict, 2))
    if args.quick:
        pairs = pairs[:2]
    print(f"\n## Transfer onto ICT heads: automatic vs published landmarks ({len(pairs)} ordered pairs; "
          f"correspondence error, % of the target's published ex-ex, mean / p95; difference of the means)\n")
    print("*published*: both sides' published landmarks; *automatic*: `transfer(head, None, rig)` (detected on "
          "the head and on the rig's own skin); *detected head only*: the head's detected landmarks against the "
          "rig's published ones.\n")
    kinds = ("published", "automatic", "detected head only")
    print("| source -> target | landmarks used | " + " | ".join(f"{k} %" for k in kinds)
          + " | automatic - published | head only - published | skin: " + " / ".join(kinds)
          + " | skin: automatic - published | s |")
    print("|---|---|---|---|---|---:|---:|---|---:|---:|")
    rigs = {}
    diffs = {k: ([], []) for k in kinds[1:]}
    for a, b in pairs:
        if a not in rigs:
            rigs[a] = rig_on(*meshes[a], truth[a])
        Vb, Fb = meshes[b]
        part = mesh_parts(len(Vb), Fb)
        skin = part == np.bincount(part).argmax()
        ub = np.linalg.norm(truth[b]["exocanthion_l"] - truth[b]["exocanthion_r"])
        out = {}
        t0 = time.perf_counter()
        for kind, lm in zip(kinds, (truth[b], None, dict(res["default", b]["lm"]))):
            details = {}
            rig = autobones.transfer((Vb, Fb), lm, rig=rigs[a], details=details)
            err = 100 * np.linalg.norm(details["correspondence"] - Vb, axis=1) / ub
            out[kind] = (err, len(rig.options["landmarks_used"]))
        for k in kinds[1:]:
            diffs[k][0].append(out[k][0].mean() - out["published"][0].mean())
            diffs[k][1].append(out[k][0][skin].mean() - out["published"][0][skin].mean())
        print(f"| {a} -> {b} | {' / '.join(str(out[k][1]) for k in kinds)} | "
              + " | ".join(f"{out[k][0].mean():.2f} / {np.percentile(out[k][0], 95):.2f}" for k in kinds)
              + f" | {diffs['automatic'][0][-1]:+.3f} | {diffs['detected head only'][0][-1]:+.3f} | "
              + " / ".join(f"{out[k][0][skin].mean():.2f}" for k in kinds)
              + f" | {diffs['automatic'][1][-1]:+.3f} | {time.perf_counter() - t0:.1f} |", flush=True)
    if pairs:
        print()
        for k in kinds[1:]:
            for what, dd in (("all vertices", diffs[k][0]), ("skin", diffs[k][1])):
                worst = max(dd, key=abs)
                n_ok = sum(abs(x) <= 0.3 for x in dd)
                print(f"{k} - published, {what}: mean {np.mean(dd):+.3f} %, largest {worst:+.3f} % of ex-ex; "
                      f"|difference| <= 0.3 % on {n_ok} of {len(dd)} pairs -> target "
                      f"{'MET' if n_ok == len(dd) else 'NOT MET'}")

    # ---- time ---------------------------------------------------------------
    t = [(h, len(meshes[h][0]), res["default", h]["frame"] + res["default", h]["time"]) for h in heads
         if "err" in res["default", h]]
    ict_t = [s for h, n, s in t if h in ICT]
    if ict_t:
        print(f"\n## Time: ICT heads (26,719 vertices), frame + detect, median {np.median(ict_t):.2f} s, max "
              f"{np.max(ict_t):.2f} s; target <= 3 s per 30k-vertex head: "
              f"{'MET' if np.max(ict_t) <= 3 else 'NOT MET'}; all heads: "
              + ", ".join(f"{h} {n:,} v {s:.2f} s" for h, n, s in t))

    # ---- no face -----------------------------------------------------------
    print("\n## Heads with no human face\n")
    print("| head | vertices | result | s |")
    print("|---|---:|---|---:|")
    for name, rel in NO_FACE.items():
        V, F = load_mesh(DATA / rel)
        t0 = time.perf_counter()
        try:
            lm = autobones.detect_landmarks(DATA / rel)
            result = f"**a face was found**: {len(lm)} names, flagged {fmt_names(lm.flagged)}"
        except AutobonesError as exc:
            msg = str(exc)
            result = ("AutobonesError, 'no face found' " if "no face found" in msg else "AutobonesError, OTHER: ") \
                + f"`{msg[:70]}...`"
        print(f"| {name} | {len(V):,} | {result} | {time.perf_counter() - t0:.2f} |", flush=True)
    print(f"\ntotal wall time {time.perf_counter() - wall0:.0f} s")


if __name__ == "__main__":
    main()
