"""Build the generic skin's expression space: ``generic_rig/default/expressions.npz``.

:func:`autobones.rig_transfer.expression_space.build_expression_space` on the built-in rig (the
packaged ARKit set carried onto its skin; what ``transfer``'s expression fit poses it with). Run
``python generic_rig/build_expression_space.py`` after ``build_default_rig.py`` (it rewrites the folder);
``autobones build-rig`` does the same for a studio's rig.
"""
from __future__ import annotations

import argparse
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

from autobones.rig_transfer.expression_space import build_expression_space  # noqa: E402
from autobones.rig_transfer.pipeline import EXPRESSION_FILE  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rig", default=os.path.join(HERE, "default"), help="rig folder (default: the built-in one)")
    args = ap.parse_args(argv)
    names = build_expression_space(args.rig)
    print(f"{len(names)} expressions -> {os.path.join(args.rig, EXPRESSION_FILE)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
