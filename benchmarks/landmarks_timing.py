"""The timing of ``benchmarks/landmarks.py``: seconds per stage of one detection, and ``--time``'s table.

The stages of :class:`autobones.landmarks.detect.LandmarkDetector` are timed by wrapping the functions it
looks up at call time (:func:`timed_stages`), so the package is measured unchanged. ``--time`` (issue
#14) runs :func:`time_worker` in fresh processes (``landmarks.py --time-worker MESH...``), alternating this
checkout's code with a baseline commit's (:func:`baseline_tree`) so both are timed in the same minutes.
"""
from __future__ import annotations

import contextlib
import os
import subprocess
import time
from pathlib import Path

import numpy as np

import autobones
import autobones.landmarks.detect as detect_mod
from autobones.io.mesh import load_mesh
from autobones.landmarks.detect import LandmarkDetector

from landmarks_heads import DATA, ROOT, TIME_HEADS

# the workers are started through the script, whose hidden --time-worker option calls time_worker
SCRIPT = Path(__file__).resolve().with_name("landmarks.py")


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


def run_config(detector, mesh, frame, **options):
    """(landmarks, seconds, {stage: seconds}) of one detection with ``detector`` and ``options``."""
    clock = Clock()
    det = LandmarkDetector(detector=TimedDetector(detector, clock), **options)
    with timed_stages(clock):
        t0 = time.perf_counter()
        lm = det.detect(*mesh, frame=frame)
        total = time.perf_counter() - t0
    return lm, total, clock.t


# ---------------------------------------------------------------------------
# --time: seconds per head in fresh processes


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


def time_meshes(tmp):
    """head -> mesh path of :data:`TIME_HEADS`, the Loop-subdivided one written under ``tmp``."""
    import trimesh

    paths = {}
    for h, rel in TIME_HEADS.items():
        if h.endswith("loop x2"):
            V, F = load_mesh(DATA / rel)
            V, F = trimesh.remesh.subdivide_loop(V, F, iterations=2)
            paths[h] = os.path.join(tmp, "loop2.obj")
            trimesh.Trimesh(V, F, process=False).export(paths[h])
        else:
            paths[h] = str(DATA / rel)
    return paths


def run_workers(paths, runs, tmp):
    """label -> [mesh path -> seconds] of two worker processes per code of ``runs`` (label -> PYTHONPATH
    or None for this checkout), alternating so every code is measured in the same minutes."""
    import json
    import sys

    got = {k: [] for k in runs}
    for _ in range(2):
        for label, pypath in runs.items():
            env = dict(os.environ, **({"PYTHONPATH": pypath} if pypath else {}))
            proc = subprocess.run([sys.executable, str(SCRIPT), "--time-worker", *paths.values()],
                                  capture_output=True, text=True, env=env, cwd=tmp)
            if proc.returncode:
                raise SystemExit(f"{label}: {proc.stderr.strip().splitlines()[-1]}")
            out = json.loads(proc.stdout.strip().splitlines()[-1])
            where = out.pop("autobones")
            if pypath and not where.startswith(pypath):
                raise SystemExit(f"the baseline worker imported autobones from {where}, not {pypath}")
            got[label].append(out)
    return got


def time_heads(baseline=None):
    """Issue #14's landmark timing table (see the docstring of ``benchmarks/landmarks.py``)."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        paths = time_meshes(tmp)
        sizes = {h: len(load_mesh(p)[0]) for h, p in paths.items()}
        runs = {"this checkout": None}
        if baseline:
            runs[baseline] = baseline_tree(baseline, os.path.join(tmp, "base"))
        got = run_workers(paths, runs, tmp)
    print("\n## Time per head, `detect_landmarks` with orientation, after the model load (median of 3 calls; "
          "two fresh processes per code, alternating)\n")
    labels = list(runs)
    head = "| head | vertices | " + " | ".join(f"{l} s" for l in labels) + (" | ratio |" if baseline else "")
    print(head)
    print("|---|---:|" + "---:|" * len(labels) + ("---:|" if baseline else ""))
    for h, p in paths.items():
        secs = [min(r[p] for r in got[l]) for l in labels]
        ratio = f" | {secs[0] / secs[1]:.2f}x |" if baseline else ""
        print(f"| {h} | {sizes[h]:,} | " + " | ".join(f"{s:.2f}" for s in secs) + ratio)
    print("\n(each figure: the faster of the two processes' medians; target <= 1.5 s per head)")
