"""The transfer part of ``benchmarks/landmarks.py``: a rig carried between ICT heads with published,
automatic and detected landmarks, its correspondence error compared (as ``benchmarks/transfer.py``)."""
from __future__ import annotations

import itertools
import time

import numpy as np

import autobones

from landmarks_heads import ICT

KINDS = ("published", "automatic", "detected head only")


def rig_on(V, F, lm):
    """As benchmarks/transfer.py: a sparse placed rig with a smooth field and 12 regions."""
    from sklearn.cluster import KMeans

    from autobones.labelled_rig import LabelledRig

    placed = autobones.place((V, F), density="sparse")
    fields = {"scalar": np.sin(V[:, 1] / 8) + 0.5 * np.cos(V[:, 0] / 6) + V[:, 2] / 20,
              "region": KMeans(12, n_init=2, random_state=0).fit_predict(V).astype(np.int64)}
    return LabelledRig(vertices=V, faces=F, landmarks=lm, skeleton=placed.skeleton, weights=placed.weights,
                       fields=fields, labels={"region": [f"r{i}" for i in range(12)]})


def print_transfer(heads, meshes, truth, res, quick):
    """One row per ordered pair of the ICT heads among ``heads`` (2 pairs if ``quick``), then the target
    lines; ``res``: the accuracy run's results, whose default landmarks are the detected ones."""
    ict = [h for h in ICT if h in heads]
    pairs = list(itertools.permutations(ict, 2))
    if quick:
        pairs = pairs[:2]
    print(f"\n## Transfer onto ICT heads: automatic vs published landmarks ({len(pairs)} ordered pairs; "
          f"correspondence error, % of the target's published ex-ex, mean / p95; difference of the means)\n")
    print("*published*: both sides' published landmarks; *automatic*: `transfer(head, None, rig)` (detected on "
          "the head and on the rig's own skin); *detected head only*: the head's detected landmarks against the "
          "rig's published ones.\n")
    print("| source -> target | landmarks used | " + " | ".join(f"{k} %" for k in KINDS)
          + " | automatic - published | head only - published | skin: " + " / ".join(KINDS)
          + " | skin: automatic - published | s |")
    print("|---|---|---|---|---|---:|---:|---|---:|---:|")
    rigs = {}
    diffs = {k: ([], []) for k in KINDS[1:]}
    for a, b in pairs:
        if a not in rigs:
            rigs[a] = rig_on(*meshes[a], truth[a])
        transfer_pair(a, b, rigs[a], meshes[b], truth[b], dict(res["default", b]["lm"]), diffs)
    if pairs:
        print()
        for k in KINDS[1:]:
            for what, dd in (("all vertices", diffs[k][0]), ("skin", diffs[k][1])):
                worst = max(dd, key=abs)
                n_ok = sum(abs(x) <= 0.3 for x in dd)
                print(f"{k} - published, {what}: mean {np.mean(dd):+.3f} %, largest {worst:+.3f} % of ex-ex; "
                      f"|difference| <= 0.3 % on {n_ok} of {len(dd)} pairs -> target "
                      f"{'MET' if n_ok == len(dd) else 'NOT MET'}")


def transfer_pair(a, b, rig, mesh, published, detected, diffs):
    """Carry ``rig`` (on head ``a``) onto head ``b`` three ways, print the row and append to ``diffs``
    (kind -> (all vertices, skin) differences from published)."""
    from autobones.geometry.topology import mesh_parts

    Vb, Fb = mesh
    part = mesh_parts(len(Vb), Fb)
    # the skin is the largest connected part (not the eyes, teeth or lashes)
    skin = part == np.bincount(part).argmax()
    ub = np.linalg.norm(published["exocanthion_l"] - published["exocanthion_r"])
    out = {}
    t0 = time.perf_counter()
    for kind, lm in zip(KINDS, (published, None, detected)):
        details = {}
        result = autobones.transfer((Vb, Fb), lm, rig=rig, details=details)
        err = 100 * np.linalg.norm(details["correspondence"] - Vb, axis=1) / ub
        out[kind] = (err, len(result.options["landmarks_used"]))
    for k in KINDS[1:]:
        diffs[k][0].append(out[k][0].mean() - out["published"][0].mean())
        diffs[k][1].append(out[k][0][skin].mean() - out["published"][0][skin].mean())
    print(f"| {a} -> {b} | {' / '.join(str(out[k][1]) for k in KINDS)} | "
          + " | ".join(f"{out[k][0].mean():.2f} / {np.percentile(out[k][0], 95):.2f}" for k in KINDS)
          + f" | {diffs['automatic'][0][-1]:+.3f} | {diffs['detected head only'][0][-1]:+.3f} | "
          + " / ".join(f"{out[k][0][skin].mean():.2f}" for k in KINDS)
          + f" | {diffs['automatic'][1][-1]:+.3f} | {time.perf_counter() - t0:.1f} |", flush=True)
