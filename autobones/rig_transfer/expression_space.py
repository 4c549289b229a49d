"""A generic rig's expression space: the ARKit shapes carried onto its own skin (``expressions.npz``).

``transfer`` fits the generic skin wearing the expression the head seems to wear
(:mod:`autobones.rig_transfer.expression_prior`); the skin wears it through this file. The shapes are
the rig folder's ARKit set (``build-rig --shapes``, else ICT-FaceKit's packaged set, Li et al. 2020)
carried onto the generic's skin by the product's own mechanism: ``transfer`` of the generic onto itself
with ``arkit=True`` and the expression fit off (the generic is neutral), then every skin expression of
it (:data:`autobones.rig_transfer.expression_prior.NOT_SKIN` left out), as float16 displacements of
the generic's vertices (its units and frame).
"""
from __future__ import annotations

import os

import numpy as np

from .expression_prior import space_from_deltas
from .pipeline import EXPRESSION_FILE, load_generic


def build_expression_space(folder):
    """Write ``expressions.npz`` (``names`` (k,), ``basis`` (k, n, 3) float16) into the rig ``folder``
    (atomically: a temporary file renamed over it); returns the names."""
    from .pipeline import transfer

    generic = load_generic(folder)
    rig = transfer((generic.vertices, generic.faces), dict(generic.landmarks), rig=folder, arkit=True,
                   expression_fit=False)
    space = space_from_deltas(rig.arkit_targets, len(generic.vertices))
    tmp = os.path.join(folder, EXPRESSION_FILE + ".tmp.npz")
    np.savez_compressed(tmp, names=np.array(space["names"]), basis=space["basis"].astype(np.float16))
    os.replace(tmp, os.path.join(folder, EXPRESSION_FILE))
    return space["names"]
