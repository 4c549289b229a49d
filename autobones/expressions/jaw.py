"""The jaw's skin weights, sharpened across the mouth line, and the condyle's glide.

The jaw turns each vertex about its pivot by its jaw weight times the angle (Bibliowicz 2005,
§4.2, jaw joint). The rig's jaw weight is reshaped for that: cut across the mouth line (the jaw
opens the lower lip only; the cut fades out toward the mouth corners, where the lips join),
spread under the chin and up the cheeks beside the mouth (so the skin there stretches instead of
folding) and faded under the chin behind the menton (so it does not swing into the neck).

Canonical frame (+Y up, +Z front), head sizes; ``fu`` is the face unit (the exocanthion
distance) in head sizes; the definitions' lengths are in fu.
"""
from __future__ import annotations

import numpy as np

from ..geometry.smooth import ramp


def jaw_column(w, V, skin, mouth, menton, fu, params, surface):
    """The sharpened jaw weight (n,) float from the rig's jaw weight ``w`` (n,).

    Parameters
    ----------
    w : (n,) float
        The rig's skin weight of the jaw bone.
    V : (n, 3) float
        Vertices.
    skin : (n,) bool
        Skin vertices.
    mouth : MouthLine
        The mouth line and zone.
    menton : (3,) float or None
        The chin's lowest point (no under-chin fade without it).
    fu : float
        Face unit.
    params : dict
        Resolved model parameters (fu): ``jaw_spread``, ``cheek_spread``, ``under_chin_height``,
        ``under_chin_depth``.
    surface : SkinSurface
        Its Laplacian and mass diffuse the weight.
    """
    hw, dx = mouth.half_width, mouth.dx
    # under the chin the jaw swings toward the neck: spread its weight there so the skin
    # stretches instead of folding (heat diffusion, as build_rig smooths it)
    spread = float(params["jaw_spread"]) * fu
    jaw_s = np.clip(surface.diffuse(w, spread ** 2), 0.0, 1.0) if spread > 0 else w
    below = ramp(mouth.signed, 0.0, -0.1 * fu) * skin
    jaw_b = (1.0 - below) * w + below * jaw_s
    # beside the mouth the cheek is one sheet from the cheekbone to the mandible: lateral of
    # the mouth corners it stretches as the jaw opens, the jaw weight diffusing up into it
    cheek = float(params["cheek_spread"]) * fu
    if cheek > 0:
        jaw_c = np.clip(surface.diffuse(w, cheek ** 2), 0.0, 1.0)
        lateral = ramp(dx, 0.8 * hw, 1.1 * hw) * skin * (1.0 - below)
        jaw_b = np.where(lateral > 0, np.maximum(jaw_b, lateral * jaw_c + (1.0 - lateral) * jaw_b), jaw_b)
    # under the chin the opening jaw swings back toward the neck: the skin there follows it
    # less and less from the menton back, so it stretches instead of folding into the neck
    if menton is not None:
        under = ramp(V[:, 1], menton[1] + float(params["under_chin_height"]) * fu, menton[1]) * skin
        fade = ramp(V[:, 2], menton[2] - float(params["under_chin_depth"]) * fu, menton[2])
        jaw_b = jaw_b * (1.0 - under * (1.0 - fade))
    # the lips join at the corners, where tiny triangles bridge the upper lip (hanging over
    # the lower) and the lower lip: any step in the jaw weight there turns them over, so the
    # cut grows from nothing at the cheilions to full half the mouth's half-width in (full
    # only at the stomion pinned the corners, a V-shaped opening; nearer the corners the
    # mouth's lining folds at AU26 and the unfolding moves a wide patch of it)
    zone_j = mouth.zone * ramp(dx, hw, 0.5 * hw)
    return (1.0 - zone_j) * jaw_b + zone_j * (1.0 - mouth.upper)


def with_jaw_column(W, j, head, jaw):
    """Skin weights (n, b) with column ``j`` replaced by ``jaw`` (n,), the other bones rescaled to
    fill the rest (to the ``head`` column, an index or None, where they hold nothing). New array."""
    Wj = W.copy()
    others = np.delete(np.arange(W.shape[1]), j)
    rest = W[:, others].sum(axis=1)
    want = 1.0 - jaw
    scale = np.where(rest > 1e-12, want / np.maximum(rest, 1e-12), 0.0)
    Wj[:, others] = W[:, others] * scale[:, None]
    if head is not None:
        Wj[:, head] += np.where(rest > 1e-12, 0.0, want)
    Wj[:, j] = jaw
    return Wj


def jaw_glide(glide, fu):
    """(3,) float: canonical translation per degree of jaw opening (head sizes) from the
    definitions' ``jaw_glide`` = (down, forward) in fu: the condyle gliding down and forward
    along the articular eminence."""
    down, forward = (list(glide) + [0.0, 0.0])[:2]
    return np.array([0.0, -float(down), float(forward)]) * fu


def jaw_weights(W, names, V, skin, mouth, menton, fu, params, surface):
    """The rig's skin weights ``W`` (n, b) with the jaw column sharpened (:func:`jaw_column`) and
    the other bones rescaled around it (:func:`with_jaw_column`); a copy of ``W`` when ``names``
    (the bone names) has no ``jaw``. Arguments as for :func:`jaw_column`."""
    if "jaw" not in names:
        return W.copy()
    j = names.index("jaw")
    jaw = jaw_column(W[:, j], V, skin, mouth, menton, fu, params, surface)
    return with_jaw_column(W, j, names.index("head") if "head" in names else None, jaw)
