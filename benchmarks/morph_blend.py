"""How far an engine's linear blend of the AU morph targets is from ``pose``.

Run by hand::

    python benchmarks/morph_blend.py

The glb's morph targets (``autobones.expressions.morph_targets.au_morph_targets``) are each AU posed alone at
intensity 1 minus the neutral head. An engine mixes them linearly; ``Rig.pose`` recomputes the
model, which is not linear everywhere (jaw and lid rotations, the skull clamp, the unfolding).
For the default head (placed + transferred with the built-in rig) and ICT identity002 (transferred
with its landmarks), each emotion prototype and two half-intensity AUs are posed both ways; the
table gives the largest vertex difference in % of the head size (the frame's size) and in % of the
pose's own largest displacement.
"""
from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np

import autobones
from autobones.expressions.model import ExpressionModel
from autobones.expressions.morph_targets import au_morph_targets

ROOT = Path(__file__).resolve().parents[1]
ICT = ROOT.parent / "shared" / "data" / "ict"


def heads():
    """(name, transferred rig): the built-in default head (``transfer(None, ...)``) and an ICT scan."""
    yield "default head", autobones.transfer(None, str(ROOT / "generic_rig" / "default_head.landmarks.json"))
    yield "ICT identity002", autobones.transfer(str(ICT / "identity002.obj"), str(ICT / "identity002.landmarks.json"))


def main():
    rows = []
    for name, rig in heads():
        model = ExpressionModel().fit(rig)
        neutral = np.asarray(model.vertices_, dtype=np.float64)
        targets = {t[2:]: d for t, d in au_morph_targets(model)[0]}
        size = float(rig.frame.size)
        cases = [(e, {k: float(v) for k, v in model.expressions[e]["au"].items()}) for e in model.expressions]
        cases += [("AU26 at 0.5", {"26": 0.5}), ("AU43 at 0.5", {"43": 0.5})]
        for label, mix in cases:
            exact = model.pose(au=mix) - neutral
            blend = sum((w * targets[k] for k, w in mix.items() if k in targets), np.zeros_like(neutral))
            err = np.linalg.norm(exact - blend, axis=1).max()
            peak = np.linalg.norm(exact, axis=1).max()
            rows.append((name, label, 100 * err / size, 100 * err / max(peak, 1e-300)))
    print("| head | pose | largest difference, % of head size | % of the pose's largest motion |")
    print("|---|---|---|---|")
    for name, label, a, b in rows:
        print(f"| {name} | {label} | {a:.2f} | {b:.1f} |")
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    print(f"\nautobones {commit}")


if __name__ == "__main__":
    main()
