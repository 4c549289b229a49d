"""The layered tissue pass (issue #16 item 1): volume, skull, folds and time per pose, across heads.

Run by hand, not by the tests::

    python benchmarks/tissue.py              # six heads and two variants (~3 min on 2 cores)
    python benchmarks/tissue.py --heads ict_identity002 default_head

Each head is rigged by ``autobones.transfer`` with its landmarks and posed by
``ExpressionModel.pose`` at every action unit of ``generic_rig/expressions.json`` at intensity 1
(both sides) and each of the six emotions, once without and once with ``tissue=True``
(Lee, Terzopoulos & Waters 1995 as a static equilibrium; ``autobones/expressions/tissue.py``).
Per pose, from the tissue's own report (``model.tissue_info_``):

- volume: total tissue volume (the prisms of both layers) over rest, minus 1 (target |.| <= 1 %);
- depth: the lowest epidermal or fascia node above the skull estimate, in head sizes (>= 0: none inside);
- folds added: skin triangles the wire result leaves the right way up and the tissue pose turns over
  (target 0), counted on the welded skin;
- kept: skin vertices given back part of the wire result to avoid such a fold;
- time: the tissue pose, seconds (the wire pose's time in the same run beside it; the first tissue
  pose also builds and factorises the tissue, reported apart as "build").

Heads: the default head (a sculpt), ICT-FaceKit identity002 (26,719 vertices, 56 parts), the menpo3d
template (53k, a registered scan) and james (a scan), the robot (a cartoon) and the goat (an animal);
variants: ICT identity002 decimated to ~40 % (fast-simplification, new triangulation) and x1000.
"""
from __future__ import annotations

import argparse
import datetime
import platform
import sys
import time
from pathlib import Path

import numpy as np

import autobones
from autobones.expressions.model import ExpressionModel
from autobones.geometry.normals import triangle_normals

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
HEADS = {
    "default_head": (None, ROOT / "generic_rig/default_head.landmarks.json"),
    "ict_identity002": (DATA / "ict/identity002.obj", DATA / "ict/identity002.landmarks.json"),
    "menpo3d_template": (DATA / "menpo3d/template.ply", DATA / "menpo3d/template.landmarks.json"),
    "menpo3d_james": (DATA / "menpo3d/james.obj", DATA / "menpo3d/james.landmarks.json"),
    "robot": (DATA / "misc/robot_head_neutral.obj", ROOT / "tests/landmarks/robot_head_neutral.landmarks.json"),
    "goat": (DATA / "misc/goathead.obj", ROOT / "tests/landmarks/goathead.landmarks.json"),
}
VARIANTS = ("ict_identity002 decimated", "ict_identity002 x1000")


def head_input(name):
    """(mesh or (V, F), landmarks) for a head or a variant."""
    import json

    from autobones.geometry.proxy import quadric_simplify

    if name in HEADS:
        mesh, marks = HEADS[name]
        return (None if mesh is None else str(mesh)), str(marks)
    base, kind = name.split(" ")
    mesh, marks = HEADS[base]
    V, F = autobones.load_mesh(str(mesh))
    lm = {k: np.asarray(v, float) for k, v in json.loads(Path(marks).read_text())["landmarks"].items()}
    if kind == "x1000":
        return (V * 1000.0, F), {k: v * 1000.0 for k, v in lm.items()}
    Vd, Fd = quadric_simplify(V, F, 0.6)
    return (Vd, Fd), lm          # landmarks are points in space: they stay where they are


def folds_added(model, wire, tissue):
    surf = model.surface_
    F, n0 = surf.skin_faces, surf.rest_normals

    def upright(V):
        Vw = model.frame_.to_canonical(V)[surf.first]
        return np.einsum("ij,ij->i", triangle_normals(Vw, F), n0) > 0

    return int((upright(wire) & ~upright(tissue)).sum())


def run_head(name):
    mesh, marks = head_input(name)
    t = time.perf_counter()
    rig = autobones.transfer(mesh, marks)
    model = ExpressionModel().fit(rig)
    t_rig = time.perf_counter() - t
    t = time.perf_counter()
    model.tissue()
    t_build = time.perf_counter() - t
    tissue = model.tissue_
    poses = [("AU" + k, {"au": {k: 1.0}}) for k in sorted(model.action_units, key=int)]
    poses += [(e, {"expression": e}) for e in model.expressions]
    rows = []
    for label, kw in poses:
        t = time.perf_counter()
        wire = model.pose(**kw)
        t_wire = time.perf_counter() - t
        t = time.perf_counter()
        V = model.pose(tissue=True, **kw)
        t_tissue = time.perf_counter() - t
        info = model.tissue_info_
        moved = float(np.linalg.norm(V - wire, axis=1).max() / rig.frame.size)
        rows.append({"pose": label, "volume": info["volume"] - 1.0, "depth": info["depth"],
                     "folds": folds_added(model, wire, V), "kept": info["kept_wire"], "iterations": info["iterations"],
                     "t_wire": t_wire, "t_tissue": t_tissue, "moved": moved})
    return {"name": name, "vertices": len(rig.vertices), "columns": len(tissue.columns_), "t_rig": t_rig,
            "t_build": t_build, "rows": rows}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--heads", nargs="*", default=list(HEADS) + list(VARIANTS))
    ap.add_argument("--detail", default="ict_identity002", help="head whose per-pose table is printed")
    args = ap.parse_args(argv)
    missing = [n for n in args.heads if n.split(" ")[0] not in HEADS]
    if missing:
        sys.exit(f"unknown heads: {missing}; known: {list(HEADS) + list(VARIANTS)}")
    t_all = time.perf_counter()
    results = []
    for name in args.heads:
        r = run_head(name)
        results.append(r)
        rows = r["rows"]
        print(f"{name}: {r['vertices']} vertices, {r['columns']} tissue columns; rig {r['t_rig']:.1f} s, tissue "
              f"build {r['t_build']:.2f} s; worst volume {max(abs(x['volume']) for x in rows):.2%}, "
              f"tissue pose median {np.median([x['t_tissue'] for x in rows]):.2f} s", flush=True)
    print("\n| head | vertices | tissue columns | build s | poses | worst volume change | its pose | lowest depth "
          "(head sizes) | folds added | vertices kept (max) | iterations (max) | tissue pose s median / max | "
          "wire pose s median | largest tissue correction (head sizes) |")
    print("|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---|---:|---:|")
    for r in results:
        rows = r["rows"]
        worst = max(rows, key=lambda x: abs(x["volume"]))
        print(f"| {r['name']} | {r['vertices']} | {r['columns']} | {r['t_build']:.2f} | {len(rows)} | "
              f"{worst['volume']:+.2%} | {worst['pose']} | {min(x['depth'] for x in rows):.2e} | "
              f"{sum(x['folds'] for x in rows)} | {max(x['kept'] for x in rows)} | "
              f"{max(x['iterations'] for x in rows)} | {np.median([x['t_tissue'] for x in rows]):.2f} / "
              f"{max(x['t_tissue'] for x in rows):.2f} | {np.median([x['t_wire'] for x in rows]):.2f} | "
              f"{max(x['moved'] for x in rows):.4f} |")
    for r in results:
        if r["name"] != args.detail:
            continue
        print(f"\n{r['name']}, per pose:\n")
        print("| pose | volume change | lowest depth | folds added | kept | iterations | tissue s | wire s | "
              "largest correction |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
        for x in r["rows"]:
            print(f"| {x['pose']} | {x['volume']:+.3%} | {x['depth']:.2e} | {x['folds']} | {x['kept']} | "
                  f"{x['iterations']} | {x['t_tissue']:.2f} | {x['t_wire']:.2f} | {x['moved']:.4f} |")
    targets = [
        ("volume within 1 % of rest at every pose", all(abs(x["volume"]) <= 0.01 for r in results for x in r["rows"]),
         ", ".join(f"{r['name']} {x['pose']} {x['volume']:+.2%}" for r in results for x in r["rows"]
                   if abs(x["volume"]) > 0.01) or "all"),
        ("no node inside the skull", all(x["depth"] >= -1e-12 for r in results for x in r["rows"]), ""),
        ("no fold added", all(x["folds"] == 0 for r in results for x in r["rows"]), ""),
        ("<= 2 s per pose on a 27k-vertex head",
         all(x["t_tissue"] <= 2.0 for r in results if r["name"] == "ict_identity002" for x in r["rows"]),
         ", ".join(f"{x['pose']} {x['t_tissue']:.2f} s" for r in results if r["name"] == "ict_identity002"
                   for x in r["rows"] if x["t_tissue"] > 2.0)),
    ]
    print("\ntargets (issue #16 item 1):")
    for what, ok, detail in targets:
        print(f"  {'met    ' if ok else 'NOT met'}  {what}" + (f": {detail}" if detail and not ok else ""))
    print(f"\n{time.perf_counter() - t_all:.0f} s in all; {datetime.datetime.now():%Y-%m-%d %H:%M}, "
          f"{platform.machine()}, {platform.python_version()}")


if __name__ == "__main__":
    main()
