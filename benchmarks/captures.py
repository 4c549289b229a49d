"""Score a rig on your own captures: how much of each real expression its shapes and presets make (issue #34).

Run by hand, on any neutral head and expressions of it (the same mesh posed: same vertices, same
order, same triangles), in any frame and unit::

    python benchmarks/captures.py NEUTRAL.obj SMILE.obj SURPRISE.obj --landmarks NEUTRAL.landmarks.json
    python benchmarks/captures.py NEUTRAL.obj A.obj B.obj --as A=happiness --as B=disgust --markdown
    python benchmarks/expressions.py --captures NEUTRAL.obj SMILE.obj --landmarks L.json   # the same

Without ``--landmarks`` the landmarks are found automatically (human faces only). The rig is
``autobones.transfer(NEUTRAL, landmarks, arkit=True)``; each capture's displacement from the neutral,
its head's rigid motion taken out first (:func:`autobones.arkit.explain.rigid_align`, fitted to the
half of the vertices that move least), is scored over the skin (the largest connected part, when it
holds most of the vertices; else all of them):

- **ARKit**: the best weights in [0, 1] of the rig's 52 ARKit shapes (bounded least squares,
  :func:`autobones.arkit.explain.explain`) and the fraction of the displacement they explain
  (``1 - |residual| / |displacement|``; target, issue #34: 0.6), with the three heaviest shapes;
- **AUs**: the same with the rig's FACS action-unit morph targets (one per AU at intensity 1, what
  ``transfer --expressions`` writes);
- **preset**: when the capture is named for an emotion (``--as NAME=PRESET``, or a file name holding
  one of the six presets or a synonym: smile, happy, surprised, angry, sad, disgusted, afraid),
  ``rig.pose(expression=PRESET)`` against it: the cosine of the two displacement fields and the size
  ratio |preset| / |capture| (targets, issue #34: cosine >= 0.6, size 0.5-2).

Shared data to try it on: the robot's three expressions (a cartoon; landmarks from
``tests/landmarks``) and ICT-FaceKit's four shapes as meshes (``ict/jawOpen.obj`` ...: the shape set's
own source, so its ARKit column is in-sample and near 1: a check that the scoring works).
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import autobones  # noqa: E402
from autobones.arkit.explain import cosine_and_size, explain, rigid_align  # noqa: E402
from autobones.errors import AutobonesError  # noqa: E402
from autobones.expressions.morph_targets import au_morph_targets  # noqa: E402
from autobones.geometry.topology import mesh_parts  # noqa: E402
from autobones.io.landmarks import read_landmarks  # noqa: E402

PRESETS = ("surprise", "fear", "happiness", "sadness", "disgust", "anger")
SYNONYMS = {"smil": "happiness", "happ": "happiness", "joy": "happiness", "surpris": "surprise", "ang": "anger",
            "mad": "anger", "sad": "sadness", "disgust": "disgust", "fear": "fear", "afraid": "fear",
            "scare": "fear"}


def preset_for(path, given):
    """The emotion preset a capture stands for: ``given`` (file stem -> preset) first, else a preset
    or synonym in its file name; None when neither."""
    stem = Path(path).stem
    if stem in given:
        return given[stem]
    low = stem.lower()
    return next((p for p in PRESETS if p in low), None) or next((v for k, v in SYNONYMS.items() if k in low), None)


def skin(V, F):
    """(n,) bool: the vertices judged: the largest connected part when it holds most of them (a head
    with separate eyeballs, teeth, lashes), else all (a mesh of many small parts, e.g. unwelded)."""
    part = mesh_parts(len(V), F)
    count = np.bincount(part)
    return part == np.argmax(count) if count.max() >= 0.5 * len(V) else np.ones(len(V), dtype=bool)


def score_capture(rig, V0, F0, path, preset, aus, mask):
    """One row: the capture at ``path`` against the rig (module docstring)."""
    V, F = autobones.load_mesh(path)
    if V.shape != V0.shape or not np.array_equal(F, F0):
        raise AutobonesError(f"{path}: {len(V)} vertices / {len(F)} triangles, the neutral {len(V0)} / {len(F0)} "
                             "or other triangles: a capture must be the neutral mesh posed, vertex for vertex")
    truth = rigid_align(V, V0) - V0
    row = {"capture": Path(path).stem, "size": float(np.linalg.norm(truth[mask], axis=1).max())}
    w, row["arkit"] = explain(truth, rig.arkit_targets, mask)
    row["top"] = sorted(w.items(), key=lambda kv: -kv[1])[:3]
    if aus:
        _, row["aus"] = explain(truth, aus, mask)
    if preset:
        pred = rig.pose(expression=preset) - rig.vertices
        row["preset"] = (preset, *cosine_and_size(pred, truth, mask))
    return row


def table(rows, markdown):
    head = ["capture", "ARKit explained", "heaviest shapes", "AU targets explained", "preset: cosine, size"]
    lines = []
    for r in rows:
        top = ", ".join(f"{n} {w:.2f}" for n, w in r["top"] if w > 0.005) or "-"
        pre = f"{r['preset'][0]}: {r['preset'][1]:.2f}, {r['preset'][2]:.2f}" if "preset" in r else "-"
        lines.append([r["capture"], f"{r['arkit']:.2f}", top, f"{r['aus']:.2f}" if "aus" in r else "-", pre])
    if markdown:
        out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        out += ["| " + " | ".join(c) + " |" for c in lines]
    else:
        widths = [max(len(str(x)) for x in col) for col in zip(head, *lines)]
        out = ["  ".join(str(x).ljust(w) for x, w in zip(row, widths)) for row in [head] + lines]
    return "\n".join(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("neutral", help="the neutral head mesh")
    ap.add_argument("captures", nargs="+", help="the same mesh posed in expressions, vertex for vertex")
    ap.add_argument("--landmarks", help="the neutral's landmark file (default: found automatically, human faces)")
    ap.add_argument("--as", dest="presets", action="append", default=[], metavar="STEM=PRESET",
                    help="score the capture with this file stem against an emotion preset: " + ", ".join(PRESETS))
    ap.add_argument("--no-aus", action="store_true", help="skip the AU morph targets (they need the muscle model)")
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args(argv)
    given = {}
    for item in args.presets:
        stem, _, preset = item.partition("=")
        if preset not in PRESETS:
            ap.error(f"--as {item}: the preset must be one of {', '.join(PRESETS)}")
        given[stem] = preset
    try:
        t = time.perf_counter()
        V0, F0 = autobones.load_mesh(args.neutral)
        lm = read_landmarks(args.landmarks) if args.landmarks else None
        rig = autobones.transfer((V0, F0), lm, arkit=True)
        aus = None if args.no_aus else dict(au_morph_targets(rig.expression_model())[0])
        mask = skin(rig.vertices, rig.faces)
        print(f"{os.path.basename(args.neutral)}: rig {time.perf_counter() - t:.1f} s, {len(V0)} vertices, "
              f"{int(mask.sum())} on the skin, {len(rig.arkit_targets)} ARKit shapes, {len(aus or {})} AU targets",
              flush=True)
        rows = [score_capture(rig, V0, F0, p, preset_for(p, given), aus, mask) for p in args.captures]
    except AutobonesError as exc:
        print(f"captures: {exc}", file=sys.stderr)
        return 2
    print(table(rows, args.markdown))
    return 0


if __name__ == "__main__":
    sys.exit(main())
