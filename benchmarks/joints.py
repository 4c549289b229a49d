"""Joints where the anatomy is (issue #32): each joint's distance from its anatomical place, from the ears.

    python benchmarks/joints.py                       # every head with tragions, as is, 2 rotations, x1000
    python benchmarks/joints.py --heads human_man,james --variants as-is --markdown
    python benchmarks/joints.py --given face --variants as-is,mask-behind,mask-front   # landmarks that stop at the face

Heads: every landmarked head ``benchmarks/zoo.py`` knows (``../shared/data``'s zoo, james, template, ICT
identities 000-002, the goat and the robot; LeePerrySmith with the landmarks ``autobones.detect_landmarks``
found, kept in ``tests/landmarks``), with the tragions of ``tests/landmarks/NAME.tragions.json`` added
where the landmarks have none (``tools/place_tragions.py``). Heads without tragions (cow,
camel, falcon) get the zone checks that need none.

Anatomical places, in the landmarks' frame (``zoo_checks.landmark_frame``: front opisthocranion, else the
tragions' midpoint, -> pronasale; up menton -> vertex, orthogonal), millimetres scaled by ex-ex / 90 mm:
the occiput-C1 centre of rotation 22.5 mm posterior and 22.6 mm inferior of the tragions' midpoint
(Chancey et al. 2007), the condyle 12 mm anterior of it at its height. Figures in ex-ex:

- ``P head`` / ``T head``: ``place``'s / ``transfer``'s head joint from the occiput-C1 centre;
- ``T jaw``: ``transfer``'s jaw joint from the condyle;
- ``P mid`` / ``T mid``: ``place``'s head joint / the larger of ``transfer``'s head and jaw off the
  landmarks' midplane (``zoo_checks.mirror_plane``);
- ``P neck``: ``place``'s neck joint's height above the lowest vertex (the neck's base; the issue puts
  the joint there, at C7 or the cut), range over the copies, its largest distance off the midplane
  (``mid``), and the copies where it is not below the head joint;
- ``P zone`` / ``T zone``: ``zoo_checks.check_pivot`` (behind the gonions' line, below the tragions, above
  the neck's base, on the midline within 0.02), on every head.

Bounds (issue #32, human heads): P head <= 0.15 and P mid <= 0.02; T head <= 0.15, T jaw <= 0.15. Animals
and cartoons: the zone checks. A cell shows the as-is figure, then the worst copy's when it differs
(``0.071 / 0.090 rot2``); ``verdict`` lists what fails. Transfer is given the tragions (its joints are
then placed from them, ``rig_transfer/joints.anchor_joints``): ``T head`` / ``T jaw`` measure
that step and the landmarks' similarity, not the dense warp. ``--given face``: transfer is given only
the face's landmarks (no ears, no back of the head: ``FACE_ONLY`` dropped), as from the detector or a face
scan's file. Opt-in copies (heads with tragions): ``mask-behind`` / ``mask-front``, the head cut into a
face mask by a plane 0.3 ex-ex behind / 0.5 ex-ex in front of the tragions' midpoint (landmarks' front).
"""
from __future__ import annotations

import argparse
import sys
import time
import zlib
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import zoo  # noqa: E402
import zoo_checks as zc  # noqa: E402

import autobones  # noqa: E402
from autobones.io.landmarks import read_landmarks  # noqa: E402
from autobones.io.mesh import load_mesh  # noqa: E402

VARIANTS = ("as-is", "rot1", "rot2", "x1000")
MASKS = {"mask-behind": -0.3, "mask-front": 0.5}   # ex-ex from the tragions' midpoint along the front
# what a face's landmarks lack (``--given face``): the ears and the back of the head
FACE_ONLY = ("tragion", "superaurale", "subaurale", "otobasion", "opisthocranion", "vertex", "gonion")
CONDYLE_MM = 12.0
BOUND = 0.15          # ex-ex: occiput-C1 and condyle (humans)
COLUMNS = ("P head", "T head", "T jaw", "P mid", "T mid", "P neck", "P zone", "T zone")


def heads(data):
    """name -> (mesh path, landmarks with the added tragions): zoo.py's landmarked heads."""
    out = {}
    for name, (mesh, lm_path) in zoo.heads_in(data).items():
        if lm_path is None:   # a head without shared landmarks: detected ones kept in tests/landmarks
            lm_path = zoo.TESTS_LM / f"{name}.landmarks.json"
            if not lm_path.exists():
                continue
        out[name] = (mesh, with_tragions(read_landmarks(lm_path), name))
    return out


def with_tragions(landmarks, name):
    """``landmarks`` as float arrays, with the tragions of ``tests/landmarks/NAME.tragions.json`` added
    where they have none."""
    lm = {n: np.asarray(p, dtype=np.float64) for n, p in landmarks.items()}
    extra = zoo.TESTS_LM / f"{name}.tragions.json"
    if extra.exists() and "tragion_l" not in lm:
        lm.update({n: np.asarray(p, dtype=np.float64) for n, p in read_landmarks(extra).items()})
    return lm


def targets(lm, ref, u):
    """(occiput-C1 centre, condyle) from the tragions, or (None, None)."""
    if "tragion_l" not in lm or "tragion_r" not in lm:
        return None, None
    mid = 0.5 * (lm["tragion_l"] + lm["tragion_r"])
    return zc.c1_centre(mid, u, ref), mid + (u / zc.EXEX_MM) * CONDYLE_MM * ref["front"]


def joint(rig, name):
    sk = rig.skeleton
    return sk.heads[sk.names.index(name)] if name in sk.names else None


def measure(var, ref, prig, trig):
    """{figure: value} of one copy (ex-ex units; None where it does not apply)."""
    lm, u = var.truth, zc.unit(var.truth, var.V)
    c1, condyle = targets(lm, ref, u)
    p, n = zc.mirror_plane(lm, ref)
    off = lambda j: abs(float((j - p) @ n)) / u  # noqa: E731
    dist = lambda j, t: None if j is None or t is None else float(np.linalg.norm(j - t)) / u  # noqa: E731
    out = {}
    if prig is not None:
        head, neck = joint(prig, "head"), joint(prig, "neck")
        out["P head"] = dist(head, c1)
        base = float((var.V[var.core] @ ref["up"]).min())
        out["P neck"] = (float(neck @ ref["up"] - base) / u, bool((neck - head) @ ref["up"] < 0), off(neck))
        out["P mid"] = off(head)
        out["P zone"] = zc.check_pivot(prig, lm, ref, var.core, False)
    if trig is not None:
        head, jaw = joint(trig, "head"), joint(trig, "jaw")
        out["T head"], out["T jaw"] = dist(head, c1), dist(jaw, condyle)
        out["T mid"] = max([off(head)] + ([off(jaw)] if jaw is not None else []))
        out["T zone"] = zc.check_pivot(trig, lm, ref, var.core, False)
    return out


def mask(V, F, lm, ref, ahead):
    """The head cut into a face mask: the faces wholly more than ``ahead`` ex-ex in front of the
    tragions' midpoint (landmarks' front), vertices compacted; the landmarks as they are."""
    mid = 0.5 * (lm["tragion_l"] + lm["tragion_r"])
    keep = ((V - mid) @ ref["front"] > ahead * zc.unit(lm, V))[F].all(axis=1)
    Vc, Fc = zc.compact(V, F[keep])
    return zc.Variant("mask", Vc, Fc, lm, lm, core=np.ones(len(Vc), dtype=bool))


def run_head(name, mesh, lm, variants, given="all"):
    """{variant: {figure: value}} for one head; a failed rig is an error string in its figures.
    ``given``: "all" the landmarks transfer is given, "face" without ``FACE_ONLY``'s names."""
    V, F = load_mesh(mesh)
    ref0 = zc.landmark_frame(V, F, lm)
    found = {}
    for vname in variants:
        if vname in MASKS and "tragion_l" not in lm:
            continue
        var = mask(V, F, lm, ref0, MASKS[vname]) if vname in MASKS else \
            zc.make_variant(vname, V, F, lm, zlib.crc32(name.encode()))
        if var is None:   # a copy that does not apply (dec5k of a head under 5k vertices)
            continue
        ref = zoo.turned(ref0, var.R)
        to_transfer = var.lm if given == "all" else {n: p for n, p in var.lm.items() if not n.startswith(FACE_ONLY)}
        t = time.perf_counter()
        prig, perr = zoo.attempt(lambda: autobones.place((var.V, var.F)))
        trig, terr = zoo.attempt(lambda: autobones.transfer((var.V, var.F), to_transfer))
        found[vname] = measure(var, ref, prig, trig)
        for label, err in (("P", perr), ("T", terr)):
            if err is not None:
                found[vname][f"{label} error"] = err.text
        zoo.log(f"  {name} {vname}: {time.perf_counter() - t:.1f} s")
    return found


def worst(found, key):
    """(as-is value, (worst value, its variant)) of a float figure over the copies."""
    vals = [(v[key], k) for k, v in found.items() if v.get(key) is not None]
    if not vals:
        return None, None
    first = found.get("as-is", {}).get(key)
    top = max(vals, key=lambda kv: kv[0])
    return first, top


def cell(found, key, fmt="{:.3f}"):
    first, top = worst(found, key)
    if top is None:
        return "-"
    text = "-" if first is None else fmt.format(first)
    if first is None or abs(top[0] - first) > 5e-4:
        text += f" / {fmt.format(top[0])} {top[1]}"
    return text


def zone_cell(found, key):
    fails = [(v[key], k) for k, v in found.items() if key in v and v[key].status != "ok"]
    if not any(key in v for v in found.values()):
        return "-"
    if not fails:
        return "ok"
    r, k = max(fails, key=lambda rk: rk[0].severity)
    return f"{r.text} [{k}{f' +{len(fails) - 1}' if len(fails) > 1 else ''}]"


def neck_cell(found):
    vals = [(v["P neck"], k) for k, v in found.items() if "P neck" in v]
    if not vals:
        return "-"
    h = [x[0][0] for x in vals]
    above = [k for (x, k) in vals if not x[1]]
    mid = max(x[0][2] for x in vals)
    return (f"{min(h):.2f}-{max(h):.2f}, mid {mid:.3f}" + (f", above head [{', '.join(above)}]" if above else ""))


def verdict(name, found, human):
    """What fails the issue's bounds, over every copy."""
    fails = []
    floats = (("P head", BOUND), ("T head", BOUND), ("T jaw", BOUND), ("P mid", zc.MIDLINE)) if human else ()
    for key, bound in floats:
        bad = [k for k, v in found.items() if v.get(key) is not None and v[key] > bound]
        if bad:
            fails.append(f"{key} [{', '.join(bad)}]")
    if not human:
        for key in ("P zone", "T zone"):
            bad = [k for k, v in found.items() if key in v and v[key].status != "ok"]
            if bad:
                fails.append(f"{key} [{', '.join(bad)}]")
    errors = sorted({v[k] for v in found.values() for k in v if k.endswith("error")})
    return "; ".join(fails + errors) or "pass"


def table(rows, markdown):
    head = ("head", "kind", *COLUMNS, "verdict")
    lines = [head] + rows
    if markdown:
        out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        out += ["| " + " | ".join(r) + " |" for r in rows]
        return "\n".join(out)
    widths = [max(len(r[i]) for r in lines) for i in range(len(head))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths)) for r in lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", default=str(zoo.DATA))
    ap.add_argument("--heads", help="comma-separated names (default: every landmarked head)")
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--given", choices=("all", "face"), default="all",
                    help="the landmarks transfer is given: all, or the face's only (no ears, no back of the head)")
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args(argv)
    known = heads(Path(args.data))
    names = args.heads.split(",") if args.heads else list(known)
    rows, t0 = [], time.perf_counter()
    for name in names:
        mesh, lm = known[name]
        human = name in zoo.HUMAN
        zoo.log(f"{name}")
        found = run_head(name, mesh, lm, args.variants.split(","), args.given)
        kind = ("human" if human else "animal/cartoon") + ("" if "tragion_l" in lm else ", no tragions")
        rows.append((name, kind, *(cell(found, c) for c in ("P head", "T head", "T jaw", "P mid", "T mid")),
                     neck_cell(found), zone_cell(found, "P zone"), zone_cell(found, "T zone"),
                     verdict(name, found, human)))
    print(table(rows, args.markdown))
    passed = sum(r[-1] == "pass" for r in rows)
    print(f"\n{passed} / {len(rows)} heads pass; variants {args.variants}; transfer given {args.given} landmarks; "
          f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
