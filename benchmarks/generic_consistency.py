"""Is the built-in generic rig laid on different heads at the same anatomical points?

Run by hand::

    python benchmarks/generic_consistency.py                  # the fit's default landmark weight
    python benchmarks/generic_consistency.py --landmark-weight 1 30

``autobones.transfer`` puts every generic-rig vertex g at a point P_k[g] on head k (its dense
correspondence); muscles, regions and skin weights ride these points. ICT-FaceKit's identities share
one vertex list, so a point of identity a (a triangle and barycentric coordinates) names the same
anatomical point on identity b. For each ordered pair (a, b): P_a[g] is expressed on a's triangle
and evaluated on b (``autobones.rig_transfer.under_skin.ride``), and compared with P_b[g]. Error per generic vertex in % of b's outer-eye-corner
distance, mean / 95th percentile, over all generic vertices and per region of the generic rig.
The benchmark that measures the fit itself between two ICT heads is ``correspondence.py``.
"""
from __future__ import annotations

import argparse
import json
import subprocess
from pathlib import Path

import numpy as np

import autobones
from autobones.rig_transfer.pipeline import load_generic
from autobones.rig_transfer.under_skin import ride

ROOT = Path(__file__).resolve().parents[1]
ICT = ROOT.parent / "shared" / "data" / "ict"
HEADS = ("identity002", "identity000", "identity001")
REGIONS = ("lips", "eyelids", "brow", "forehead", "cheeks", "nose")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--landmark-weight", type=float, nargs="*", default=[None],
                    help="fit_surface landmark weights to compare (default: the fit's default)")
    args = ap.parse_args()
    generic = load_generic()
    region = np.asarray(generic.fields["region"]).astype(int)
    labels = list(generic.labels["region"])
    print("| landmark weight | pair | all | " + " | ".join(REGIONS) + " |")
    print("|---" * (len(REGIONS) + 3) + "|")
    for lw in args.landmark_weight:
        P, V, ex = {}, {}, {}
        for name in HEADS:
            details = {}
            kw = {} if lw is None else {"landmark_weight": lw}
            rig = autobones.transfer(str(ICT / f"{name}.obj"), str(ICT / f"{name}.landmarks.json"), details=details, **kw)
            P[name], V[name], F = details["correspondence"], np.asarray(rig.vertices), np.asarray(rig.faces)
            lm = json.loads((ICT / f"{name}.landmarks.json").read_text())["landmarks"]
            ex[name] = float(np.linalg.norm(np.subtract(lm["exocanthion_l"], lm["exocanthion_r"])))
        for a in HEADS:
            for b in HEADS:
                if a == b:
                    continue
                err = np.linalg.norm(ride(P[a], V[a], F, V[b]) - P[b], axis=1) / ex[b] * 100
                cells = [f"{err.mean():.2f} / {np.percentile(err, 95):.2f}"]
                for r in REGIONS:
                    e = err[region == labels.index(r)]
                    cells.append(f"{e.mean():.2f} / {np.percentile(e, 95):.2f}")
                print(f"| {'default' if lw is None else f'{lw:g}'} | {a} → {b} | " + " | ".join(cells) + " |", flush=True)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    print(f"\nautobones {commit}")


if __name__ == "__main__":
    main()
