"""The zoo benchmark (issue #31): every shared head and copies of it, checks that need no ground truth.

    python benchmarks/zoo.py --quick                  # as-is, 2 rotations, x1000, decimated, flip, mirror; checks 1-5
    python benchmarks/zoo.py                          # every variant, checks 1-8
    python benchmarks/zoo.py --heads cowHead,camelhead --checks 1,2 --markdown
    python benchmarks/zoo.py --data /path/to/shared/data -j 2

Heads: every mesh of ``../shared/data`` with a landmark file (``zoo/*``, menpo3d's james and template,
ICT identities 000-002, the goat and the robot with ``tests/landmarks``' files), identity000 wearing five
real ICT expressions (open jaw, smile, surprise, pucker, blink; ``zoo_expressive.py``) and the ``misc``
heads without landmarks (place-only checks; the robot's expressions measured against its neutral's landmark
frame). Variants: as is; 6 random rotations (seed 31); x0.001, x1000; remeshed (Loop x1, or midpoints
where Loop leaves the surface, decimated back to the triangle count); decimated to 5k vertices (larger heads only);
one stray triangle 10 head sizes away; landmarks jittered by 1% of ex-ex and snapped back to the skin;
every triangle wound inward (``flip``, normals into the head); the head's mirror image (``mirror``, x
negated, written outward, left and right landmark names swapped); 12 holes of 0.03 head sizes cut away
from the landmarks (``holes``); cut across the landmarks' front 0.3 ex-ex behind the ear canals (else in
front of the opisthocranion: ``backcut``, a bust or trophy cut behind the ears, transfer given the landmarks
left on it); cropped level with the chin, 0.05 ex-ex under the menton (``chincut``, a face scan's crop: no
neck left). Landmarks follow the copy's rotation and scale (snapped to the surface on remeshed copies).

Checks (``zoo_checks.py``; "P" the ``place`` rig, "T" the ``transfer`` rig):
1 frame: place's front / up within 30° of the landmarks'; rotated and scaled copies' frames mapped back
  equal the as-is one to 1e-6 ("drift"). 2 jaw (T): jaw weight >= 0.9 at chin and lower lip, <= 0.1 at
  nose, nasion, vertex; no jump > 0.3 off the lip line. 3 neck (P, T): on a 15° head turn the lowest 5% of
  the vertices ("base") and of the height ("base(h)") move <= 1% of the peak. 4 pivot (P, T): head joint
  behind the gonions, below the tragions, above the neck's base, on the midline (0.02 ex-ex); humans with
  tragions: within 0.15 ex-ex of the occiput-C1 centre. 5 weights (P, T): weighted, sum 1, no NaN;
  glTF: the Khronos validator's errors (as-is only). 6 corr (T): p95 offset of the generic vertices'
  points on the remeshed / decimated / stray copies (mapped back by closest point) from the as-is ones
  <= 1% ex-ex; "6 corr rot" the same on rotated and scaled copies (mapped back exactly). 7 ARKit (humans, every
  variant): no triangle turned over, eyeBlinkLeft brings the upper lid margin >= 90% of the way to the lower. 8 landmarks (humans, as-is): automatic detection runs.
A cell: ``ok``, ``n/a: why``, ``-`` (not applicable), or the worst failing figure with the variant it came
from and how many other variants failed (``up 47° [rot3 +2]``).
"""
from __future__ import annotations

import argparse
import re
import sys
import tempfile
import time
import traceback
import zlib
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
import zoo_checks as zc  # noqa: E402
from zoo_expressive import EXPRESSIONS, IDENTITY, expressive_heads  # noqa: E402

import autobones  # noqa: E402
from autobones.errors import AutobonesError  # noqa: E402
from autobones.io.landmarks import read_landmarks  # noqa: E402
from autobones.io.mesh import load_mesh  # noqa: E402

DATA = ROOT.parent / "shared" / "data"
TESTS_LM = ROOT / "tests" / "landmarks"
FIXED = {  # heads outside zoo/: name -> (mesh, landmarks or None); landmarks in tests/ start with "tests/", meshes
    # in the project too (Blender's Suzanne: program output, tests/data/LICENSES.md) with "tests/data/"
    "suzanne": ("tests/data/blender/suzanne.obj", "tests/suzanne.landmarks.json"),
    "james": ("menpo3d/james.obj", "menpo3d/james.landmarks.json"),
    "template": ("menpo3d/template.ply", "menpo3d/template.landmarks.json"),
    **{f"identity00{k}": (f"ict/identity00{k}.obj", f"ict/identity00{k}.landmarks.json") for k in range(3)},
    "goathead": ("misc/goathead.obj", "tests/goathead.landmarks.json"),
    "robot_head_neutral": ("misc/robot_head_neutral.obj", "tests/robot_head_neutral.landmarks.json"),
    **{n: (f"misc/{n}.obj", None) for n in ("LeePerrySmith", "demosthenes-low-res", "fran_cut", "fsaverage_head",
                                           "koala_low_resolution", "robot_head_Angry", "robot_head_Sad",
                                           "robot_head_Surprised")},
}
# heads without landmarks of their own whose frame another head's landmarks give: the robot's three expressions
# are its neutral head's vertices, a third of them moved (eyes, brows, mouth) and its body still, so the neutral's
# landmark frame holds for them (check 1, and the heights of check 3); nothing else reads these landmarks
FRAME_FROM = {n: "tests/robot_head_neutral.landmarks.json"
              for n in ("robot_head_Angry", "robot_head_Sad", "robot_head_Surprised")}
HUMAN = {"human_man", "human_woman", "james", "template", "identity000", "identity001", "identity002",
         "LeePerrySmith", "demosthenes-low-res", "fran_cut", *(f"{IDENTITY}_{e}" for e in EXPRESSIONS)}
VARIANTS = ("as-is", *(f"rot{k}" for k in range(1, zc.ROTATIONS + 1)), "x0.001", "x1000", "remesh", "dec5k", "stray",
            "jitter", "flip", "mirror", "holes", "backcut", "chincut")
QUICK = ("as-is", "rot1", "rot2", "x1000", "dec5k", "flip", "mirror")
COLUMNS = (("0 rig", 0), ("1 frame", 1), ("2 jaw", 2), ("3 neck P", 3), ("3 neck T", 3), ("4 pivot P", 4), ("4 pivot T", 4),
           ("5 weights", 5), ("5 glTF", 5), ("6 corr", 6), ("6 corr rot", 6), ("7 ARKit", 7), ("8 landmarks", 8))
CELL_MAX = 52


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def heads_in(data):
    """name -> (mesh path, landmark path or None): zoo/ (every landmark file with its mesh) and FIXED."""
    out = {}
    for lm in sorted((data / "zoo").glob("*.landmarks.json")):
        name = lm.name[:-len(".landmarks.json")]
        mesh = next((p for p in (data / "zoo" / f"{name}{e}" for e in (".obj", ".off", ".ply")) if p.exists()), None)
        if mesh is not None:
            out[name] = (mesh, lm)
    for name, (mesh, lm) in FIXED.items():
        lm = None if lm is None else (TESTS_LM / lm[6:] if lm.startswith("tests/") else data / lm)
        mesh = ROOT / mesh if mesh.startswith("tests/data/") else data / mesh
        if mesh.exists():
            out[name] = (mesh, lm)
    out.update(expressive_heads(data))   # ICT identity000 wearing real expressions (zoo_expressive.py)
    return out


# ------------------------------------------------------------------------------------- rigs and checks
def attempt(fn):
    """(value, None) or (None, Result) for a refusal (AutobonesError) or an error."""
    try:
        return fn(), None
    except AutobonesError as exc:
        msg = "refused: " + " ".join(str(exc).split())
        return None, zc.Result("refused", msg, 100.0, [("", msg)])
    except Exception as exc:  # noqa: BLE001  (a benchmark cell, never a crash)
        msg = f"error: {type(exc).__name__}: {' '.join(str(exc).split())}"
        log(traceback.format_exc())
        return None, zc.Result("error", msg, 100.0, [("", msg)])


def guarded(fn, *args):
    result, err = attempt(lambda: fn(*args))
    return err or result


NO_RIG = zc.Result("norig", "no rig")
BAD = ("fail", "error", "refused")


def merge(parts):
    """One cell from several Results (``{"P": r, "T": r}``), each failing text prefixed by its label."""
    parts = {k: r for k, r in parts.items() if r is not None and r.status != "norig"}
    if not parts:
        return None
    bad = [(k, r) for k, r in parts.items() if r.status in BAD]
    if not bad:
        ok = [r for r in parts.values() if r.status == "ok"]
        return ok[0] if ok else next(iter(parts.values()))
    worst = max(bad, key=lambda kr: kr[1].severity)[1]
    notes = [(k or lab, m) for k, r in bad for lab, m in r.notes]
    text = "; ".join(f"{k} {r.status if r.notes else r.text}" if k else r.text for k, r in bad)
    return zc.Result(worst.status, text, worst.severity, notes)


@dataclass
class Head:
    name: str
    human: bool
    lm: dict
    unit: float
    ref: dict                   # landmark frame (None without landmarks)
    up: np.ndarray = None       # the up used for heights (landmarks', else the as-is place rig's)
    rotation0: np.ndarray = None
    corr0: tuple = None         # (P0, ok0, V0, F0) of the as-is transfer
    drift: list = field(default_factory=list)


def turned(ref, R):
    """The landmark frame ``ref`` of a copy ``x' = R x``; a mirror (det R < 0) keeps left = up x front."""
    if ref is None:
        return None
    out = {k: R @ v for k, v in ref.items()}
    out["left"] = np.cross(out["up"], out["front"])
    return out


def body_checks(head, var, rig, ref, checks, tag):
    """Checks 3 (neck base), 4 (pivot) and 5 (weights) of either rig; ``tag`` "P" or "T" names the cells."""
    out = {}
    if 3 in checks and var.name == "chincut":
        # cropped at the chin, nothing is left of the neck: its lowest vertices are the chin, which turns
        # with the head (held still, they counted as a pass where a rig took the lips for the chin)
        out[f"3 neck {tag}"] = zc.na("cropped at the chin: no neck")
    elif 3 in checks:
        out[f"3 neck {tag}"] = guarded(zc.check_neck_base, rig, var.R @ head.up, var.core,
                                       zc.chin_height(var.truth, var.R @ head.up))
    if 4 in checks:
        out[f"4 pivot {tag}"] = guarded(zc.check_pivot, rig, var.truth, ref, var.core, head.human)
    if 5 in checks:
        out["5 weights"] = guarded(zc.check_weights, rig)
    return out


def place_checks(head, var, rig, checks):
    out = {}
    ref = turned(head.ref, var.R)
    if 1 in checks:
        res = zc.check_frame(rig, ref)
        if var.name.startswith(("rot", "x")) and head.rotation0 is not None:
            entries, deg = zc.frame_drift(rig.frame.rotation, head.rotation0, var.R)
            head.drift.append((deg, var.name, entries))
            if entries > zc.DRIFT:
                drift = (f"drift {deg:.1f}°" if deg >= 0.1 else f"drift {deg:.1e}°", 1 + deg)
                fails = [] if res.status != "fail" else [(t, res.severity) for t in res.text.split(", ")]
                res = zc.Result.of(fails + [drift])
            elif res.status == "na":   # no landmarks: the drift is the whole check
                res = zc.Result("ok")
        out["1 frame"] = res
    out.update(body_checks(head, var, rig, ref, checks, "P"))
    return out


def transfer_checks(head, var, rig, details, checks):
    out = {}
    ref = turned(head.ref, var.R)
    if 2 in checks:
        out["2 jaw"] = guarded(zc.check_jaw, rig, var.truth, var.lm)
    out.update(body_checks(head, var, rig, ref, checks, "T"))
    if 6 in checks and var.name == "as-is":
        head.corr0 = (details["correspondence"], details["reliable"], var.V, var.F)
    elif 6 in checks and head.corr0 is not None and var.name not in ("jitter", "mirror"):
        P0, ok0, V0, F0 = head.corr0
        p95, _ = zc.correspondence_offset(details["correspondence"], P0, ok0 & details["reliable"], V0, F0,
                                          var.back, var.snap)
        column = "6 corr" if var.snap or var.name == "stray" else "6 corr rot"
        out[column] = zc.check_correspondence(p95 / head.unit)
    if 7 in checks and head.human:
        out["7 ARKit"] = guarded(zc.check_arkit, rig, var.truth, var.R @ head.up)
    return out


def validate(rig, folder, tag):
    path = Path(folder) / f"{tag}.glb"
    rig.save(str(path))
    return zc.check_gltf(path)


def rig_checks(head, var, checks, folder):
    """Every selected check on one copy: {column: Result}; ``0 rig`` says whether the rigs were made."""
    cells, t = {}, time.perf_counter()
    want_place = bool(checks & {1, 3, 4, 5})
    want_transfer = var.lm is not None and bool(checks & {2, 3, 4, 5, 6, 7})
    prig = trig = perr = terr = None
    if want_place:
        prig, perr = attempt(lambda: autobones.place((var.V, var.F)))
        if var.name == "as-is" and prig is not None:
            head.rotation0 = prig.frame.rotation
            head.up = head.up if head.up is not None else prig.frame.rotation[1]
        if perr is not None:
            cells.update({c: NO_RIG for c in ("1 frame", "3 neck P", "4 pivot P", "5 weights")})
        elif head.up is not None:
            cells.update(place_checks(head, var, prig, checks))
    tp = time.perf_counter() - t
    if want_transfer:
        details = {}
        arkit = 7 in checks and head.human
        trig, terr = attempt(lambda: autobones.transfer((var.V, var.F), var.lm, details=details, arkit=arkit))
        if terr is not None:
            cells.update({c: NO_RIG for c in ("2 jaw", "3 neck T", "4 pivot T", "6 corr", "6 corr rot", "7 ARKit")})
        elif head.up is not None:
            tc = transfer_checks(head, var, trig, details, checks)
            if "5 weights" in tc:
                tc["5 weights"] = merge({"P": cells.get("5 weights"), "T": tc["5 weights"]})
            cells.update(tc)
    made = lambda rig, err, want: None if not want else err or zc.Result("ok")  # noqa: E731
    cells["0 rig"] = merge({"P": made(prig, perr, want_place), "T": made(trig, terr, want_transfer)})
    if 5 in checks and var.name == "as-is":
        cells["5 glTF"] = (zc.na("validator not installed") if not zc.validator_installed() else
                           merge({"P": prig and guarded(validate, prig, folder, "place"),
                                  "T": trig and guarded(validate, trig, folder, "transfer")}))
    log(f"  {head.name} {var.name}: {len(var.V)} vertices, place {tp:.1f} s, total {time.perf_counter() - t:.1f} s"
        + "".join(f"; {c} {r.text}" for c, r in cells.items() if r is not None and r.text != "ok"))
    return cells


def landmarks_cell(head, V, F):
    """Check 8: automatic landmarks run on a human head (and how far they are from the given ones)."""
    found, err = attempt(lambda: autobones.detect_landmarks((V, F)))
    if err is not None:
        return zc.na("MediaPipe extra not installed") if "pip install" in err.text else err
    if not head.lm:
        return zc.Result("ok", f"ok ({len(found)})")
    shared = [n for n in found if n in head.lm]
    e = np.mean([np.linalg.norm(found[n] - head.lm[n]) for n in shared]) / head.unit if shared else np.nan
    return zc.Result("ok", f"ok ({len(found)}, {e:.1%})")


# ------------------------------------------------------------------------------------- one head
def run_head(name, mesh, lm_path, variants, checks):
    """Every copy of one head: (name, {column: [(variant, Result)]}, seconds, (largest frame drift in
    degrees, its variant) or None). Never raises."""
    t = time.perf_counter()
    found = {c: [] for c, _ in COLUMNS}
    loaded, err = attempt(lambda: (load_mesh(mesh), None if lm_path is None else read_landmarks(lm_path)))
    if err is not None:
        return name, {**{c: [] for c, _ in COLUMNS}, "0 rig": [("load", err)]}, time.perf_counter() - t, None
    (V, F), lm = loaded
    if lm is not None:
        lm = {n: np.asarray(p, dtype=np.float64) for n, p in lm.items()}
    head = Head(name, name in HUMAN, lm, zc.unit(lm, V), zc.landmark_frame(V, F, lm))
    if lm is None and name in FRAME_FROM:
        head.ref = zc.landmark_frame(V, F, {n: np.asarray(p, dtype=np.float64)
                                            for n, p in read_landmarks(TESTS_LM / FRAME_FROM[name][6:]).items()})
    head.up = None if head.ref is None else head.ref["up"]
    with tempfile.TemporaryDirectory(prefix="zoo_") as folder:
        for vname in variants:
            var, err = attempt(lambda: zc.make_variant(vname, V, F, lm, zlib.crc32(name.encode())))
            if var is None and err is None:
                continue
            if err is None:
                cells, err = attempt(lambda: rig_checks(head, var, checks, folder))
            cells = {"0 rig": err} if err is not None else cells
            for c, r in cells.items():
                if r is not None:
                    found[c].append((vname, r))
    if 8 in checks and head.human:
        found["8 landmarks"].append(("as-is", landmarks_cell(head, V, F)))
    if lm is None:
        for c in ("2 jaw", "3 neck T", "4 pivot T", "6 corr", "6 corr rot"):
            found[c] = [("as-is", zc.na("no landmarks"))]
    drift = max(head.drift) if head.drift else None
    if drift:
        log(f"  {name}: frame drift over rotated / scaled copies {drift[0]:.3g}° ({drift[1]})")
    return name, found, time.perf_counter() - t, drift


def summarise(results):
    """[(variant, Result)] -> one cell Result: the worst failure with its variant and how many other
    variants failed, then the variants that were refused or errored (messages in the notes), else ok,
    else the n/a reason; "no rig" when no variant had the rig; None: not run."""
    results = [(v, r) for v, r in results if r is not None]
    if not results:
        return None
    rigged = [(v, r) for v, r in results if r.status != "norig"]
    if not rigged:
        return zc.Result("norig", "no rig", 50.0)
    fails = sorted([(v, r) for v, r in rigged if r.status == "fail" and not r.notes], key=lambda vr: -vr[1].severity)
    parts = []
    if fails:
        more = f" +{len(fails) - 1}" if len(fails) > 1 else ""
        parts.append(f"{fails[0][1].text} [{fails[0][0]}{more}]")
    broken = [(v, r) for v, r in rigged if r.notes]
    for kind in ("refused", "error"):
        vs = [v for v, r in broken if any(m.startswith(kind) for _, m in r.notes)]
        labels = sorted({lab for _, r in broken for lab, m in r.notes if m.startswith(kind) and lab})
        if vs:
            parts.append(f"{'/'.join(labels) + ' ' if labels else ''}{kind} [{', '.join(vs)}]")
    if parts:
        status = "fail" if fails else broken[0][1].status
        return zc.Result(status, "; ".join(parts), fails[0][1].severity if fails else 100.0)
    ok = [r for _, r in rigged if r.status == "ok"]
    return ok[0] if ok else rigged[0][1]


def error_notes(done):
    """One line per distinct refusal / error message (numbers aside), with the heads, rigs and variants."""
    seen = {}
    for name, found, _, _ in done:
        for results in found.values():
            for v, r in results:
                for lab, msg in (r.notes if r is not None else ()):
                    rec = seen.setdefault(re.sub(r"\d+(\.\d+)?", "#", msg), {"msg": msg, "heads": {}})
                    labs, vs = rec["heads"].setdefault(name, (set(), []))
                    labs.add(lab)
                    vs.append(v) if v not in vs else None
    out = []
    for rec in seen.values():
        where = ", ".join(f"{n}{' ' + '/'.join(sorted(labs - {''})) if labs - {''} else ''} [{', '.join(vs)}]"
                          for n, (labs, vs) in rec["heads"].items())
        many = len(rec["heads"]) > 1
        out.append(f"{len(rec['heads'])} heads: {where}: {rec['msg']}" + (" (figures of the first)" if many else "")
                   if many else f"{where}: {rec['msg']}")
    return out


def applies(column, name, checks):
    number = dict(COLUMNS)[column]
    return (number == 0 or number in checks) and (number not in (7, 8) or name in HUMAN)


def table(rows, checks, markdown):
    """rows: [(name, {column: Result or None})] -> the table text and the footnotes of long cells."""
    cols = [c for c, n in COLUMNS if n in checks or n == 0]
    notes, body = [], []
    for name, cells in rows:
        line = [name]
        for c in cols:
            r = cells.get(c)
            text = "-" if r is None else r.text
            if len(text) > CELL_MAX and not markdown:
                notes.append(f"[{len(notes) + 1}] {name}, {c}: {text}")
                text = text[:CELL_MAX - 6].rstrip() + f"… [{len(notes)}]"
            line.append(text)
        body.append(line)
    head = ["head"] + cols
    if markdown:
        out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        out += ["| " + " | ".join(x.replace("|", "/") for x in line) + " |" for line in body]
    else:
        w = [max(len(x[i]) for x in [head] + body) for i in range(len(head))]
        out = ["  ".join(x.ljust(w[i]) for i, x in enumerate(line)).rstrip() for line in [head] + body]
    return "\n".join(out), notes


def summary_line(rows, variant_counts):
    cells = [r for _, cs in rows for r in cs.values() if r is not None and r.status not in ("na", "norig")]
    passed = sum(r.status == "ok" for r in cells)
    runs = [r for rs in variant_counts for _, r in rs if r is not None and r.status not in ("na", "norig")]
    full = [n for n, cs in rows if all(r is None or r.status in ("ok", "na") for r in cs.values())]
    return (f"checks passed: {passed}/{len(cells)} head cells ({sum(r.status == 'ok' for r in runs)}/{len(runs)} "
            f"head-variant checks); heads fully passing: {len(full)}/{len(rows)}"
            + (f" ({', '.join(full)})" if full else ""))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="as-is, 2 rotations, x1000, decimated; checks 1-5")
    ap.add_argument("--heads", help="comma-separated head names (default: all)")
    ap.add_argument("--checks", help="comma-separated check numbers 1-8 (default: 1-5 quick, 1-8 full)")
    ap.add_argument("--variants", help="comma-separated variants (default: all, or the quick set)")
    ap.add_argument("--markdown", action="store_true", help="a markdown table (for benchmarks/README.md)")
    ap.add_argument("--data", type=Path, default=DATA, help="the shared data folder (default ../shared/data)")
    ap.add_argument("-j", "--jobs", type=int, default=1, help="heads in parallel processes (default 1)")
    args = ap.parse_args(argv)
    heads = heads_in(args.data)
    if args.heads:
        wanted = [h.strip() for h in args.heads.split(",") if h.strip()]
        unknown = [h for h in wanted if h not in heads]
        if unknown:
            ap.error(f"unknown heads {', '.join(unknown)}; known: {', '.join(heads)}")
        heads = {h: heads[h] for h in wanted}
    try:
        checks = ({int(c) for c in args.checks.split(",")} if args.checks else
                  set(range(1, 6)) if args.quick else set(range(1, 9)))
    except ValueError:
        ap.error(f"--checks {args.checks}: expected numbers 1-8, comma-separated")
    variants = tuple(args.variants.split(",")) if args.variants else QUICK if args.quick else VARIANTS
    bad = [v for v in variants if v not in VARIANTS]
    if bad:
        ap.error(f"unknown variants {', '.join(bad)}; known: {', '.join(VARIANTS)}")
    if "as-is" in variants:
        variants = ("as-is",) + tuple(v for v in variants if v != "as-is")  # first: the others compare to it
    t = time.perf_counter()
    log(f"zoo: {len(heads)} heads x {len(variants)} variants, checks {sorted(checks)}")
    jobs = [(n, m, lm, variants, checks) for n, (m, lm) in heads.items()]
    if args.jobs > 1:
        with ProcessPoolExecutor(args.jobs) as pool:
            done = list(pool.map(run_head, *zip(*jobs)))
    else:
        done = [run_head(*job) for job in jobs]
    rows, raw = [], []
    for name, found, seconds, _ in done:
        log(f"{name}: {seconds:.1f} s")
        rows.append((name, {c: summarise(found[c]) if applies(c, name, checks) else None for c, _ in COLUMNS}))
        raw.extend(found[c] for c, _ in COLUMNS if applies(c, name, checks))
    text, notes = table(rows, checks, args.markdown)
    print(text)
    notes += error_notes(done)
    if notes:
        print("\n" + "\n".join(("- " if args.markdown else "") + n for n in notes))
    print("\n" + summary_line(rows, raw))
    drifts = [(d[0], n, d[1]) for n, _, _, d in done if d]
    if drifts:
        ok = [n for n, _, _, d in done if d and d[2] <= zc.DRIFT]
        print(f"frame drift of the rotated / scaled copies: {len(ok)}/{len(drifts)} heads within 1e-6; largest "
              + ", ".join(f"{n} {d:.3g}° ({v})" for d, n, v in sorted(drifts, reverse=True)[:3]))
    print(f"{len(heads)} heads, variants {', '.join(variants)}; {time.perf_counter() - t:.0f} s")


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:
        traceback.print_exc()
        sys.exit(130)
