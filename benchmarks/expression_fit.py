"""Does the generic skin slide on an expressive head? ``transfer`` with and without the expression fit (#34 item 1).

    python benchmarks/expression_fit.py [--quick] [--markdown]

ICT-FaceKit's shape set (``../shared/data/ict/ict_facekit_shapes.npz``) is linear: identity k wearing
expression E is ``neutral + identity_k + expression_E``, vertex for vertex the same skin as identity k
neutral. So where the built-in generic rig lands on the expressive head can be carried back to the
neutral head exactly: each generic vertex's point (``details['correspondence']``) has a triangle and
barycentric coordinates on the expressive mesh, and the same triangle of the neutral mesh gives the
skin point it sits on. Its distance from where the generic vertex lands on the neutral head itself is
how far the skin slid because the head wore an expression (% of ex-ex), per region of the generic rig
(``field/region``). No ground truth beyond ICT's own linearity is needed.

Heads: identities 003, 007, 011 (``--quick``: 003) x expressions (jawOpen, mouthSmile_L, mouthPucker,
mouthFunnel, eyeBlink_L, browDown_L); variants as is and decimated to 5k vertices (the decimated copy's
points are carried to the original expressive mesh by closest point first). The landmarks are ICT's
neutral ones carried by their barycentric coordinates. ``transfer(expression_fit=True)`` (the default)
against ``expression_fit=False``. The expression fit's space includes ICT's own shapes, so this is what
a user gets, not a left-out test: ``correspondence.py --families --expression-prior`` is that.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import autobones
from autobones.geometry.closest import closest_points
from autobones.io.mesh import load_mesh

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
EXPRESSIONS = ("jawOpen", "mouthSmile_L", "mouthPucker", "mouthFunnel", "eyeBlink_L", "browDown_L")
REGIONS_SHOWN = ("lips", "chin", "cheeks", "jaw", "nose", "eyelids", "brow", "neck")


def _decimated(V, F, vertices=5000):
    import fast_simplification

    Vd, Fd = fast_simplification.simplify(V.astype(np.float32), F.astype(np.int32), target_count=2 * vertices)
    return np.asarray(Vd, dtype=np.float64), np.asarray(Fd, dtype=np.int64)


def _landed(V, F, lm, fit):
    rig_details = {}
    rig = autobones.transfer((V, F), lm, details=rig_details, expression_fit=fit)
    return rig_details["correspondence"], rig.options["expression_fit"]


def _slide(P_expr, V_expr, V_neutral, F, P_neutral, exex):
    """(n,) % of ex-ex: each point on the expressive mesh carried to the neutral one by its triangle."""
    _, face, bary, _ = closest_points(P_expr, V_expr, F)
    back = np.einsum("ij,ijk->ik", bary, V_neutral[F[face]])
    return 100 * np.linalg.norm(back - P_neutral, axis=1) / exex


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="one identity")
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args(argv)
    shapes = np.load(DATA / "ict" / "ict_facekit_shapes.npz")
    Vn0, F = load_mesh(DATA / "ict" / "generic_neutral_mesh.obj")[:2]
    lm0 = json.loads((DATA / "ict" / "generic_neutral_mesh.landmarks.json").read_text())["landmarks"]
    names = sorted(lm0)
    _, lface, lbary, _ = closest_points(np.array([lm0[n] for n in names]), Vn0, F)
    generic = autobones.rig_transfer.pipeline.load_generic()
    region = generic.fields["region"].astype(int)
    labels = generic.labels["region"]
    ids = ["identity003"] if args.quick else ["identity003", "identity007", "identity011"]
    rows = []
    t0 = time.perf_counter()
    for ident in ids:
        Vn = shapes["neutral"].astype(np.float64) + shapes[f"identity/{ident}"]
        lm_n = {n: lbary[i] @ Vn[F[lface[i]]] for i, n in enumerate(names)}
        # the neutral head fitted the same way as the expressive one it is compared with (without the
        # expression fit a face gets the plain spline, with it the local warp: mixing the two is a slide)
        P_n = {fit: _landed(Vn, F, lm_n, fit)[0] for fit in (False, True)}
        exex = np.linalg.norm(lm_n["exocanthion_l"] - lm_n["exocanthion_r"])
        for expr in EXPRESSIONS:
            Ve = Vn + shapes[f"expression/{expr}"]
            lm_e = {n: lbary[i] @ Ve[F[lface[i]]] for i, n in enumerate(names)}
            for variant in ("as is", "decimated 5k"):
                VT, FT = (Ve, F) if variant == "as is" else _decimated(Ve, F)
                cells = {}
                for fit in (False, True):
                    P_e, record = _landed(VT, FT, lm_e, fit)
                    if variant != "as is":   # onto the original expressive surface first
                        P_e = closest_points(P_e, Ve, F)[0]
                    cells[fit] = (_slide(P_e, Ve, Vn, F, P_n[fit], exex), record)
                rows.append((ident, expr, variant, cells))
                found = ", ".join(f"{k} {v:.2f}" for k, v in list(cells[True][1].get("weights", {}).items())[:3])
                print(f"  {ident} {expr:13s} {variant:12s} slide off {cells[False][0].mean():.2f}% "
                      f"on {cells[True][0].mean():.2f}%  found: {found or 'neutral'}", flush=True)
    print(f"\n{len(rows)} heads, {time.perf_counter() - t0:.0f} s\n")
    _table(rows, region, labels)


def _table(rows, region, labels):
    """Per expression and region: mean / p95 slide, fit off -> on, pooled over identities and variants."""
    shown = [r for r in REGIONS_SHOWN if r in labels]
    print("| expression | found (first identity, as is) | " + " | ".join(f"{r} off -> on" for r in shown) + " | all |")
    print("|---|---|" + "---|" * (len(shown) + 1))
    for expr in EXPRESSIONS:
        mine = [c for (_, e, _, c) in rows if e == expr]
        if not mine:
            continue
        found = ", ".join(f"{k} {v:.2f}" for k, v in list(mine[0][True][1].get("weights", {}).items())[:2]) or "neutral"

        def cell(mask):
            off = np.concatenate([c[False][0][mask] for c in mine])
            on = np.concatenate([c[True][0][mask] for c in mine])
            return f"{off.mean():.2f} / {np.percentile(off, 95):.2f} -> {on.mean():.2f} / {np.percentile(on, 95):.2f}"

        print(f"| {expr} | {found} | " + " | ".join(cell(region == labels.index(r)) for r in shown)
              + f" | {cell(np.ones_like(region, dtype=bool))} |")
    print("\n(mean / p95 % of ex-ex that a generic vertex slid on the skin because the head wore the expression; "
          "off: expression_fit=False, on: the default)")


if __name__ == "__main__":
    main()
