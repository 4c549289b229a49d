"""Left/right symmetry of transferred rigs and their expressions (issue #4, the goat).

Run by hand, not by the tests::

    python benchmarks/symmetry.py                 # goat, robot, ICT identity002, default head
    python benchmarks/symmetry.py goat robot      # some of them
    python benchmarks/symmetry.py --compare       # each head with the symmetric fit off, auto and on

Every head is rigged by ``autobones.transfer`` with its landmark file and
``ExpressionModel`` is fitted on it. The mirror plane is the landmarks' own
(``autobones.landmarks.refine.symmetry_plane``: normal the pairs' mean ``x_l - x_r``, through
the median of the pair midpoints and midline names), so nothing assumes the file's axes. All lengths are in percent
of the head's exocanthion distance (ex-ex). Columns:

- ``lm``: landmark pairs' own mirror mismatch ``|mirror(x_l) - x_r|``, mean / max
  (a floor for everything carried from them);
- ``corr``: the dense correspondence's mirror error: generic vertex ``v`` and its
  mirror partner ``m(v)`` on the (exactly symmetric) generic skin should land on
  mirror points, ``|mirror(P[v]) - P[m(v)]|``, mean / 95th percentile;
- ``origins``, ``insertions``: the muscle pairs' mirror mismatch, mean / max over
  the 13 pairs;
- ``wires``: the wire control vertices after snapping to the skin, mean over
  pairs of the mean mismatch / max over pairs;
- ``happy``, ``AU12``: displacement asymmetry of a symmetric expression
  (happiness; AU12 on both sides), ``||D - mirror(D)|| / ||D||`` over the skin,
  ``mirror(D)`` the reflected displacement of each vertex's nearest skin vertex
  across the plane (0: symmetric; 1: as large as the motion itself);
- ``L/R``: summed displacement length on the left of the plane over the right;
- ``floor``: the same asymmetry for a displacement that is exactly symmetric in
  space (Gaussian bumps of 0.15 ex-ex at the mirror-averaged insertions): what
  the head's own asymmetry and vertex layout cost the metric.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
DATA = ROOT.parent / "shared" / "data"
sys.path.insert(0, str(ROOT))

from autobones.landmarks.refine import symmetry_plane  # noqa: E402  (the landmarks' mirror plane)
from autobones.orient import reflect  # noqa: E402

HEADS = {  # name: (mesh or None for the default head, landmark file)
    "goat": (DATA / "misc/goathead.obj", ROOT / "tests/landmarks/goathead.landmarks.json"),
    "robot": (DATA / "misc/robot_head_neutral.obj", ROOT / "tests/landmarks/robot_head_neutral.landmarks.json"),
    "ict_identity002": (DATA / "ict/identity002.obj", DATA / "ict/identity002.landmarks.json"),
    "default_head": (None, ROOT / "generic_rig/default_head.landmarks.json"),
}


def pair_mismatch(points, plane):
    """``|mirror(x_l) - x_r|`` for every ``<name>_l`` / ``<name>_r`` pair of ``points``
    (dict of str -> (3,)); (pairs,) float, input units."""
    return np.array([np.linalg.norm(reflect(points[k], *plane) - np.asarray(points[k[:-2] + "_r"]))
                     for k in points if k.endswith("_l") and k[:-2] + "_r" in points])


def mirror_partners(V, plane, mask=None):
    """(n,) index of the vertex of ``V`` (n, 3) nearest each vertex's mirror image, among
    ``mask`` (n,) bool when given."""
    idx = np.arange(len(V)) if mask is None else np.flatnonzero(mask)
    return idx[cKDTree(V[idx]).query(reflect(V, *plane))[1]]


def displacement_asymmetry(V, D, plane, mask):
    """``||D - mirror(D)|| / ||D||`` over the vertices in ``mask``: ``V`` (n, 3) rest vertices,
    ``D`` (n, 3) displacements, mirror(D) at a vertex = its mirror partner's displacement
    reflected. Dimensionless (0: symmetric)."""
    n = plane[0]
    j = mirror_partners(V, plane, mask)
    M = D[j] - 2.0 * (D[j] @ n)[:, None] * n
    return float(np.linalg.norm((D - M)[mask]) / max(np.linalg.norm(D[mask]), 1e-300))


def symmetric_bumps(V, muscles, plane, width):
    """(n, 3) displacement exactly symmetric in space: a Gaussian bump of ``width`` (units of
    ``V``) at each muscle pair's mirror-averaged insertion and its mirror image, pointing along
    the mirror-averaged muscle direction (unit amplitude)."""
    by = {m["name"]: m for m in muscles}
    n = plane[0]
    D = np.zeros_like(V)
    for k, m in by.items():
        if not (k.endswith("_l") and k[:-2] + "_r" in by):
            continue
        r = by[k[:-2] + "_r"]
        c = 0.5 * (np.asarray(m["insertion"]) + reflect(r["insertion"], *plane))
        e = np.asarray(m["insertion"]) - m["origin"]
        f = np.asarray(r["insertion"]) - r["origin"]
        e = e + f - 2.0 * (f @ n) * n
        e /= np.linalg.norm(e)
        for cc, ee in ((c, e), (reflect(c, *plane), e - 2.0 * (e @ n) * n)):
            D += np.exp(-((V - cc) ** 2).sum(axis=1) / width ** 2)[:, None] * ee
    return D


def measure(name, mesh, marks, symmetric="auto"):
    """One row of the table (a dict) for one head (``symmetric``: of ``autobones.transfer``)."""
    import autobones
    from autobones.expressions.model import ExpressionModel
    from autobones.rig_transfer.pipeline import load_generic

    t0 = time.perf_counter()
    details = {}
    rig = autobones.transfer(mesh, marks, details=details, symmetric=symmetric)
    model = ExpressionModel().fit(rig)
    seconds = time.perf_counter() - t0
    lm = {k: np.asarray(v) for k, v in rig.landmarks.items()}
    plane = symmetry_plane(lm)
    unit = 0.01 * float(np.linalg.norm(lm["exocanthion_l"] - lm["exocanthion_r"]))   # 1 % of ex-ex
    generic = load_generic()
    P = details["correspondence"]
    m = mirror_partners(generic.vertices, symmetry_plane(generic.landmarks))
    corr = np.linalg.norm(reflect(P, *plane) - P[m], axis=1) / unit
    mus = {x["name"]: x for x in rig.muscles}
    origins = pair_mismatch({k: x["origin"] for k, x in mus.items()}, plane) / unit
    insertions = pair_mismatch({k: x["insertion"] for k, x in mus.items()}, plane) / unit
    V, skin = rig.vertices, model.skin_
    wires = {w["muscle"]: V[w["vertices"]] for w in model.wires_}
    wire = np.array([np.linalg.norm(reflect(wires[k], *plane) - wires[k[:-2] + "_r"], axis=1).mean()
                     for k in wires if k.endswith("_l") and k[:-2] + "_r" in wires]) / unit
    happy = model.pose(expression="happiness") - V
    au12 = model.pose(au={12: 1.0}) - V
    side = V @ plane[0] - plane[1]
    size = np.linalg.norm(happy, axis=1) * skin
    floor = symmetric_bumps(V, rig.muscles, plane, 15.0 * unit)
    lmm = pair_mismatch(lm, plane) / unit
    return {"head": name, "s": seconds, "lm": (lmm.mean(), lmm.max()), "corr": (corr.mean(), np.percentile(corr, 95)),
            "origins": (origins.mean(), origins.max()), "insertions": (insertions.mean(), insertions.max()),
            "wires": (wire.mean(), wire.max()), "happy": displacement_asymmetry(V, happy, plane, skin),
            "AU12": displacement_asymmetry(V, au12, plane, skin),
            "L/R": size[side > 0].sum() / max(size[side < 0].sum(), 1e-300),
            "floor": displacement_asymmetry(V, floor, plane, skin),
            "symmetric": "on" if rig.options["symmetric"]["applied"] else "off"}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("heads", nargs="*", choices=[[]] + list(HEADS), help="default: all four")
    ap.add_argument("--compare", action="store_true", help="each head with transfer(symmetric='off'), 'auto' and 'on'")
    args = ap.parse_args(argv)
    print("| head | symmetric fit | lm % | corr % | origins % | insertions % | wires % | happy | AU12 | L/R | floor | s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in args.heads or list(HEADS):
        for mode in ("off", "auto", "on") if args.compare else ("auto",):
            r = measure(name, *HEADS[name], symmetric=mode)
            pair = lambda k: f"{r[k][0]:.1f} / {r[k][1]:.1f}"  # noqa: E731
            print(f"| {name} | {mode}: {r['symmetric']} | {pair('lm')} | {pair('corr')} | {pair('origins')} | "
                  f"{pair('insertions')} | {pair('wires')} | {r['happy']:.2f} | {r['AU12']:.2f} | {r['L/R']:.2f} | "
                  f"{r['floor']:.2f} | {r['s']:.1f} |", flush=True)


if __name__ == "__main__":
    main()
