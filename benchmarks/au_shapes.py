"""Part "au-shapes" of benchmarks/expressions.py (issue #34 item 2): the AUs through the head's ARKit shapes.

Run by hand, not by the tests::

    python benchmarks/expressions.py --part au-shapes            # ~5 min on 2 cores
    python benchmarks/expressions.py --part au-shapes --variants identity001

Heads: ICT identity000, identity001, identity002 on ICT's own triangulation with their landmark
files, identity000 remeshed (``remesh`` of benchmarks/arkit.py: one Loop subdivision, then
``fast_simplification`` back) and identity001 decimated to half its triangles (``fast_simplification``
alone), both with ICT's neutral landmarks carried on. All are held out: the packaged ARKit shapes
come from ICT's generic neutral, never from an identity. Each is rigged by
``autobones.transfer(mesh, landmarks, arkit=True)``.

Per AU of the ``au_arkit`` table: explained = 1 - ||pose(au={k: 1}) - rest - truth|| / ||truth|| over
the skin (ICT's largest part; on a remeshed head the vertices whose closest ICT point is on it),
truth = ICT's own displacement of the row's ICT shapes (both halves; ``ict_facekit_shapes.npz``):
ICT is linear (identity + expression), so that is the identity's own AU; on a remeshed head it is
interpolated at each vertex's closest ICT point. Columns: ``layer="shapes"`` and ``layer="muscles"``.

Emotions: cosine and size ratio ||pose - rest|| / ||truth|| of ``pose(expression=X)`` against the
ICT shapes the table gives for the preset's AUs (the same combination rule as the pose:
:func:`autobones.expressions.au_shapes.split_mix`). This is ICT against its own AU mapping, not
real people's emotions; AUs the table does not map (anger's AU23, AU25) have no ICT truth, and
their muscle motion counts as error.
"""
from __future__ import annotations

import datetime
import json
import time

import numpy as np

import autobones
from autobones.arkit.names import ARKIT_NAMES, ict_names
from autobones.errors import AutobonesError
from autobones.expressions import au_shapes
from autobones.expressions.definitions import au_arkit_table, load_expressions
from autobones.geometry.topology import mesh_parts

TARGET = 0.80   # every mapped AU, shapes layer
VARIANTS = ("identity000", "identity001", "identity002", "identity000 remeshed", "identity001 decimated")


def decimate(V, F, keep=0.5):
    """``fast_simplification`` to ``keep`` of the triangles, unreferenced vertices dropped."""
    import fast_simplification

    Vr, Fr = fast_simplification.simplify(V, F, target_reduction=1.0 - keep)
    used = np.unique(Fr)
    remap = -np.ones(len(Vr), dtype=np.int64)
    remap[used] = np.arange(len(used))
    return np.asarray(Vr, dtype=np.float64)[used], remap[Fr]


def head(variant, z, N0, F, part, ak, ict):
    """(V, F, landmarks, sample, skin): the variant's mesh and landmarks, ``sample(D)`` -> an ICT displacement
    D (N, 3) at its vertices (interpolated at their closest ICT points when remeshed or decimated), and
    ``skin`` (bool per vertex: on ICT's largest part)."""
    name, _, how = variant.partition(" ")
    Vi = N0 + z[f"identity/{name}"].astype(np.float64)
    skin_label = np.argmax(np.bincount(part))
    if not how:
        lm = {k: np.asarray(v, float) for k, v in json.loads((ict / f"{name}.landmarks.json").read_text())
              ["landmarks"].items()}
        return Vi, F, lm, (lambda D: D), part == skin_label
    lm_neutral = {k: np.asarray(v, float) for k, v in
                  json.loads((ict / "generic_neutral_mesh.landmarks.json").read_text())["landmarks"].items()}
    lf, lb = ak.carry(np.array(list(lm_neutral.values())), N0, F, part)
    lm = {k: (Vi[F[f]] * b[:, None]).sum(axis=0) for k, f, b in zip(lm_neutral, lf, lb)}
    if how == "remeshed":
        Vt, Ft, lm_t, tf, tb = ak.remeshed_identity(Vi, F, part, lm)
    else:  # decimated: the same carrying of landmarks and truth as remeshed_identity, on another mesh
        Vt, Ft, lm_t, tf, tb = _carried(ak, Vi, F, part, lm, *decimate(Vi, F))
    tri = F[tf]
    return Vt, Ft, lm_t, (lambda D: np.einsum("vcd,vc->vd", D[tri], tb)), part[tri[:, 0]] == skin_label


def _carried(ak, Vi, F, part, lm, Vt, Ft):
    """benchmarks/arkit.py's ``remeshed_identity`` for an already made mesh (Vt, Ft)."""
    from autobones.geometry.closest import closest_points

    tpart = mesh_parts(len(Vt), Ft)
    f0, _ = ak.carry(Vt, Vi, F, part)
    votes = np.zeros((tpart.max() + 1, part.max() + 1))
    np.add.at(votes, (tpart, part[F[f0, 0]]), 1)
    tf, tb = ak.carry(Vt, Vi, F, part, np.argmax(votes, axis=1)[tpart])
    _, lfv, lbv, _ = closest_points(np.array(list(lm.values())), Vt, Ft)
    return Vt, Ft, {n: (Vt[Ft[f]] * b[:, None]).sum(axis=0) for n, f, b in zip(lm, lfv, lbv)}, tf, tb


def explained(got, truth, sel):
    return 1.0 - np.linalg.norm(got[sel] - truth[sel]) / max(np.linalg.norm(truth[sel]), 1e-300)


def ict_combination(weights, E):
    """ICT displacement (N, 3) of ARKit ``weights`` (name -> weight), each through its ICT names."""
    return sum(w * E[n] for s, w in weights.items() for n in ict_names(s))


def score_head(rig, sample, skin, table, presets, E):
    """Per-AU explained (shapes, muscles) and per-emotion (cosine, size ratio) for both layers."""
    V = rig.vertices
    out = {}
    for row in table:
        truth = sample(sum(E[n] for n in row["ict"]))
        for a in row["au"]:
            for layer in ("shapes", "muscles"):
                try:
                    out["au", str(a), layer] = explained(rig.pose(au={a: 1.0}, layer=layer) - V, truth, skin)
                except AutobonesError:   # AU16, AU45: no muscle definition
                    out["au", str(a), layer] = np.nan
    for name in presets:
        weights, _ = au_shapes.split_mix(au_shapes.au_mix(None, name, presets), table, ARKIT_NAMES)
        truth = sample(ict_combination(weights, E))[skin].ravel()
        for layer in ("shapes", "muscles"):
            d = (rig.pose(expression=name, layer=layer) - V)[skin].ravel()
            out["emotion", name, layer] = (float(d @ truth / (np.linalg.norm(d) * np.linalg.norm(truth))),
                                           float(np.linalg.norm(d) / np.linalg.norm(truth)))
    return out


def au_shapes_benchmark(ict, machine, variants=VARIANTS):
    """Transfer each variant with its ARKit shapes, score every mapped AU and the six emotions, print the
    tables (markdown) and the target check; returns the scores per variant."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    import arkit as ak   # benchmarks/arkit.py: remesh, carry

    t_all = time.perf_counter()
    z = np.load(ict / "ict_facekit_shapes.npz")
    N0, F = autobones.load_mesh(str(ict / "generic_neutral_mesh.obj"))
    assert np.abs(N0 - z["neutral"]).max() < 1e-4, "the npz's neutral is not generic_neutral_mesh.obj"
    part = mesh_parts(len(N0), F)
    table, presets = au_arkit_table(), load_expressions()["expressions"]
    E = {n: z[f"expression/{n}"].astype(np.float64) for row in table for n in row["ict"]}
    res = {}
    for v in variants:
        t = time.perf_counter()
        Vt, Ft, lm, sample, skin = head(v, z, N0, F, part, ak, ict)
        rig = autobones.transfer((Vt, Ft), lm, arkit=True)
        res[v] = score_head(rig, sample, skin, table, presets, E)
        print(f"{v}: {len(Vt)} vertices, {skin.sum()} skin, {time.perf_counter() - t:.1f} s", flush=True)
    aus = au_shapes.mapped_aus(table)
    pct = lambda x: "-" if np.isnan(x) else f"{100 * x:.1f}"   # noqa: E731
    print("\nAUs through the head's ARKit shapes: explained % of ICT's own AU displacement on the skin, "
          "shapes / muscles\n")
    print("| AU | ARKit shapes | " + " | ".join(variants) + " | worst, shapes |")
    print("|---|---|" + "---|" * (len(variants) + 1))
    shape_of = {str(a): ", ".join(r["arkit"]) for r in table for a in r["au"]}
    worst = {}
    for a in aus:
        cells = [f"{pct(res[v]['au', a, 'shapes'])} / {pct(res[v]['au', a, 'muscles'])}" for v in variants]
        worst[a] = min(res[v]["au", a, "shapes"] for v in variants)
        print(f"| AU{a} | {shape_of[a]} | " + " | ".join(cells) + f" | {pct(worst[a])} |")
    for layer in ("shapes", "muscles"):
        m = [np.nanmean([res[v]["au", a, layer] for a in aus]) for v in variants]
        print(f"| **mean, {layer}** | | " + " | ".join(pct(x) for x in m) + " | |")
    print("\nEmotion presets against ICT's shapes for the preset's AUs (ICT against its own AU mapping, not real "
          "people): cosine / size ratio, shapes layer; muscles layer\n")
    print("| emotion | " + " | ".join(variants) + " |")
    print("|---|" + "---|" * len(variants))
    for name in presets:
        cells = ["{:.2f} / {:.2f}; {:.2f} / {:.2f}".format(*res[v]["emotion", name, "shapes"],
                                                          *res[v]["emotion", name, "muscles"]) for v in variants]
        print(f"| {name} | " + " | ".join(cells) + " |")
    low = [f"AU{a} {pct(worst[a])}" for a in aus if worst[a] < TARGET]
    print(f"\ntarget: every mapped AU >= {100 * TARGET:.0f} % with shapes on every head: "
          + ("met" if not low else "NOT met: " + ", ".join(low)))
    print(f"\nau-shapes: {time.perf_counter() - t_all:.1f} s; {datetime.date.today()}, {machine()}")
    return res
