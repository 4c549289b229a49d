"""The baseline deformation transfer is measured against: displacements copied through the correspondence.

Goes beyond the seeds (issue #15). Each target vertex takes the source displacement at its
closest point on the source laid on the target (``(P, F_src)``, barycentric), turned and
scaled by the similarity that best maps the source landmarks onto the target's
(Umeyama 1991): what "copy the blendshape deltas" does when the two heads share no topology.
"""
from __future__ import annotations

import numpy as np

from ..geometry.closest import closest_points


def copy_displacements(F_src, deltas, P, V_tgt, scale, rotation):
    """Copied displacements (k, n_t, 3): ``scale * rotation @ delta`` at each target vertex's closest
    point on ``(P, F_src)``; ``deltas`` (k, n_s, 3) in source units, ``P`` (n_s, 3) target frame."""
    _, face, bary, _ = closest_points(np.asarray(V_tgt, dtype=np.float64), P, F_src)
    corners = np.asarray(F_src)[face]
    out = np.einsum("kvcd,vc->kvd", np.asarray(deltas)[:, corners], bary)
    return scale * out @ np.asarray(rotation).T
