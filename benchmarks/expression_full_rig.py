"""Parts 1 and 2 of benchmarks/expressions.py: the full expression rig fitted to ICT's four real
expressions on one identity, and its parameters transferred to two others (module doc there).

``full_rig_benchmark`` prints the table, the targets and, after them, what one joint could explain
with any weight field (``rotation_ceiling``); the fits are ``expression_fitting.fit_rig``.
"""
from __future__ import annotations

import time

import numpy as np

from autobones.io.mesh import load_mesh
from expression_fitting import fit_rig, rotation_ceiling
from expression_heads import (EXPRESSIONS, ICT, NEUTRAL, REGIONS, copy_through, fmt, region_scores,
                              rig_head)

COLS = ["all", "skin", "parts"] + [r for r, _ in REGIONS]


def _row(lines, who, method, e, sc):
    lines.append(f"| {who} | {method} | {e} | " + " | ".join(fmt(sc[c]) for c in COLS) + " |")


def _displacements():
    """ICT's neutral faces and each expression's displacement from it (the same on every identity)."""
    N0, F = load_mesh(NEUTRAL)
    E = {}
    for e in EXPRESSIONS:
        X, Fe = load_mesh(ICT / f"{e}.obj")
        assert X.shape == N0.shape and np.array_equal(Fe, F)
        E[e] = X - N0                                     # the same displacement on every identity
    return F, E


def full_rig_benchmark(source="identity002", targets=("identity000", "identity001"), refine=30):
    """Parts 1 and 2 of the proof; prints its table and returns the lines."""
    from autobones.rig_transfer.pipeline import load_generic

    F, E = _displacements()
    gF = np.asarray(load_generic().faces)
    heads = {}
    for name in (source, *targets):
        heads[name] = rig_head(name, str(ICT / f"{name}.obj"), str(ICT / f"{name}.landmarks.json"))
        assert np.array_equal(heads[name][0].faces, F), f"{name}: not the ICT topology"
    hdr = "| identity | method | expression | " + " | ".join(COLS) + " |"
    lines = [hdr, "|" + "---|" * (len(COLS) + 3)]
    fits, summary, t_fit = {}, {}, time.perf_counter()
    _fit_source(source, heads[source], E, refine, lines, fits, summary)
    for tname in targets:
        _transfer(tname, heads[tname], source, heads[source], E, F, gF, fits, lines, summary)
    t_fit = time.perf_counter() - t_fit
    print("\n".join(lines))
    print("\ntargets: fit >= 80 % and transfer >= 70 % explained per expression (column 'all' / 'skin'):")
    for key in [(source, "all"), (source, "skin")] + [(t, w) for t in targets for w in ("copy", "all", "skin")]:
        v = [summary[key[0], key[1], e] for e in EXPRESSIONS]
        print(f"  {key[0]} {key[1]:5s} "
              + "  ".join(f"{e} {fmt(s['all'])}/{fmt(s['skin'])}" for e, s in zip(EXPRESSIONS, v))
              + f"   mean {fmt(np.mean([s['all'] for s in v]))}/{fmt(np.mean([s['skin'] for s in v]))}")
    print(f"full-rig fits and transfers: {t_fit:.1f} s")
    _print_ceilings(heads[source], E)
    return lines


def _fit_source(source, head, E, refine, lines, fits, summary):
    """Part 1: every expression fitted on the source, on all vertices and on the skin; the parameters
    go to ``fits``, the scores to ``summary`` and the table ``lines``, with a progress line each."""
    rig_s, m_s, P_s, masks_s = head
    Vs = rig_s.vertices
    for e in EXPRESSIONS:
        Xs = Vs + E[e]
        _row(lines, source, "neutral", e, region_scores(Vs, Xs, Vs, masks_s))
        for where in ("all", "skin"):
            t = time.perf_counter()
            c, jaw, lids, info = fit_rig(m_s, Xs, masks_s[where], refine=refine)
            fits[e, where] = (c, jaw, lids)
            Y = m_s.pose_parameters(c, jaw, lids)
            sc = region_scores(Y, Xs, Vs, masks_s)
            summary[source, where, e] = sc
            _row(lines, source, f"full rig, fit on {where}", e, sc)
            top = np.argsort(-c)[:4]
            print(f"  {e} fit on {where}: {time.perf_counter() - t:.1f} s, stage 1 -> 2 residual "
                  f"{info['stage1']:.3f} -> {info['stage2']:.3f}; jaw {jaw:.1f} deg, lids "
                  f"{np.array2string(lids, precision=2)}, largest contractions "
                  + ", ".join(f"{m_s.muscle_names_[i]} {c[i]:.2f}" for i in top if c[i] > 0.01), flush=True)


def _transfer(tname, head, source, src_head, E, F, gF, fits, lines, summary):
    """Part 2 on the target ``tname``: the baselines (neutral, copy by vertex index, copy through
    the correspondence) and the source's fitted parameters posed on it, into ``lines`` and ``summary``."""
    rig_s, _, P_s, _ = src_head
    Vs = rig_s.vertices
    rig_t, m_t, P_t, masks_t = head
    Vt = rig_t.vertices
    for e in EXPRESSIONS:
        Xt = Vt + E[e]
        _row(lines, tname, "neutral", e, region_scores(Vt, Xt, Vt, masks_t))
        _row(lines, tname, "copy by vertex index", e, region_scores(Vt + E[e], Xt, Vt, masks_t))
        Dc = copy_through(P_s, P_t, gF, Vs, F, E[e], Vt)
        sc = region_scores(Vt + Dc, Xt, Vt, masks_t)
        summary[tname, "copy", e] = sc
        _row(lines, tname, "copy through the correspondence", e, sc)
        for where in ("all", "skin"):
            c, jaw, lids = fits[e, where]
            sc = region_scores(m_t.pose_parameters(c, jaw, lids), Xt, Vt, masks_t)
            summary[tname, where, e] = sc
            _row(lines, tname, f"full rig, {source}'s fit on {where}", e, sc)


def _print_ceilings(head, E):
    """What one joint could do with ANY weight field (free angle per vertex), on the source head."""
    rig_s, m_s, _, masks_s = head
    Vs = rig_s.vertices
    grid = np.arange(-90.0, 90.01, 0.5)
    j = m_s.bones_.index("jaw")
    for e, label, pivot, glide in (("eyeBlink_L", "left upper-lid joint about the eye bone", m_s.lid_pivots_[0], None),
                                   ("jawOpen", "jaw joint (with its glide)", m_s.pivots_[j], m_s.jaw_glide_)):
        Xs = Vs + E[e]
        sc = region_scores(rotation_ceiling(m_s, Xs, pivot, grid, glide), Xs, Vs, masks_s)
        print(f"ceiling, {e}: the {label} with a free angle per vertex explains "
              + ", ".join(f"{k} {fmt(v)}" for k, v in sc.items() if k != "parts"))
