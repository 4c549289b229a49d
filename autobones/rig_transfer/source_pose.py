"""The source skin posed before the landmarks' warp (:func:`autobones.rig_transfer.correspondence.fit_surface`):
its jaw opened as far as the landmarks say (:mod:`.jaw_prior`) and the expression the target wears
(:mod:`.expression_prior`). A smooth warp can neither open a mouth nor smile, and the fit's shape term
keeps the source's own edges: the posed skin is what both then warp and keep. Each function takes and
returns the source vertices ``V_src`` (n, 3) and its landmarks ``P`` (k, 3), source frame and units.
"""
from __future__ import annotations

import logging

import numpy as np

from ..geometry.closest import closest_points
from .expression_prior import check_space, fit_expression, pose, weights_by_name
from .jaw_prior import check_prior, estimate_jaw_angle, open_jaw

log = logging.getLogger("autobones.rig_transfer.correspondence")


def open_source_jaw(V_src, F_src, P, Q, jaw, details):
    """The source skin ``V_src`` (n, 3) and its landmarks ``P`` (k, 3) with the jaw opened to the
    target landmarks ``Q`` (k, 3) (:mod:`.jaw_prior`); each landmark moves with its closest point of
    the skin. Unchanged arrays when the estimate is 0."""
    w, pivot, axis, glide = check_prior(jaw, len(V_src))
    _, lface, lbary, _ = closest_points(P, V_src, F_src)
    on_skin = np.einsum("ij,ijk->ik", lbary, V_src[F_src[lface]])
    info = {}
    angle = estimate_jaw_angle(P, Q, np.einsum("ij,ij->i", lbary, w[F_src[lface]]), pivot, axis, details=info,
                               glide=glide)
    if details is not None:
        details.update(jaw_deg=angle, jaw=info)
    log.debug("fit_surface: jaw opened %.1f degrees (estimate %.2f)", angle, info["raw"])
    if angle == 0.0:
        return V_src, P
    V_src = open_jaw(V_src, w, pivot, axis, angle, glide)
    return V_src, P + np.einsum("ij,ijk->ik", lbary, V_src[F_src[lface]]) - on_skin


def pose_source_expression(V_src, F_src, P, Q, V_tgt, F_tgt, expressions, details):
    """The source skin ``V_src`` (n, 3) and its landmarks ``P`` (k, 3) wearing the expression the target
    seems to wear (:mod:`.expression_prior`: the space's given ``weights``, else solved here); each
    landmark moves with its closest triangle of the skin. Worn on top of the jaw prior's opening: on
    ICT's open jaws the generic slid 7.0-8.1 % of ex-ex with the hinge alone and 5.1-5.5 % with
    jawOpen worn too (benchmarks/expression_fit.py): a hinge does not stretch the cheeks."""
    names, basis = check_space(expressions, len(V_src))
    info = {}
    if expressions.get("weights") is not None:
        w = weights_by_name(names, expressions["weights"])
        info["weights"] = {n: round(float(v), 3) for n, v in zip(names, w) if v > 0.05}
    else:
        w = fit_expression(V_src, F_src, P, Q, V_tgt, F_tgt, expressions, identity=expressions.get("identity"),
                           details=info)
    if details is not None:
        details["expression"] = info
    if not w.any():
        return V_src, P
    _, lface, lbary, _ = closest_points(P, V_src, F_src)
    moved = pose(V_src, basis, w)
    return moved, P + np.einsum("ij,ijk->ik", lbary, moved[F_src[lface]] - V_src[F_src[lface]])
