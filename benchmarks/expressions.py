"""Can the rig express a face?  Issue #4's proof: the full expression rig's fit (1) and
transfer (2), and the placed bones alone (3).

Run by hand, not by the tests::

    python benchmarks/expressions.py            # everything (~4 min on 2 cores)
    python benchmarks/expressions.py --part rig # parts 1 and 2 only (~8 min with --refine 0, 2026-12-02)
    python benchmarks/expressions.py --part rig --refine 0   # no nonlinear refinement
    python benchmarks/expressions.py --quick    # bones: sparse and dense only, no rigid variant
    python benchmarks/expressions.py --sweeps 60  # more rigid block-descent sweeps
    python benchmarks/expressions.py --part ict57 --refine 0   # ICT's AU shapes, remeshed transfer (~20 min)
    python benchmarks/expressions.py --part ict57 --shapes jawOpen eyeBlink_L --identities identity003
    python benchmarks/expressions.py --part ceiling   # what any contractions of the fields could explain (~8 min)
    python benchmarks/expressions.py --part au-shapes # AUs through the head's ARKit shapes vs muscles (~5 min)
    python benchmarks/expressions.py --captures NEUTRAL.obj A.obj B.obj --landmarks L.json   # your own captures

Part "au-shapes" (issue #34 item 2; not run by "all"): benchmarks/au_shapes.py, see its docstring.
``--captures`` (issue #34 item 4): the rest of the command line goes to benchmarks/captures.py, which
scores a rig on any neutral and its expressions (ARKit and AU targets' explained fraction, presets).

Code: this file is the command line. The parts are in benchmarks/expression_full_rig.py (1 and 2),
expression_bones.py (3) and expression_ict57.py ("ict57", "ceiling"); their fits (``fit_rig``,
``SharedSolves``, ``LBSFit``, ``fit_rigid``, ``rotation_ceiling``) in expression_fitting.py; the
heads, scores and table helpers they share (``rig_head``, ``explained``, ``copy_through``) in
expression_heads.py.

Parts 1 and 2 (``full_rig_benchmark``): identity002 rigged by ``transfer`` with its
landmarks, ``ExpressionModel`` fitted to each expression (``fit_rig``: grid over
jaw and lids with bounded linear least squares over the muscle contractions (40 since the sphincters), then
``scipy.optimize.least_squares`` on the full nonlinear pose), on all vertices and
on the skin only; the same parameters applied to identity000 and identity001,
with the baselines neutral, copy by vertex index (100 % by construction: ICT's
identities share one displacement per expression) and copy through the
transfer's dense correspondence (``copy_through``). Scores per vertex set: all,
skin (``model.skin_``), parts (the rest) and the skin regions of the transferred
``region`` field (``REGIONS``).

Ceilings (after the table): what one joint could explain with ANY weight field, on identity002:
each vertex turns about the joint's axis (canonical +X through its pivot) by its own best angle
(``rotation_ceiling``; 0.5-degree grid), for the left upper lid in eyeBlink_L and the jaw (with its
condyle glide) in jawOpen. Where this is below the target, no lid or jaw weights can reach it and
the rest must come from the muscles.

Part 3, bones alone, follows.

Part "ict57" (``ict57_benchmark``, issue #16 item 3; not run by "all"): every ICT-FaceKit shape the
AU <-> ARKit table maps (``au_arkit`` in ``generic_rig/expressions.json``: 34 shapes, both halves
where ICT splits them, from ``ict_facekit_shapes.npz``) fitted by ``fit_rig`` on identity002 (ICT's
triangulation; skin and all, as above), and the same parameters applied on identity000 and
identity001 **remeshed** (``remesh`` of benchmarks/arkit.py: one Loop subdivision, then
``fast_simplification`` back; no vertex or triangle is ICT's), each rigged by ``transfer`` with
ICT's neutral landmarks carried onto it as benchmarks/arkit.py's ``run_identity`` does. The truth
at a remeshed vertex is the ICT displacement interpolated at its closest point on the identity,
in the part it came from. Beside it, the copy through the correspondence (``copy_through``).
Stage 1's grid solves are shared between the shapes (``SharedSolves``: ``linear_pose`` and its QR
do not depend on the target), which gives ``_solve_linear``'s answers (checked at the start).
The "tissue" columns pose the same fitted parameters with the layered tissue pass (issue #16 item 1,
``pose_parameters(..., tissue=True)``); the fit does not search through the tissue.

Data: ICT-FaceKit (``../shared/data/ict``), a linear model whose neutral head
``generic_neutral_mesh.obj`` and four real expression shapes (``jawOpen``,
``mouthSmile_L``, ``eyeBlink_L``, ``browInnerUp_L``) share one vertex list
(26,719 vertices; ``load_mesh`` keeps the file's order, which is checked).

Rigs: ``autobones.place`` of the neutral head at sparse / medium / dense, and
dense with the head's landmarks (adds the transferred jaw and eye bones, facial
bones parented to head or jaw). Plus two references: "neutral" (no motion, 0 %)
and "global affine" (one bone weighted 1 everywhere).

Fit, weights FIXED: the best per-bone transforms reproducing an expression by
linear blend skinning, x_i ~ sum_j w_ij (A_j v_i + t_j), A_j a free 3x3 affine,
t_j a translation (12 unknowns per bone). Each output coordinate c separates:
x_ic = sum_j w_ij [v_i, 1] . p_jc, an (n x 4b) sparse design matrix solved three
times through its (4b x 4b) normal equations (``scipy.linalg.lstsq`` on them,
so bones the data do not pin down get the minimum-norm answer). Coordinates are
centred and scaled before the solve, for conditioning. Two weight sets:

- "4 infl": ``autobones.io.gltf.top_influences(W, 4)``, the weights as exported;
- "all": the full ``rig.weights``.

Optional "rigid" variant (skin, 4 influences, A_j a rotation): block coordinate
descent, each bone in turn solved by weighted Procrustes against what the other
bones leave, started from the affine fit projected to rotations; ``--sweeps``
Gauss-Seidel sweeps (never worse than its start, which is checked).

Metric (issue #4): explained = 1 - ||residual|| / ||displacement||, Frobenius
norms over a vertex set, displacement = expression - neutral, residual =
fitted - expression; 100 % is exact, 0 % is no better than not moving
(negative: the fit moves a region more wrongly than leaving it still).

The ICT mesh is 56 connected parts: the skin (the largest, 14,062 vertices:
face, scalp, ears, neck, mouth and eye sockets) plus teeth, gums, tongue,
eyeballs and eye-blend shells. Those inner parts carry most of some
expressions' displacement (jawOpen: 232.6 over all vertices, 129.4 on the
skin; eyeBlink_L 22.8 vs 8.8) and get bone-heat weights from bones they are not
attached to. So two fits per row:

- all: fitted and scored over every vertex (the issue's literal wording);
- skin: fitted and scored over the skin only, and from that same skin fit,
- lower / upper: the skin's "moved" vertices (||displacement|| > 1 % of that
  expression's largest on the skin) below / at or above the nose tip (landmark
  ``pronasale``; the mesh is +Y up). Fewer than 50 moved vertices in a region
  prints "-".

Lip check: the lips are the skin vertices of region ``lips`` of the transferred
labelled generic rig (the same on every rig: one mesh) on the outer surface
(z > cheilion z - 0.7; deeper ones are the mouth socket); upper lip above the
line stomion -> cheilion (in |x|), lower below, mouth corners (|x| > 0.8 of the
cheilion's) left out. A lip vertex is "mixed" when a bone other than ``head``
gives it weight >= 0.2 and also gives weight >= 0.2 to some vertex of the
other lip (full weights). ``head`` is left out: it is the parent that stays
still, not a mouth bone.

Self-check before the table: the neutral shape is fitted with zero residual
(identity transforms), and a rigid motion of the whole head is explained
>= 99.9 % by every rig and weight set.
"""
from __future__ import annotations

import argparse
import sys

from expression_bones import bones_benchmark
from expression_full_rig import full_rig_benchmark
from expression_heads import ICT, machine
from expression_ict57 import ceiling_benchmark, ict57_benchmark


def parser():
    """The command line (all but ``--captures``, which hands the rest to benchmarks/captures.py)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="sparse and dense only, no rigid variant")
    ap.add_argument("--sweeps", type=int, default=30, help="rigid variant: block-descent sweeps (0: skip it)")
    ap.add_argument("--part", choices=list(PARTS), default="all",
                    help="rig: the full-rig fit and transfer (parts 1, 2) only; bones: bones alone (part 3) only; "
                         "ict57: every ICT shape the AU <-> ARKit table maps, transferred to remeshed identities "
                         "(not part of 'all'); ceiling: what any contractions of the muscle fields could explain "
                         "of those shapes on identity002 (not part of 'all'); au-shapes: every mapped AU and the "
                         "six emotions through the head's ARKit shapes against the muscles, on held-out ICT "
                         "identities (benchmarks/au_shapes.py; not part of 'all')")
    ap.add_argument("--variants", nargs="+",
                    help="au-shapes: only these heads (identity001, 'identity000 remeshed', ...)")
    ap.add_argument("--identities", nargs="+", default=["identity000", "identity001"],
                    help="ict57: the ICT identities the fit is transferred to (remeshed)")
    ap.add_argument("--shapes", nargs="+", help="ict57: only these ICT shapes (default: every mapped one)")
    ap.add_argument("--refine", type=int, default=30,
                    help="full rig: least_squares evaluations of the nonlinear refinement (0: grid + linear only)")
    return ap


def run_rig(args):
    full_rig_benchmark(refine=args.refine)
    print()


def run_bones(args):
    bones_benchmark(quick=args.quick, sweeps=0 if args.quick else args.sweeps)


def run_all(args):
    run_rig(args)
    run_bones(args)


def run_ict57(args):
    ict57_benchmark(targets=tuple(args.identities), refine=args.refine, shapes=args.shapes)


def run_ceiling(args):
    ceiling_benchmark(shapes=args.shapes)


def run_au_shapes(args):
    import au_shapes

    au_shapes.au_shapes_benchmark(ICT, machine, **({"variants": args.variants} if args.variants else {}))


# --part -> what runs it; the order is the help's
PARTS = {"all": run_all, "rig": run_rig, "bones": run_bones, "ict57": run_ict57, "ceiling": run_ceiling,
         "au-shapes": run_au_shapes}


def main():
    if "--captures" in sys.argv[1:]:  # everything after it is captures.py's command line
        import captures

        return captures.main(sys.argv[sys.argv.index("--captures") + 1:])
    args = parser().parse_args()
    PARTS[args.part](args)


if __name__ == "__main__":
    sys.exit(main())
