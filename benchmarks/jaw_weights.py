"""Benchmark the transferred jaw weight before and after its repair (``autobones.rig_transfer.jaw``).

    python benchmarks/jaw_weights.py            # every landmarked head, and long-snout copies
    python benchmarks/jaw_weights.py --quick    # goat, robot, james and its snout copy

For each landmarked head (``../shared/data``'s landmark files, the default head, the hand-placed goat
and robot of ``tests/landmarks``) and for synthetic long-snout copies (the face in front of the
eye corners stretched along the head's front axis, landmarks moved with it), ``autobones.transfer``
is run with the jaw repair switched off ("before", the carried weight) and on ("after"). Reported:

- ``chin``: jaw weight at the ``pogonion`` (at the ``menton`` where there is no pogonion);
- ``lower lip``: at the vertex nearest the ``stomion`` on the lower side of the mouth plane
  (``stomion``, both ``cheilion``), within 0.1 face units; ``-`` without those landmarks;
- ``max jump``: the largest jaw-weight step along an edge off the lip line
  (:func:`autobones.rig_transfer.jaw.lip_line_edges`), and how many such edges step by more than 0.3;
- ``changed``: mean |after - before| over the vertices, and the share moved by more than 0.1.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from unittest import mock

import numpy as np

import autobones
from autobones.io.landmarks import read_landmarks
from autobones.io.mesh import load_mesh
from autobones.rig_transfer import pipeline
from autobones.rig_transfer.jaw import MAX_JUMP, face_unit, lip_line_edges, mouth_frame

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
sys.path.insert(0, str(ROOT / "tests"))
from shared_data import long_snout  # noqa: E402  (the test helpers' stretched-snout head)
HEADS = {  # name: (mesh, landmark file); None: the built-in default head
    "default_head": (None, ROOT / "generic_rig" / "default_head.landmarks.json"),
    "ict_neutral": (DATA / "ict/generic_neutral_mesh.obj", DATA / "ict/generic_neutral_mesh.landmarks.json"),
    "ict_identity000": (DATA / "ict/identity000.obj", DATA / "ict/identity000.landmarks.json"),
    "ict_identity001": (DATA / "ict/identity001.obj", DATA / "ict/identity001.landmarks.json"),
    "ict_identity002": (DATA / "ict/identity002.obj", DATA / "ict/identity002.landmarks.json"),
    "james": (DATA / "menpo3d/james.obj", DATA / "menpo3d/james.landmarks.json"),
    "template": (DATA / "menpo3d/template.ply", DATA / "menpo3d/template.landmarks.json"),
    "goat": (DATA / "misc/goathead.obj", ROOT / "tests/landmarks/goathead.landmarks.json"),
    "robot": (DATA / "misc/robot_head_neutral.obj", ROOT / "tests/landmarks/robot_head_neutral.landmarks.json"),
}
SNOUTS = {"james": (2.0, 4.0), "ict_identity002": (3.0,), "goat": (1.0,)}  # stretch factors k
QUICK = ("goat", "robot", "james", "james_snout2")


def probes(V, lm):
    """Vertex indices (chin, lower lip or None) of the table's two probes."""
    chin = lm.get("pogonion", lm.get("menton"))
    i_chin = int(np.argmin(np.linalg.norm(V - chin, axis=1))) if chin is not None else None
    mouth = mouth_frame(lm)
    if mouth is None:
        return i_chin, None
    d = np.linalg.norm(V - mouth["stomion"], axis=1)
    below = ((V - mouth["stomion"]) @ mouth["normal"] < 0) & (d < 0.1 * face_unit(V, lm))
    return i_chin, (int(np.flatnonzero(below)[np.argmin(d[below])]) if below.any() else None)


def measure(V, F, lm, jaw):
    E, on_line = lip_line_edges(V, F, lm)
    jump = np.abs(jaw[E[:, 0]] - jaw[E[:, 1]])[~on_line]
    i_chin, i_lip = probes(V, lm)
    return dict(chin=None if i_chin is None else jaw[i_chin], lip=None if i_lip is None else jaw[i_lip],
                jump=float(jump.max()), over=int((jump > MAX_JUMP).sum()))


def jaw_of(rig):
    return rig.weights[:, rig.skeleton.names.index("jaw")]


def heads(names):
    for name in names:
        base, _, k = name.partition("_snout")
        mesh, marks = HEADS[base]
        lm = read_landmarks(marks)
        V, F = load_mesh(mesh) if mesh is not None else load_mesh(ROOT / "generic_rig" / "default_head.obj")
        if k:
            V, lm = long_snout(V, F, lm, float(k))
        yield name, V, F, lm


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    names = list(QUICK) if args.quick else (
        list(HEADS) + [f"{h}_snout{k:g}" for h, ks in SNOUTS.items() for k in ks])
    fmt = lambda v: "   -" if v is None else f"{v:4.2f}"  # noqa: E731
    print(f"{'head':22s} {'verts':>7s} | {'chin':>4s} {'lip':>4s} {'jump':>4s} {'>0.3':>5s} | "
          f"{'chin':>4s} {'lip':>4s} {'jump':>4s} {'>0.3':>5s} | {'mean|d|':>7s} {'>0.1':>6s} {'s':>5s}")
    print(f"{'':22s} {'':7s} | {'before':^21s} | {'after':^21s} |")
    for name, V, F, lm in heads(names):
        with mock.patch.object(pipeline, "repair_jaw_weights", lambda V, F, W, names, lm, details=None, still=None: W):
            before = jaw_of(autobones.transfer((V, F), lm))
        t = time.perf_counter()
        after = jaw_of(autobones.transfer((V, F), lm))
        seconds = time.perf_counter() - t
        b, a = measure(V, F, lm, before), measure(V, F, lm, after)
        d = np.abs(after - before)
        print(f"{name:22s} {len(V):7d} | {fmt(b['chin'])} {fmt(b['lip'])} {b['jump']:4.2f} {b['over']:5d} | "
              f"{fmt(a['chin'])} {fmt(a['lip'])} {a['jump']:4.2f} {a['over']:5d} | {d.mean():7.4f} "
              f"{(d > 0.1).mean():6.1%} {seconds:5.1f}", flush=True)


if __name__ == "__main__":
    main()
