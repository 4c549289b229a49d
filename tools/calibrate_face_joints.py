"""Rebuild ``generic_rig/default/face_joints.json``: where the occiput-C1 centre and the condyle sit against a
human face's landmarks, in the built-in generic rig's frame (:func:`autobones.rig_transfer.joints.face_points`).

Run from the repository root with the shared data set beside it (``../shared/data``):
``python tools/calibrate_face_joints.py [--markdown] [--dry-run]`` (about 2 minutes). Every human head of
``benchmarks/joints.py`` with ear canals (hand-placed tragions: ICT identities 000-002, menpo3d's james and
template, Lee Perry-Smith, the zoo's SMPL man and woman) gives its anatomical joints (Chancey et al. 2007:
the occiput-C1 centre 22.5 mm behind and 22.6 mm below the tragions' midpoint, the condyle 12 mm in front
of it, scaled by ex-ex / 90 mm), carried back into the generic's frame by the inverse of the similarity
that maps the generic's landmarks onto the head's face (:func:`autobones.rig_transfer.joints.face_fit`):

- ``detected``: the detector's landmarks on both skins (``place`` on a face mask);
- ``given``: the generic's contract landmarks against the head's hand-placed face names, without the
  ears, the back and top of the head and the jaw's angles (``transfer`` with a face's landmark file).

Each kind's point is the mean over the heads, each source family (its folder) weighing the same, on the
generic's landmarks' midplane. The tables printed are the honest figures: each head placed by the
generic's own joints and by the calibration **without the head's family**, in ex-ex from the anatomy;
``detected`` also on the head cut into masks 0.3 ex-ex behind and 0.5 in front of its ear canals.
"""
import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT))

CUTS = {"as is": None, "mask behind": -0.3, "mask in front": 0.5}   # ex-ex ahead of the ear canals
JOINTS = ("head", "jaw")


def detected(V, F):
    """The detector's contract landmarks on a face (dict str -> (3,)), or None where none is found."""
    from autobones.errors import AutobonesError
    from autobones.landmarks.detect import LandmarkDetector

    try:
        return {n: np.asarray(p, dtype=np.float64) for n, p in LandmarkDetector().detect(V, F, what="the face").items()}
    except AutobonesError:
        return None


def head_copies(name, mesh, lm):
    """{family, truth (joint -> (3,)), u (ex-ex), ref (landmarks' frame), given (face names), cuts
    [(cut, detected landmarks or None)]} of one head."""
    import joints as jb
    import zoo_checks as zc

    from autobones.io.mesh import load_mesh

    V, F = load_mesh(mesh)
    ref, u = zc.landmark_frame(V, F, lm), zc.unit(lm, V)
    c1, condyle = jb.targets(lm, ref, u)
    cuts = []
    for cut, ahead in CUTS.items():
        part = None if ahead is None else jb.mask(V, F, lm, ref, ahead)
        cuts.append((cut, detected(V, F) if part is None else detected(part.V, part.F)))
    given = {n: p for n, p in lm.items() if not n.startswith(jb.FACE_ONLY)}
    return {"family": Path(mesh).parent.name, "truth": {"head": c1, "jaw": condyle}, "u": u, "ref": ref,
            "given": given, "cuts": cuts}


def pulled_back(G, face, truth, motion):
    """The head's anatomical joints ``truth`` carried into the generic's frame by the inverse of the
    face's similarity from ``G`` (dict joint -> (3,)), or None where the face fits no human's; ``motion``
    the generic's face's (``pipeline.face_motion``), as ``transfer`` and ``place`` fit it."""
    from autobones.rig_transfer.joints import face_fit

    fit = face_fit(G, {n: p for n, p in face.items() if n in G}, motion)
    if fit is None:
        return None
    s, R, p0, q0 = fit
    return {j: p0 + R.T @ (t - q0) / s for j, t in truth.items()}


def calibrated(samples, G):
    """Per joint, the family-weighted mean of ``samples`` [(family, {joint: (3,)})], on ``G``'s midplane."""
    from autobones.geometry.mirror_plane import onto_plane
    from autobones.landmarks.refine import symmetry_plane

    families = sorted({f for f, _ in samples})
    plane = symmetry_plane(G)
    return {j: onto_plane(np.mean([np.mean([p[j] for f, p in samples if f == fam], axis=0) for fam in families],
                                  axis=0), *plane) for j in JOINTS}


def placed(G, face, point, motion):
    """``point`` (3,) of the generic's frame mapped onto a face by its landmarks, on their midplane."""
    from autobones.rig_transfer.joints import onto_face

    on = onto_face(G, face, {"p": point}, motion)
    return None if on is None else on["p"]


def compare(kind, G, own, heads, faces, motion):
    """Rows of (head, family, copy, joint, own, held out, front / up / left) and the two error lists per
    joint; ``faces(head)`` gives [(copy, face landmarks or None)]; each head's own samples are its as-is face."""
    samples = {}
    for name, h in heads.items():
        face = faces(h)[0][1]
        back = None if face is None else pulled_back(G, face, h["truth"], motion)
        if back is not None:
            samples[name] = (h["family"], back)
    rows, errors = [], {j: ([], []) for j in JOINTS}
    for name, h in heads.items():
        held = calibrated([s for s in samples.values() if s[0] != h["family"]], G)
        for cut, face in faces(h):
            for j in JOINTS:
                a = None if face is None else placed(G, face, own[j], motion)
                if a is None:
                    rows.append((name, h["family"], cut, j, "no human face", "-", "-"))
                    continue
                b = placed(G, face, held[j], motion)
                e = (b - h["truth"][j]) / h["u"]
                errors[j][0].append(np.linalg.norm(a - h["truth"][j]) / h["u"])
                errors[j][1].append(np.linalg.norm(e))
                rows.append((name, h["family"], cut, j, f"{errors[j][0][-1]:.3f}", f"{errors[j][1][-1]:.3f}",
                             " / ".join(f"{e @ h['ref'][k]:+.3f}" for k in ("front", "up", "left"))))
    return rows, errors, samples


def report(kind, rows, errors, markdown):
    head = ("head", "family", "copy", "joint", "generic's joint", "calibrated, family held out", "front / up / left")
    print(f"\n{kind}:")
    if markdown:
        print("| " + " | ".join(head) + " |\n|" + "---|" * len(head))
        print("\n".join("| " + " | ".join(r) + " |" for r in rows))
    else:
        print("\n".join("  ".join(f"{c:>13s}" for c in r) for r in [head, *rows]))
    for j, (before, after) in errors.items():
        for label, e in (("generic's joint", np.array(before)), ("calibrated, family held out", np.array(after))):
            print(f"{kind} {j}, {label}: {len(e)} copies, mean {e.mean():.3f}, median {np.median(e):.3f}, "
                  f"max {e.max():.3f}, within 0.15 ex-ex {int((e <= 0.15).sum())}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--markdown", action="store_true", help="print the tables as Markdown")
    ap.add_argument("--dry-run", action="store_true", help="measure and print, write nothing")
    args = ap.parse_args(argv)
    import joints as jb
    import zoo

    from autobones.generic_rig import default_rig_path
    from autobones.io.atomic import write_text_atomic
    from autobones.rig_transfer.joints import FACE_JOINTS_FILE, FACE_JOINTS_FORMAT
    from autobones.rig_transfer.pipeline import face_motion, generic_detected_landmarks, load_generic

    generic = load_generic()
    bones = list(generic.skeleton.names)
    own = {j: np.asarray(generic.skeleton.heads[bones.index(j)], dtype=np.float64) for j in JOINTS}
    heads = {n: head_copies(n, *h) for n, h in jb.heads(zoo.DATA).items() if n in zoo.HUMAN and "tragion_l" in h[1]}
    kinds = {"detected": (generic_detected_landmarks(generic, None), lambda h: h["cuts"]),
             "given": ({n: np.asarray(p, dtype=np.float64) for n, p in generic.landmarks.items()},
                       lambda h: [("as is", h["given"])])}
    out = {"format": FACE_JOINTS_FORMAT, "heads": sorted(heads),
           "families": sorted({h["family"] for h in heads.values()})}
    for kind, (G, faces) in kinds.items():
        rows, errors, samples = compare(kind, G, own, heads, faces, face_motion(generic))
        report(kind, rows, errors, args.markdown)
        out[kind] = {j: [float(x) for x in p] for j, p in calibrated(list(samples.values()), G).items()}
    if not args.dry_run:
        path = Path(default_rig_path()) / FACE_JOINTS_FILE
        write_text_atomic(path, json.dumps(out, indent=1) + "\n")
        print(f"\nwrote {path}: from {len(heads)} heads")
    return 0


if __name__ == "__main__":
    sys.exit(main())
