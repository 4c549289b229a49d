"""Build the generic skin's expression space: ``generic_rig/default/expressions.npz``.

``transfer`` fits the generic skin wearing the expression the head seems to wear
(:mod:`autobones.rig_transfer.expression_prior`). The space is the packaged ARKit set (ICT-FaceKit's
shapes, Li et al. 2020: ``generic_rig/arkit``, its licence there) carried onto the generic rig's own
skin by the product's own mechanism: ``autobones.transfer(generic skin, its landmarks, arkit=True)``
with the expression fit off (the generic is neutral), then every skin expression of it
(:data:`autobones.rig_transfer.expression_prior.NOT_SKIN` left out), as float16 displacements of
the generic's vertices (metres, the generic's frame).

Run ``python generic_rig/build_expression_space.py`` after ``build_default_rig.py`` (it rewrites the
folder).
"""
from __future__ import annotations

import argparse
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

from autobones.rig_transfer.expression_prior import space_from_deltas  # noqa: E402
from autobones.rig_transfer.pipeline import EXPRESSION_FILE, load_generic  # noqa: E402


def build(folder):
    """``expressions.npz`` in the rig ``folder`` from its own skin and landmarks; returns its names."""
    import autobones

    generic = load_generic(folder)
    rig = autobones.transfer((generic.vertices, generic.faces), dict(generic.landmarks), rig=folder, arkit=True,
                             expression_fit=False)
    space = space_from_deltas(rig.arkit_targets, len(generic.vertices))
    tmp = os.path.join(folder, EXPRESSION_FILE + ".tmp.npz")
    np.savez_compressed(tmp, names=np.array(space["names"]), basis=space["basis"].astype(np.float16))
    os.replace(tmp, os.path.join(folder, EXPRESSION_FILE))
    return space["names"]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rig", default=os.path.join(HERE, "default"), help="rig folder (default: the built-in one)")
    args = ap.parse_args(argv)
    names = build(args.rig)
    print(f"{len(names)} expressions -> {os.path.join(args.rig, EXPRESSION_FILE)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
