"""Parts "ict57" and "ceiling" of benchmarks/expressions.py (issue #16; module doc there): ICT's
shapes that the AU <-> ARKit table maps, fitted by the full rig on one identity and transferred to
remeshed ones (``ict57_benchmark``), and what any contractions of the muscle fields could explain
of them (``ceiling_benchmark``).
"""
from __future__ import annotations

import datetime
import json
import time
from pathlib import Path

import numpy as np

from autobones.geometry.topology import mesh_parts
from autobones.io.mesh import load_mesh
from expression_fitting import SharedSolves, _solve_linear, fit_rig
from expression_heads import ICT, LANDMARKS, NEUTRAL, copy_through, explained, fmt, machine, rig_head

ICT57_TARGETS = {"fit skin mean": 0.80, "fit skin every shape": 0.65, "fit skin of the four": 0.80,
                 "transfer skin mean": 0.70}
FOUR = ("jawOpen", "mouthSmile_L", "eyeBlink_L", "browInnerUp_L")


def _arkit_bench():
    """benchmarks/arkit.py as a module (its ``remesh``, ``carry``), loaded by path."""
    import importlib.util
    import sys

    if "_bench_arkit" not in sys.modules:
        spec = importlib.util.spec_from_file_location("_bench_arkit", Path(__file__).with_name("arkit.py"))
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        sys.modules["_bench_arkit"] = mod
    return sys.modules["_bench_arkit"]


def ict57_shapes(shapes=None):
    """(ICT expression name, AU label) for every row of the definitions' ``au_arkit`` table, both
    halves where ICT splits a shape, in the table's order; only those named in ``shapes`` if given
    (SystemExit when none of them is in the table)."""
    from autobones.expressions.definitions import au_arkit_table

    rows = [(n, "/".join(f"AU{a}" for a in row["au"])) for row in au_arkit_table() for n in row["ict"]]
    if shapes:
        rows = [r for r in rows if r[0] in shapes]
        if not rows:
            raise SystemExit(f"--shapes: none of {shapes} is in the au_arkit table")
    return rows


def remeshed_identity(name, z, N0, F, part, lm_neutral):
    """ICT identity ``name`` (``N0 + identity``, cm) with ICT's neutral landmarks at their barycentric
    place on it, then remeshed as benchmarks/arkit.py's ``run_identity`` does (its
    ``remeshed_identity``). Returns (Vt (n, 3), Ft (m, 3), landmarks dict, tf (n,) ICT face,
    tb (n, 3) barycentric: where each remeshed vertex's truth is read)."""
    ak = _arkit_bench()
    Vi = N0 + z[f"identity/{name}"].astype(np.float64)
    lf, lb = ak.carry(np.array(list(lm_neutral.values())), N0, F, part)
    lm = {n: (Vi[F[f]] * b[:, None]).sum(axis=0) for n, f, b in zip(lm_neutral, lf, lb)}
    return ak.remeshed_identity(Vi, F, part, lm)



def ict57_benchmark(source="identity002", targets=("identity000", "identity001"), refine=30, shapes=None):
    """Issue #16 item 3: every ICT shape the AU <-> ARKit table maps, fitted by the full rig on
    ``source`` (ICT's triangulation) and the parameters applied on ``targets`` remeshed, beside
    the copy through the correspondence. Prints the table and returns the per-shape scores."""
    from autobones.rig_transfer.pipeline import load_generic

    t_all = time.perf_counter()
    rows = ict57_shapes(shapes)
    z = np.load(ICT / "ict_facekit_shapes.npz")
    N0, F = load_mesh(NEUTRAL)
    assert np.abs(N0 - z["neutral"]).max() < 1e-4, "the npz's neutral is not generic_neutral_mesh.obj"
    part = mesh_parts(len(N0), F)
    lm_neutral = {n: np.asarray(v, float) for n, v in json.loads(LANDMARKS.read_text())["landmarks"].items()}
    E = {n: z[f"expression/{n}"].astype(np.float64) for n, _ in rows}
    gF = np.asarray(load_generic().faces)

    rig_s, m_s, P_s, masks_s = rig_head(source, str(ICT / f"{source}.obj"), str(ICT / f"{source}.landmarks.json"))
    assert np.array_equal(rig_s.faces, F), f"{source}: not the ICT topology"
    src = (rig_s.vertices, m_s, P_s, masks_s)
    heads = {name: _remeshed_head(name, z, N0, F, part, lm_neutral) for name in targets}
    shared = SharedSolves(m_s, rig_s.vertices, E, {w: masks_s[w] for w in ("skin", "all")})
    _check_shared(shared, src, E, rows[0][0])
    res = {}
    for n, au in rows:
        res[n] = _fit_shape(n, au, E[n], src, heads, shared, refine, F, gF)
    _print_ict57(res, source, heads, refine, t_all)
    return res


def _remeshed_head(name, z, N0, F, part, lm_neutral):
    """Target ``name`` remeshed and rigged: (Vt, model, correspondence, region masks, the ICT
    triangle and barycentric coordinates each vertex's truth is read at)."""
    t = time.perf_counter()
    Vt, Ft, lm_t, tf, tb = remeshed_identity(name, z, N0, F, part, lm_neutral)
    print(f"remeshed {name}: {len(Vt)} vertices, {len(Ft)} triangles, {time.perf_counter() - t:.1f} s", flush=True)
    rig_t, m_t, P_t, masks_t = rig_head(f"{name} remeshed", (Vt, Ft), lm_t)
    return Vt, m_t, P_t, masks_t, F[tf], tb


def _check_shared(shared, src, E, n0):
    """Self-check: the shared solve is _solve_linear's (same QR, target split into base + displacement)."""
    Vs, m_s, _, masks_s = src
    for w in ("skin", "all"):
        a = shared.solver(n0, w)(8.0, np.array([0.3, 0, 0, 0.1]))
        b = _solve_linear(m_s, Vs + E[n0], masks_s[w], 8.0, np.array([0.3, 0, 0, 0.1]), shared.lo, shared.hi)
        assert abs(a[1] - b[1]) <= 1e-6 * max(b[1], 1e-12) and np.allclose(a[0], b[0], atol=1e-6), (w, a[1], b[1])
    print("self-check passed: shared stage-1 solves equal _solve_linear", flush=True)


def _fit_shape(n, au, D, src, heads, shared, refine, F, gF):
    """Shape ``n`` (ICT displacement ``D``) fitted on the source's skin and on all its vertices, the
    parameters posed on each remeshed head (and with the tissue pass), beside the copy through the
    correspondence. Prints a progress line; returns the shape's scores."""
    t = time.perf_counter()
    Vs, m_s, P_s, masks_s = src
    Xs = Vs + D
    r = {"au": au}
    truth, copies = {}, {}
    for name, (Vt, m_t, P_t, masks_t, tri, tb) in heads.items():
        truth[name] = Vt + np.einsum("vcd,vc->vd", D[tri], tb)   # the truth at each remeshed vertex
        copies[name] = Vt + copy_through(P_s, P_t, gF, Vs, F, D, Vt)
    for where in ("skin", "all"):
        sel = masks_s[where]
        c, jaw, lids, info = fit_rig(m_s, Xs, sel, refine=refine, solve=shared.solver(n, where))
        r["fit", where] = explained(m_s.pose_parameters(c, jaw, lids), Xs, Vs, sel)
        # the same parameters with the tissue pass (issue #16 item 1): not refitted through it
        r["fit+tissue", where] = explained(m_s.pose_parameters(c, jaw, lids, tissue=True), Xs, Vs, sel)
        _score_transfer(r, where, (c, jaw, lids), heads, truth, copies)
        if where == "skin":
            r["params"] = (jaw, lids, info)
    jaw, lids, info = r["params"]
    print(f"  {n} ({au}): {time.perf_counter() - t:.1f} s ({shared.misses} grid points made for "
          f"{shared.calls} solves so far); skin fit {fmt(r['fit', 'skin'])} (jaw {jaw:.1f} deg, "
          f"lids {np.array2string(lids, precision=2)}, residual {info['stage1']:.3f} -> {info['stage2']:.3f}), "
          f"all {fmt(r['fit', 'all'])}; transfer skin "
          + " / ".join(fmt(r["transfer", "skin", h]) for h in heads) + f"; copy-through skin {fmt(r['copy', 'skin'])}",
          flush=True)
    return r


def _score_transfer(r, where, params, heads, truth, copies):
    """Into ``r``: the fitted ``params`` posed on each remeshed head (with and without the tissue
    pass) and the copy-through, scored on its ``where`` vertices; per head and their mean."""
    c, jaw, lids = params
    tr, cp, tt = [], [], []
    for name, (Vt, m_t, P_t, masks_t, tri, tb) in heads.items():
        tr.append(explained(m_t.pose_parameters(c, jaw, lids), truth[name], Vt, masks_t[where]))
        tt.append(explained(m_t.pose_parameters(c, jaw, lids, tissue=True), truth[name], Vt, masks_t[where]))
        cp.append(explained(copies[name], truth[name], Vt, masks_t[where]))
        r["transfer", where, name] = tr[-1]
    r["transfer", where], r["copy", where] = float(np.mean(tr)), float(np.mean(cp))
    r["transfer+tissue", where] = float(np.mean(tt))


ICT57_COLS = [("fit skin", ("fit", "skin")), ("fit all", ("fit", "all")), ("transfer skin", ("transfer", "skin")),
              ("transfer all", ("transfer", "all")), ("copy-through skin", ("copy", "skin")),
              ("copy-through all", ("copy", "all")), ("fit skin, tissue", ("fit+tissue", "skin")),
              ("fit all, tissue", ("fit+tissue", "all")), ("transfer skin, tissue", ("transfer+tissue", "skin")),
              ("transfer all, tissue", ("transfer+tissue", "all"))]


def _ict57_table(res):
    """The markdown table (a row per shape, then their mean and the worst) and each column as an array."""
    cols = ICT57_COLS
    lines = ["| shape | AU | " + " | ".join(c for c, _ in cols) + " |",
             "|---|---|" + "---|" * len(cols)]
    for n, r in res.items():
        lines.append(f"| {n} | {r['au']} | " + " | ".join(fmt(r[k]) for _, k in cols) + " |")
    M = {c: np.array([r[k] for r in res.values()]) for c, k in cols}
    lines.append(f"| **mean of {len(res)}** | | " + " | ".join(fmt(np.nanmean(M[c])) for c, _ in cols) + " |")
    names = list(res)
    lines.append("| **worst** | | " + " | ".join(f"{fmt(np.nanmin(M[c]))} ({names[int(np.nanargmin(M[c]))]})"
                                                  for c, _ in cols) + " |")
    return lines, M


def _print_ict57(res, source, heads, refine, t_all):
    """The table, its notes, the issue's targets and the run's time."""
    lines, M = _ict57_table(res)
    print(f"\nICT's shapes mapped to action units (generic_rig/expressions.json au_arkit), explained %: fit on "
          f"{source} (ICT's triangulation), transfer = {source}'s parameters on "
          + " and ".join(f"{h} remeshed" for h in heads) + " (mean of the two), copy-through = the displacement "
          "copied through the transfer's dense correspondence (mean of the two)\n")
    print("\n".join(lines))
    print("\nnotes: 'skin' columns are fitted and scored on the skin (largest part), 'all' columns on every "
          "vertex (eyeballs, teeth, lashes, shells too). 'tissue' columns pose the same parameters with the "
          "layered tissue pass (issue #16 item 1; pose(tissue=True)), not refitted through it. Per remeshed "
          "identity, transfer skin: "
          + "; ".join(f"{h} mean {fmt(np.mean([r['transfer', 'skin', h] for r in res.values()]))}" for h in heads))
    _print_ict57_targets(res, M)
    print(f"\nict57: {time.perf_counter() - t_all:.1f} s in all ({len(res)} shapes x 2 fits, refine {refine}); "
          f"{datetime.date.today()}, {machine()}")


def _print_ict57_targets(res, M):
    """Issue #16 item 3's targets, met or not, judged on the skin columns."""
    fs, ts = M["fit skin"], M["transfer skin"]
    four = [n for n in FOUR if n in res]
    checks = [
        (f"fit skin mean >= 80 % over the {len(res)} mapped shapes", np.nanmean(fs) >= 0.80, fmt(np.nanmean(fs))),
        ("every shape's fit skin >= 65 %", np.nanmin(fs) >= 0.65,
         ", ".join(f"{n} {fmt(r['fit', 'skin'])}" for n, r in res.items() if r["fit", "skin"] < 0.65) or "none below"),
        ("jawOpen, mouthSmile_L, eyeBlink_L, browInnerUp_L fit skin each >= 80 %",
         bool(four) and all(res[n]["fit", "skin"] >= 0.80 for n in four),
         ", ".join(f"{n} {fmt(res[n]['fit', 'skin'])}" for n in four) or "not run"),
        ("transfer to remeshed identities, skin mean >= 70 %", np.nanmean(ts) >= 0.70, fmt(np.nanmean(ts))),
    ]
    print("\ntargets (issue #16 item 3; judged on the skin columns):")
    for what, ok, val in checks:
        print(f"  {'met    ' if ok else 'NOT met'}  {what}: {val}")
    print(f"  (on all vertices: fit mean {fmt(np.nanmean(M['fit all']))}, transfer mean "
          f"{fmt(np.nanmean(M['transfer all']))}; copy-through skin mean {fmt(np.nanmean(M['copy-through skin']))})")


def ceiling_benchmark(source="identity002", shapes=None):
    """How far the rig's muscle fields can go at all: for every mapped ICT shape, stage 1 of
    ``fit_rig`` (grid over jaw and lids, linear surrogate, no refinement) on ``source``, once with
    the contractions in their bounds (what the benchmark fits) and once with the contractions free
    in sign and size (any linear combination of the fields: a ceiling no contraction values, bounds
    or refinement can pass). Scored on the surrogate ``linear_pose`` itself, so the two columns
    differ only by the bounds. Prints the table; returns the per-shape scores."""
    t_all = time.perf_counter()
    rows = ict57_shapes(shapes)
    z = np.load(ICT / "ict_facekit_shapes.npz")
    E = {n: z[f"expression/{n}"].astype(np.float64) for n, _ in rows}
    rig_s, m_s, _, masks_s = rig_head(source, str(ICT / f"{source}.obj"), str(ICT / f"{source}.landmarks.json"))
    Vs = rig_s.vertices
    where = "skin"
    sel = masks_s[where]
    bounded = SharedSolves(m_s, Vs, E, {where: sel})
    free = SharedSolves(m_s, Vs, E, {where: sel})
    free.lo, free.hi = np.full(len(free.lo), -np.inf), np.full(len(free.hi), np.inf)
    free.cache = bounded.cache                              # same QR per grid point; only the bounds differ

    def surrogate(c, jaw, lids):
        A, b = m_s.linear_pose(jaw, lids)
        return b + np.tensordot(c, A, axes=1)

    res = {}
    for n, au in rows:
        X = Vs + E[n]
        r = {"au": au}
        for key, sh in (("bounded", bounded), ("free", free)):
            c, jaw, lids, _ = fit_rig(m_s, X, sel, refine=0, solve=sh.solver(n, where))
            r[key] = explained(surrogate(c, jaw, lids), X, Vs, sel)
        # c is the free fit's: the muscles it makes push (a muscle cannot)
        r["free range"] = (float(c.min()), float(c.max()))
        r["free pushes"] = [f"{m_s.joints_.names[i]} {c[i]:.2f}" for i in np.argsort(c)[:3] if c[i] < -0.05]
        res[n] = r
        print(f"  {n} ({au}): bounded {fmt(r['bounded'])}, free {fmt(r['free'])} "
              f"(free contractions {r['free range'][0]:.2f} .. {r['free range'][1]:.2f}; most negative: "
              f"{', '.join(r['free pushes']) or 'none'})", flush=True)
    lines = ["| shape | AU | bounded (fitted) | free (ceiling) | free contractions min .. max |",
             "|---|---|---|---|---|"]
    for n, r in res.items():
        lines.append(f"| {n} | {r['au']} | {fmt(r['bounded'])} | {fmt(r['free'])} | "
                     f"{r['free range'][0]:.2f} .. {r['free range'][1]:.2f} |")
    b = np.array([r["bounded"] for r in res.values()])
    f = np.array([r["free"] for r in res.values()])
    lines.append(f"| **mean of {len(res)}** | | {fmt(np.nanmean(b))} | {fmt(np.nanmean(f))} | |")
    print(f"\nThe muscle fields' ceiling on {source}, skin, explained % on the linear surrogate "
          f"({len(m_s.joints_.types)} contractions, jaw and 4 lids on fit_rig's grid):\n")
    print("\n".join(lines))
    print(f"\nshapes with a free ceiling >= 80 %: {int((f >= 0.8).sum())} of {len(f)}; "
          f">= 65 %: {int((f >= 0.65).sum())}")
    print(f"ceiling: {time.perf_counter() - t_all:.1f} s; {datetime.date.today()}, {machine()}")
    return res
