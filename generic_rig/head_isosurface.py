"""Half-head surface from the implicit field: grid sampling + marching cubes.

Only x >= 0 is sampled (the field is mirror-symmetric), so marching cubes
(Lorensen & Cline 1987, scikit-image's ``marching_cubes``) returns an open
half-surface whose border lies exactly on the plane x = 0.  Metres, default
head frame (+Y up, +Z front, +X subject's left).
"""

from __future__ import annotations

import numpy as np

from .head_field import NECK_CUT_Y, head_field
from .half_mesh import clean

GRID_STEP = 0.0008           # marching-cubes sampling step (m)


def sample_half(step=GRID_STEP):
    """Sample ``head_field`` on a regular grid over x in [0, 0.105] m.

    Returns ``vol`` (nx, ny, nz) float64 field values and the axes
    ``(xs, ys, zs)`` (m), with ``vol[i, j, k]`` at ``(xs[i], ys[j], zs[k])``;
    ``xs[0] == 0`` exactly.
    """
    xs = np.arange(0, int(round(0.105 / step)) + 1) * step
    # the neck cut falls half-way between two grid planes -> a flat cap
    y0, y1 = NECK_CUT_Y - 3.5 * step, 0.240
    ys = y0 + np.arange(0, int(np.ceil((y1 - y0) / step)) + 1) * step
    z0, z1 = -0.115, 0.125
    zs = z0 + np.arange(0, int(np.ceil((z1 - z0) / step)) + 1) * step
    vol = np.empty((len(xs), len(ys), len(zs)), dtype=np.float64)
    Y, Z = np.meshgrid(ys, zs, indexing="ij")
    for i, xv in enumerate(xs):          # one x-plane at a time bounds memory
        P = np.stack([np.full(Y.size, xv), Y.ravel(), Z.ravel()], -1)
        vol[i] = head_field(P).reshape(Y.shape)
    return vol, (xs, ys, zs)


def _orient_outward(verts, faces):
    """faces (M, 3), flipped if needed so normals point to increasing field.

    scikit-image's winding depends on its gradient convention, so test it on
    ~2000 faces instead of assuming it.
    """
    v0, v1, v2 = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    n = np.cross(v1 - v0, v2 - v0)
    c = (v0 + v1 + v2) / 3
    eps = 1e-4
    nn = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-20)
    sel = np.arange(0, len(faces), max(1, len(faces) // 2000))
    outward = head_field(c[sel] + eps * nn[sel]) > head_field(c[sel] - eps * nn[sel])
    if outward.mean() < 0.5:
        faces = faces[:, ::-1].copy()
    return faces


def marching_half(step=GRID_STEP):
    """Dense outward-oriented half-head: V (n, 3) float m, F (m, 3) int64.

    Border vertices have x == 0.0 exactly.
    """
    from skimage.measure import marching_cubes     # build-time extra only
    vol, (xs, ys, zs) = sample_half(step)
    vol[vol == 0.0] = 1e-12            # no vertex exactly on a grid node
    verts, faces, _, _ = marching_cubes(vol, level=0.0, spacing=(step, step, step),
                                        allow_degenerate=False)
    verts = verts + np.array([xs[0], ys[0], zs[0]])
    verts[np.abs(verts[:, 0]) < 1e-12, 0] = 0.0
    faces = _orient_outward(verts, faces.astype(np.int64))
    return clean(verts, faces)
