"""Part 3 of benchmarks/expressions.py: the placed bones alone (module doc there).

ICT's four expressions reproduced by linear blend skinning with each rig's weights fixed and the
best per-bone transforms (``expression_fitting.LBSFit``, rigid variant ``fit_rigid``), on every
vertex and on the skin; then the lip check (``lips``, ``lip_mixing``). ``bones_benchmark`` prints
the table.
"""
from __future__ import annotations

import datetime
import json
import subprocess
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

import autobones
from autobones.geometry.topology import mesh_parts
from autobones.io.gltf import top_influences
from autobones.io.mesh import load_mesh
from expression_fitting import LBSFit, fit_rigid
from expression_heads import EXPRESSIONS, ICT, LANDMARKS, NEUTRAL, explained, fmt, machine

def sparse_top4(W):
    J, w = top_influences(W, 4)
    n = len(W)
    M = sp.csr_matrix((w.astype(np.float64).ravel(), (np.repeat(np.arange(n), J.shape[1]), J.ravel())), shape=W.shape)
    M.sum_duplicates()  # unused slots are (joint 0, weight 0)
    return M


def lips(V, lm, region_field, region_names, skin):
    """Boolean masks (upper lip, lower lip) on the neutral head."""
    on = (region_field == region_names.index("lips")) & skin & (V[:, 2] > lm["cheilion_l"][2] - 0.7)
    st, ch = np.asarray(lm["stomion"]), np.asarray(lm["cheilion_l"])
    ax = np.abs(V[:, 0])
    line = st[1] + (ch[1] - st[1]) * np.clip(ax / ch[0], 0, 1)
    inner = on & (ax < 0.8 * ch[0])
    return inner & (V[:, 1] > line), inner & (V[:, 1] <= line)


def lip_mixing(W, names, up, lo, thr=0.2):
    """Lip vertices carrying >= thr of a non-head bone that also weights the other lip >= thr."""
    W = np.asarray(W)
    big = W >= thr
    span = big[up].any(axis=0) & big[lo].any(axis=0)
    if "head" in names:
        span[names.index("head")] = False
    mixed = big[:, span].any(axis=1)
    return int((mixed & up).sum()), int((mixed & lo).sum()), [names[j] for j in np.flatnonzero(span)]



def bones_benchmark(quick=False, sweeps=30):
    """Part 3: every rig's weights fixed, the best bone transforms per expression; prints the table,
    the means, the lip check and the time. ``quick``: sparse and dense rigs only; ``sweeps``: the
    rigid variant's block-descent sweeps (0: no rigid column)."""
    V, F = load_mesh(NEUTRAL)
    shapes = {}
    for e in EXPRESSIONS:
        X, Fe = load_mesh(ICT / f"{e}.obj")
        assert X.shape == V.shape and np.array_equal(Fe, F), f"{e}: not the neutral's vertex list"
        shapes[e] = X
    lm = json.loads(LANDMARKS.read_text())["landmarks"]
    nose_y = lm["pronasale"][1]
    rigs = _place_rigs(V, quick)
    ref = rigs["dense + landmarks"]
    parts = mesh_parts(len(V), F)
    skin = parts == np.argmax(np.bincount(parts))
    up_lip, lo_lip = lips(V, lm, ref.fields["region"], ref.field_labels["region"], skin)

    # weight sets per rig; "global affine" is one bone with weight 1
    entries = [("global affine", 1, {"all": np.ones((len(V), 1))}, ["root"])]
    for label, rig in rigs.items():
        entries.append((label, len(rig.skeleton), {"4 infl": sparse_top4(rig.weights), "all": rig.weights},
                        list(rig.skeleton.names)))
    fits = _self_check(V, skin, entries)
    t_fit = _table(V, skin, shapes, nose_y, entries, fits, sweeps)
    _print_lips(V, shapes, rigs, up_lip, lo_lip)
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=Path(__file__).parent,
                                capture_output=True, text=True).stdout.strip()
    except OSError:
        commit = "?"
    print(f"\nfits: {t_fit:.1f} s; {datetime.date.today()}, autobones {commit}, {machine()}")


def _place_rigs(V, quick):
    """``autobones.place`` of the neutral at each density, and dense with the landmarks."""
    specs = [("sparse", "sparse", None), ("medium", "medium", None), ("dense", "dense", None),
             ("dense + landmarks", "dense", str(LANDMARKS))]
    if quick:
        specs = [specs[0], specs[2], specs[3]]
    rigs = {}
    for label, density, landmarks in specs:
        t = time.perf_counter()
        rig = autobones.place(str(NEUTRAL), density=density, landmarks=landmarks)
        assert np.allclose(rig.vertices, V), "place must keep the vertices"
        rigs[label] = rig
        print(f"placed {label}: {len(rig.skeleton)} bones in {time.perf_counter() - t:.1f} s", flush=True)
    return rigs


def _self_check(V, skin, entries):
    """Every rig and weight set's fit, on all vertices and on the skin, checked: the neutral is
    fitted exactly and a rigid motion of the head >= 99.9 %. Returns {(label, kind, where): (fit, W)}."""
    ang = np.deg2rad(12.0)
    Rx = np.array([[1, 0, 0], [0, np.cos(ang), -np.sin(ang)], [0, np.sin(ang), np.cos(ang)]])
    Ry = np.array([[np.cos(ang / 2), 0, np.sin(ang / 2)], [0, 1, 0], [-np.sin(ang / 2), 0, np.cos(ang / 2)]])
    Xrig = (V - V.mean(0)) @ (Ry @ Rx).T + V.mean(0) + np.array([0.7, -1.3, 2.1])
    fits = {}
    for label, b, wsets, names in entries:
        for kind, W in wsets.items():
            Ws = sp.csr_matrix(W)[np.flatnonzero(skin)]
            for where, fit, sel in [("all", LBSFit(V, W), slice(None)), ("skin", LBSFit(V[skin], Ws), skin)]:
                fits[label, kind, where] = (fit, Ws if where == "skin" else W)
                Y0, _ = fit.fit(V[sel])
                err0 = np.abs(Y0 - V[sel]).max()
                # 4 infl: float32 weights sum to 1 only to float32 rounding (~1e-7 of the head size)
                assert err0 < 1e-6 * fit.s, f"{label}/{kind}/{where}: neutral fit residual {err0:.3g}"
                e = explained(fit.fit(Xrig[sel])[0], Xrig[sel], V[sel])
                assert e >= 0.999, f"{label}/{kind}/{where}: rigid head motion explained {100 * e:.3f} %"
    print("self-check passed: neutral residual 0, rigid head motion >= 99.9 % on every rig and weight set\n")
    return fits


def _table(V, skin, shapes, nose_y, entries, fits, sweeps):
    """The table (rows: rig x expression), the means per rig and the moved-vertex counts, printed.
    Returns the fits' time in seconds."""
    Vs = V[skin]
    sk = {e: X[skin] for e, X in shapes.items()}
    lower, upper = {}, {}
    for e, X in sk.items():
        d = np.linalg.norm(X - Vs, axis=1)
        moved = d > 0.01 * d.max()
        lower[e] = moved & (Vs[:, 1] < nose_y)
        upper[e] = moved & (Vs[:, 1] >= nose_y)
    hdr = ("| rig | bones | expression | all weights: all / skin / lower / upper | 4 infl: all / skin / lower / upper |"
           + (" rigid 4 infl: skin |" if sweeps else ""))
    lines = [hdr, "|" + "---|" * (hdr.count("|") - 1)]
    summary = {}

    def region(fitted, e, sel):
        return explained(fitted, sk[e], Vs, sel) if sel.sum() >= 50 else np.nan

    def scores(label, kind, e):
        if label is None:  # neutral: no motion
            fa, fs = V, Vs
        else:
            fa = fits[label, kind, "all"][0].fit(shapes[e])[0]
            fs = fits[label, kind, "skin"][0].fit(sk[e])[0]
        return (explained(fa, shapes[e], V), explained(fs, sk[e], Vs),
                region(fs, e, lower[e]), region(fs, e, upper[e]))

    for e in EXPRESSIONS:
        z = " / ".join(map(fmt, scores(None, None, e)))
        lines.append(f"| neutral | 0 | {e} | {z} | {z} |" + (" 0.0 |" if sweeps else ""))
    t_fit = time.perf_counter()
    for label, b, wsets, names in entries:
        for e in EXPRESSIONS:
            row = {kind: scores(label, kind, e) for kind in wsets}
            rig_col = _rigid_column(fits, label, wsets, sk[e], Vs, sweeps)
            a = row["all"]
            f4 = row.get("4 infl", (np.nan,) * 4)
            summary.setdefault(label, []).append((a[0], a[1], f4[1]))
            lines.append(f"| {label} | {b} | {e} | {' / '.join(map(fmt, a))} | {' / '.join(map(fmt, f4))} |{rig_col}")
    t_fit = time.perf_counter() - t_fit

    print("\n".join(lines))
    print("\nmean over the 4 expressions, explained (all vertices, all weights / skin, all weights / skin, 4 infl):")
    for label, vals in summary.items():
        v = np.array(vals)
        m = [fmt(np.nanmean(v[:, k])) if not np.all(np.isnan(v[:, k])) else "-" for k in range(3)]
        print(f"  {label:18s} {m[0]:>5s} / {m[1]:>5s} / {m[2]:>5s}   (skin min {fmt(np.nanmin(v[:, 1]))})")
    print(f"\nskin {skin.sum()} of {len(V)} vertices; moved skin vertices lower / upper face: "
          + ", ".join(f"{e} {lower[e].sum()}/{upper[e].sum()}" for e in EXPRESSIONS))
    return t_fit


def _rigid_column(fits, label, wsets, X, Vs, sweeps):
    """The table's rigid cell: the skin's 4-influence weights with a rotation per bone ("" without
    sweeps, "-" for a rig without 4-influence weights); checks the descent never got worse."""
    if not sweeps:
        return ""
    if "4 infl" not in wsets:
        return " - |"
    fit, W = fits[label, "4 infl", "skin"]
    Yr = fit_rigid(fit, W, X, sweeps)
    start = fit_rigid(fit, W, X, 0)
    er = explained(Yr, X, Vs)
    assert er >= explained(start, X, Vs) - 1e-9, "rigid descent went up"
    return f" {fmt(er)} |"


def _print_lips(V, shapes, rigs, up_lip, lo_lip):
    """The lip check: lip sizes, jawOpen's motion of each lip, and per rig the lip vertices mixed."""
    print(f"lip check: {up_lip.sum()} upper-lip, {lo_lip.sum()} lower-lip vertices; jawOpen mean displacement "
          f"upper {np.linalg.norm(shapes['jawOpen'] - V, axis=1)[up_lip].mean():.3f}, "
          f"lower {np.linalg.norm(shapes['jawOpen'] - V, axis=1)[lo_lip].mean():.3f}")
    for label, rig in rigs.items():
        mu, ml, span = lip_mixing(rig.weights, list(rig.skeleton.names), up_lip, lo_lip)
        print(f"  {label:18s} mixed: {mu}/{up_lip.sum()} upper, {ml}/{lo_lip.sum()} lower; "
              f"bones weighting both lips >= 0.2: {', '.join(span) or 'none'}")
