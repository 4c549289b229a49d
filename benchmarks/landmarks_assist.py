"""``python benchmarks/landmarks.py --assist``: assisted landmarks (issue #35 part 2) on every landmarked head.

For each head with a landmark file (``../shared/data``: ICT, menpo3d, the zoo; the hand-placed files
of ``tests/landmarks`` for Lee Perry-Smith, the goat and the robot) the five names
:data:`autobones.landmarks.assist.REQUIRED` are taken from the file and given to
:func:`autobones.landmarks.assist.assist_landmarks`; every other name of the file is scored:
distance of the proposal from the file's point, % of the file's ex-ex. Heads whose file lacks one of
the five cannot be assisted and are listed. Targets (issue #35): human heads, 90 % of the pooled
names within 5 % of ex-ex; animals and cartoons, the median name within 5 %.

Variants (``--variants``, default ``as-is``; the zoo benchmark's copies, ``zoo_checks.make_variant``):
``rotN`` (a random rotation), ``x1000`` / ``x0.001``, ``dec5k`` (decimated to 5k vertices, heads above
that), ``remesh`` (Loop once, decimated back). The five are the copy's (rotated, scaled, or snapped to
the new surface); proposals are mapped back to the file's frame before scoring.

Reading (``--reading``): where each name is read off the fitted generic skin. ``held-out`` (default): the
calibration of :mod:`autobones.landmarks.assist_calibration` made from the human heads of the other source
families only (ict, menpo3d, misc, zoo: a head is never scored against a calibration that saw it or its
family); ``shipped``: the built-in calibration (made from all nine human heads: in-sample for them, unseen
for the animals); ``own``: the generic rig's own landmarks (no calibration).
"""
from __future__ import annotations

import sys
import time
import zlib
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import zoo  # noqa: E402
import zoo_checks as zc  # noqa: E402

from autobones.errors import AutobonesError  # noqa: E402
from autobones.io.landmarks import read_landmarks  # noqa: E402
from autobones.io.mesh import load_mesh  # noqa: E402
from autobones.landmarks.assist import REQUIRED, assist_landmarks, fit_generic, generic_skin  # noqa: E402
from autobones.landmarks.assist_calibration import calibrate, pull_back  # noqa: E402

HUMAN = zoo.HUMAN | {"generic_neutral_mesh"}
WITHIN = 5.0   # % of ex-ex


def landmarked_heads():
    """name -> (mesh path, landmark path) of every shared head with a landmark file, sorted."""
    heads = {n: (m, lm) for n, (m, lm) in zoo.heads_in(zoo.DATA).items() if lm is not None}
    heads["generic_neutral_mesh"] = (zoo.DATA / "ict/generic_neutral_mesh.obj",
                                     zoo.DATA / "ict/generic_neutral_mesh.landmarks.json")
    heads["LeePerrySmith"] = (zoo.DATA / "misc/LeePerrySmith.obj", zoo.TESTS_LM / "LeePerrySmith.landmarks.json")
    return dict(sorted(heads.items(), key=lambda kv: (kv[0] not in HUMAN, kv[0].lower())))


def family(mesh):
    """The source family of a head: its folder in the shared data set (ict, menpo3d, misc, zoo)."""
    return Path(mesh).parent.name


def human_samples(heads=None):
    """[(head, family, {name: point on the generic rest skin})] of every landmarked human head: its
    landmarks pulled back through the generic's fit from the five (assist_calibration.pull_back)."""
    out = []
    for h, (mesh, lmf) in (heads or landmarked_heads()).items():
        if h not in HUMAN:
            continue
        truth = read_landmarks(lmf)
        V, F = load_mesh(mesh)
        fit, _ = fit_generic(V, F, {n: truth[n] for n in REQUIRED})
        names = [n for n in truth if n not in REQUIRED]
        back = pull_back(np.array([truth[n] for n in names]), fit.Vg, fit.Fg, fit.P)
        out.append((h, family(mesh), dict(zip(names, back))))
    return out


def held_out_readings(samples):
    """family -> the calibrated reading from the human heads of every other family (leave one family out)."""
    g, _ = generic_skin()
    fams = sorted({f for _, f, _ in samples} | {family(m) for m, _ in landmarked_heads().values()})
    return {f: {**g.landmarks, **calibrate([(ff, p) for _, ff, p in samples if ff != f], g.vertices, g.faces)[0]}
            for f in fams}


def score(name, V, F, truth, variant, reading=None, detected=None):
    """(errors {name: % ex-ex}, confidences, seconds, omitted) of one head copy, or a string why not."""
    var = zc.make_variant(variant, V, F, truth, zlib.crc32(name.encode()))
    if var is None:
        return "n/a"
    given = {n: var.lm[n] for n in REQUIRED}
    t0 = time.perf_counter()
    try:
        out = assist_landmarks(var.V, var.F, given, reading=reading, detected=detected)
    except AutobonesError as exc:
        return f"refused: {exc}"
    secs = time.perf_counter() - t0
    unit = np.linalg.norm(truth["exocanthion_l"] - truth["exocanthion_r"])
    err = {n: 100 * float(np.linalg.norm(var.back(out.points[n]) - truth[n])) / unit
           for n in truth if n not in REQUIRED and n in out.points}
    return err, {n: out.confidence[n] for n in err}, secs, dict(out.omitted)


def run(variants=("as-is",), heads=None, reading="held-out", detected=None):
    """Print the per-head and pooled tables (markdown) for ``variants``; ``reading``: where the names are
    read off the generic skin: ``own`` (the generic's landmarks), ``shipped`` (the built-in calibration,
    made from these human heads: in-sample for them) or ``held-out`` (calibrated on the human heads of the
    other source families: what a head the calibration never saw gets)."""
    table = landmarked_heads()
    if heads:
        table = {h: table[h] for h in heads}
    readings = None
    if reading == "held-out":
        readings = held_out_readings(human_samples())
    elif reading == "own":
        own = dict(generic_skin()[0].landmarks)
    rows, lacking = [], {}
    for h, (mesh, lmf) in table.items():
        truth = read_landmarks(lmf)
        missing = [n for n in REQUIRED if n not in truth]
        if missing:
            lacking[h] = missing
            continue
        V, F = load_mesh(mesh)
        use = readings[family(mesh)] if readings is not None else own if reading == "own" else None
        for v in variants:
            r = score(h, V, F, truth, v, use, detected)
            if isinstance(r, str):
                print(f"  {h} {v}: {r}", file=sys.stderr, flush=True)
                continue
            rows.append((h, v, len(V)) + r)
            e = np.array(list(r[0].values()))
            print(f"  {h:22s} {v:7s} mean {e.mean():5.1f}% within {np.mean(e <= WITHIN) * 100:3.0f}%  {r[2]:.2f} s",
                  file=sys.stderr, flush=True)
    print(f"\n## Assisted landmarks: {', '.join(REQUIRED)} given, the rest proposed "
          f"(% of ex-ex; variants {', '.join(variants)}; reading {reading})\n")
    print("| head | group | variant | vertices | names | mean % | median % | within 5 % | worst (name) "
          "| corr(confidence, error) | omitted | s |")
    print("|---|---|---|---:|---:|---:|---:|---:|---|---:|---|---:|")
    for h, v, n, err, conf, secs, omitted in rows:
        e = np.array(list(err.values()))
        worst = max(err, key=err.get)
        c = np.array([conf[k] for k in err])
        corr = np.corrcoef(c, e)[0, 1] if len(e) > 2 and c.std() > 0 else float("nan")
        print(f"| {h} | {'human' if h in HUMAN else 'other'} | {v} | {n:,} | {len(e)} | {e.mean():.1f} "
              f"| {np.median(e):.1f} | {np.mean(e <= WITHIN) * 100:.0f} % | {err[worst]:.1f} ({worst}) "
              f"| {corr:+.2f} | {', '.join(omitted) or '-'} | {secs:.2f} |")
    print("\n| group | variant | heads | names | mean % | median % | within 5 % | target |")
    print("|---|---|---:|---:|---:|---:|---:|---|")
    for group in ("human", "other"):
        for v in variants:
            sel = [r for r in rows if r[1] == v and (r[0] in HUMAN) == (group == "human")]
            e = np.array([x for r in sel for x in r[3].values()])
            if not len(e):
                continue
            within = np.mean(e <= WITHIN) * 100
            target = (f"90 % within 5 %: {'MET' if within >= 90 else 'NOT MET'}" if group == "human" else
                      f"median within 5 %: {'MET' if np.median(e) <= WITHIN else 'NOT MET'}")
            print(f"| {group} | {v} | {len(sel)} | {len(e)} | {e.mean():.1f} | {np.median(e):.1f} | {within:.0f} % "
                  f"| {target} |")
    if lacking:
        print("\nNot assisted (the file lacks one of the five): "
              + "; ".join(f"{h} ({', '.join(m)})" for h, m in lacking.items()))
    names = sorted({k for r in rows for k in r[3]})
    print("\n| name | human copies | human mean % | human max % | other copies | other mean % |")
    print("|---|---:|---:|---:|---:|---:|")
    for k in names:
        hum = [r[3][k] for r in rows if k in r[3] and r[0] in HUMAN]
        oth = [r[3][k] for r in rows if k in r[3] and r[0] not in HUMAN]
        print(f"| {k} | {len(hum)} | {np.mean(hum) if hum else float('nan'):.1f} | "
              f"{max(hum) if hum else float('nan'):.1f} | {len(oth)} | {np.mean(oth) if oth else float('nan'):.1f} |")
    return rows


# ---------------------------------------------------------------------------------------------------------
# issue #35 part 3: the automatic landmarks refined by the generic's fit from them (measured, not shipped)


def refit_samples(variants):
    """Per (head, variant) of the human heads: the detected landmarks, the generic fitted through them (as
    ``transfer`` does without landmarks: the detector's landmarks of the generic skin onto the head's) and
    the head's own landmarks pulled back through that fit. Times: detection and fit seconds."""
    import autobones
    from autobones.rig_transfer.correspondence import dense_correspondence
    from autobones.rig_transfer.pipeline import generic_detected_landmarks

    g, jaw = generic_skin()
    gdet = generic_detected_landmarks(g)
    out = []
    for h, (mesh, lmf) in landmarked_heads().items():
        if h not in HUMAN:
            continue
        truth, (V, F) = read_landmarks(lmf), load_mesh(mesh)
        for v in variants:
            var = zc.make_variant(v, V, F, truth, zlib.crc32(h.encode()))
            if var is None:
                continue
            t0 = time.perf_counter()
            det = autobones.detect_landmarks((var.V, var.F))
            t1 = time.perf_counter()
            names = [n for n in det if n in gdet]
            P, _, _, _ = dense_correspondence(g.vertices, g.faces, var.V, var.F, {n: gdet[n] for n in names},
                                              {n: det[n] for n in names}, jaw=jaw)
            t2 = time.perf_counter()
            tv = {n: var.s * (var.R @ p) for n, p in truth.items()}   # truth in the copy's frame
            back = pull_back(np.array(list(tv.values())), g.vertices, g.faces, P)
            out.append(dict(head=h, family=family(mesh), variant=v, var=var, truth=truth, det=dict(det), P=P,
                            back=dict(zip(tv, back)), t_detect=t1 - t0, t_fit=t2 - t1))
            print(f"  refit {h} {v}: detect {t1 - t0:.2f} s, fit {t2 - t1:.2f} s", file=sys.stderr, flush=True)
    return out


def refit_run(variants=("as-is",)):
    """Detected vs refit (read off with a calibration from the other families' heads of the same variant)
    vs their mean, per head and variant, % of the file's ex-ex; pooled per variant and per name."""
    from autobones.geometry.closest import closest_points
    from autobones.landmarks.assist import read_off

    g, _ = generic_skin()
    rows = refit_samples(variants)
    errs = []   # (head, family, variant, {name: (detected, refit, mean)}, t_detect, t_fit)
    for r in rows:
        others = [(o["family"], o["back"]) for o in rows if o["variant"] == r["variant"] and o["family"] != r["family"]]
        reading = {**g.landmarks, **calibrate(others, g.vertices, g.faces)[0]}
        var, det, truth = r["var"], r["det"], r["truth"]
        names = [n for n in det if n in truth]
        Q, _ = read_off(np.array([reading[n] for n in names]), g.vertices, g.faces, r["P"])
        fit, *_ = closest_points(Q, var.V, var.F)
        unit = np.linalg.norm(truth["exocanthion_l"] - truth["exocanthion_r"])
        e = lambda p, n: 100 * float(np.linalg.norm(var.back(p) - truth[n])) / unit  # noqa: E731
        errs.append((r["head"], r["family"], r["variant"],
                     {n: (e(det[n], n), e(fit[i], n), e((det[n] + fit[i]) / 2, n)) for i, n in enumerate(names)},
                     r["t_detect"], r["t_fit"]))
    kinds = ("detected", "refit", "mean of both")
    print("\n## Automatic landmarks refined by the generic's fit (issue #35 part 3): % of the file's ex-ex\n")
    print("*refit*: the generic fitted through the detected landmarks, each name read off where the human heads "
          "of the other source families' files land on it (held out); *mean of both*: the midpoint.\n")
    print("| head | family | variant | names | " + " | ".join(f"{k} mean / max" for k in kinds) + " | detect s | fit s |")
    print("|---|---|---|---:|" + "---|" * len(kinds) + "---:|---:|")
    for h, f, v, e, td, tf in errs:
        cells = " | ".join(f"{np.mean([x[i] for x in e.values()]):.2f} / {max(x[i] for x in e.values()):.1f}"
                           for i in range(3))
        print(f"| {h} | {f} | {v} | {len(e)} | {cells} | {td:.2f} | {tf:.2f} |")
    fams = sorted({f for _, f, _, _, _, _ in errs})
    print("\n| family | " + " | ".join(f"{v}: detected / refit / mean" for v in variants) + " |")
    print("|---|" + "---|" * len(variants))
    for f in fams:
        cells = []
        for v in variants:
            sel = [e for _, ff, vv, e, _, _ in errs if ff == f and vv == v]
            cells.append(" / ".join(f"{np.mean([x[i] for e in sel for x in e.values()]):.2f}" for i in range(3))
                         if sel else "-")
        print(f"| {f} | " + " | ".join(cells) + " |")
    print("\n| variant | head x name | " + " | ".join(f"{k} pooled mean" for k in kinds)
          + " | " + " | ".join(f"{k} worst name (mean over heads)" for k in kinds) + " |")
    print("|---|---:|" + "---:|" * len(kinds) + "---|" * len(kinds))
    for v in variants + ("all",):
        sel = [e for _, _, vv, e, _, _ in errs if v in ("all", vv)]
        if not sel:
            continue
        pooled = [np.mean([x[i] for e in sel for x in e.values()]) for i in range(3)]
        names = sorted({n for e in sel for n in e})
        per = [{n: np.mean([e[n][i] for e in sel if n in e]) for n in names} for i in range(3)]
        worst = [max(p, key=p.get) for p in per]
        print(f"| {v} | {sum(len(e) for e in sel)} | " + " | ".join(f"{x:.2f}" for x in pooled) + " | "
              + " | ".join(f"{w} {p[w]:.2f}" for w, p in zip(worst, per)) + " |")
    return errs
