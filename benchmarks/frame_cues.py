"""What tells a neck cut from a face capture's opening, measured (issue #31 check 1 on cut copies).

    python benchmarks/frame_cues.py [--heads cowHead,spot] [--variants as-is,backcut,chincut] [--data ../shared/data]

``detect_frame`` reads a single planar opening either as a neck cut (up is away from it) or, when the shell is
open wide, as a face-only capture's opening (front is away from it), and lets the reference head's overlay
choose; on animals that overlay fits neither well, and the zoo's ``backcut`` and ``chincut`` copies of 12 of its
15 non-human heads stand 32-162 degrees off. This prints, for every landmarked zoo head and copy, the frame's
error against the landmarks' (``zoo_checks.landmark_frame``) and each cue ``detect_frame`` has, so a rule that
would separate the two readings can be tried against all of them at once:

- ``told`` / ``close``: what settled the front (:attr:`autobones.orient.Frame.front_check`) and whether it was
  said as a close call;
- ``open``: the shell's vector area over its area (:func:`autobones.cut_cues.open_shell_facing`);
- ``loop``: the main opening's normal against the landmarks' front and up (``-1.00 / +0.0`` faces backwards:
  a cut behind the ears; ``+0.2 / -0.97``: a neck cut), ``planar`` whether it reads as a planar cut;
- ``share``: the share of the midline profile's reach ahead of the opening, stood on it as a neck cut
  (:func:`autobones.cut_cues.cut_up_front`);
- ``wider``: the widest cross-section beyond the opening over its own, ear to ear (a neck cut opens onto a
  wider head; a face cut behind the ears is the widest section);
- ``face`` / ``neck``: the best overlay score of the face-only reading (against the reference's front parts)
  and of the head stood on the opening, where the head was taken for a face-only capture.

The closing lines give each cue's range over the rows whose frame is right and those whose frame is wrong, by
the opening's true kind: ``bottom`` (its normal within 45 degrees of the landmarks' down: a neck cut, a chin
crop), ``back`` (within 45 degrees of their back: a cut behind the ears) or ``other``.
"""
from __future__ import annotations

import argparse
import sys
import zlib
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import zoo  # noqa: E402
import zoo_checks as zc  # noqa: E402

from autobones.cut_cues import cut_cues, cut_up_front, is_planar_cut, midline_cuts, open_shell_facing  # noqa: E402
from autobones.frame_candidates import cut_candidates, shape_candidates  # noqa: E402
from autobones.geometry.sample import sample_surface  # noqa: E402
from autobones.geometry.topology import distinct_faces, without_large_parts  # noqa: E402
from autobones.io.landmarks import read_landmarks  # noqa: E402
from autobones.io.mesh import load_mesh  # noqa: E402
from autobones.orient import SAMPLE_COUNT, default_reference, detect_frame  # noqa: E402
from autobones.reference_overlay import best_part_scores, overlay_scores  # noqa: E402


def widening(P, cues, normal, size, slab=0.05):
    """The widest cross-section of the sample ``P`` (s, 3) beyond the main opening, across the symmetry
    plane (unit ``normal``), over the section at the opening: slabs ``slab`` head sizes thick."""
    d = cues["loop_normal"]
    t = (P - cues["loop_centre"]) @ -d
    width = P @ normal
    at = (t >= 0) & (t < slab * size)
    beyond = [np.ptp(width[s]) for a in np.arange(slab, 1.0, slab)
              if (s := (t >= a * size) & (t < (a + slab) * size)).sum() > 3]
    return max(beyond, default=0.0) / max(float(np.ptp(width[at])) if at.sum() > 3 else 0.0, 1e-300)


def cues_of(V, F, frame):
    """The cues ``detect_frame`` weighed for (V, F), given its ``frame``: a dict of figures."""
    F = distinct_faces(F)
    head = without_large_parts(V, F)
    P, _, _ = sample_surface(V, head, SAMPLE_COUNT, seed=0)
    normal = frame.rotation[0]
    offset = float(frame.origin @ normal)
    cues = midline_cuts(cut_cues(V, head), normal, offset)
    out = {"open": open_shell_facing(cues)[1], "planar": is_planar_cut(cues), "loop": cues["loop_normal"]}
    if out["planar"]:
        size = np.ptp(P @ frame.rotation.T, axis=0).max()
        out["share"] = cut_up_front(P, normal, offset, cues)[2]
        out["wider"] = widening(P, cues, normal, size)
    ref = default_reference()
    every = shape_candidates(P, normal, cues)
    candidates, parts, face_only = cut_candidates(P, normal, every, cues, ref)
    if face_only:
        out["face"] = min(best_part_scores(P, candidates, parts)[0])
        if out["planar"]:
            neck = [(u, f) for u, f in every if u @ -cues["loop_normal"] > 0.95]
            out["neck"] = min(overlay_scores(P, neck, ref)) if neck else None
    return out


def row(name, vname, V, F, lm, ref):
    """One printed row (str) and its figures (dict) for a copy of a landmarked head (``ref`` its landmarks'
    frame, :func:`zoo_checks.landmark_frame`)."""
    var = zc.make_variant(vname, V, F, lm, zlib.crc32(name.encode()))
    if var is None:
        return None, None
    truth = zoo.turned(ref, var.R)
    frame = detect_frame(var.V, var.F)
    err = max(zc.angle(frame.rotation[2], truth["front"]), zc.angle(frame.rotation[1], truth["up"]))
    c = cues_of(var.V, var.F, frame)
    check = frame.front_check or {}
    c.update(err=err, told=check.get("told_by", "-"), close=bool(check.get("close")))
    loop = c["loop"]
    c["kind"] = ("none" if loop is None else "bottom" if loop @ -truth["up"] > np.cos(np.radians(45))
                 else "back" if loop @ -truth["front"] > np.cos(np.radians(45)) else "other")
    fig = lambda k, f="{:.3f}": f.format(c[k]) if c.get(k) is not None else "-"  # noqa: E731
    text = (f"{name:20s} {vname:8s} {err:5.0f}° {'ok ' if err <= zc.FRAME_DEG else 'BAD'} {c['told']:15s} "
            f"{'close' if c['close'] else '     '} open {c['open']:.2f} "
            + ("loop -" if loop is None else f"loop {loop @ truth['front']:+.2f} / {loop @ truth['up']:+.2f}")
            + f" {c['kind']:6s} planar {int(c['planar'])} share {fig('share')} wider {fig('wider', '{:.2f}')}"
            f" face {fig('face')} neck {fig('neck')}")
    return text, c


def ranges(rows):
    """Lines: each cue's range over the rows of each (opening kind, right / wrong frame) class."""
    out = []
    for kind in ("bottom", "back", "other"):
        for right in (True, False):
            group = [c for c in rows if c["kind"] == kind and (c["err"] <= zc.FRAME_DEG) == right]
            if not group:
                continue
            parts = []
            for k in ("open", "share", "wider", "face", "neck"):
                v = [c[k] for c in group if c.get(k) is not None]
                if v:
                    parts.append(f"{k} {min(v):.3f}-{max(v):.3f}")
            out.append(f"{kind} openings, frame {'right' if right else 'wrong'} ({len(group)}): " + ", ".join(parts))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--heads", help="comma-separated head names (default: every landmarked head)")
    ap.add_argument("--variants", default="as-is,backcut,chincut", help="comma-separated zoo copies")
    ap.add_argument("--data", default=str(zoo.DATA), help="the shared data folder (default ../shared/data)")
    args = ap.parse_args(argv)
    heads = zoo.heads_in(Path(args.data))
    names = args.heads.split(",") if args.heads else list(heads)
    found = []
    for name in names:
        mesh, lm_path = heads[name]
        if lm_path is None:
            continue
        V, F = load_mesh(mesh)
        lm = {n: np.asarray(p, dtype=np.float64) for n, p in read_landmarks(lm_path).items()}
        ref = zc.landmark_frame(V, F, lm)
        if ref is None:
            continue
        for vname in args.variants.split(","):
            text, c = row(name, vname, V, F, lm, ref)
            if text is not None:
                print(text, flush=True)
                found.append(c)
    print()
    print("\n".join(ranges(found)))


if __name__ == "__main__":
    main()
