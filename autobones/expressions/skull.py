"""Skull non-penetration: the soft-tissue thickness under the skin, and muscles sliding over bone.

Bibliowicz 2005, §4.2 keeps the skin off the skull: a skin point may sink along its rest normal
by at most the soft-tissue thickness of its region (the offset skull surface, taken locally
parallel to the skin). The clamp itself acts when posing (``ExpressionModel.pose_parameters``).
"""
from __future__ import annotations

import numpy as np

from ..geometry.smooth import ramp

# the region labels of a transferred rig, in order, when its sidecar does not name them
REGIONS_DEFAULT = ("scalp", "forehead", "brow", "eyelids", "nose", "cheeks", "lips", "chin", "jaw", "ears", "neck")


def tissue_thickness(region, labels, skull, fu, surface):
    """Soft-tissue thickness per vertex (n,) float, head sizes.

    Parameters
    ----------
    region : (n,) int or None
        The rig's region field (label index per vertex); None: every vertex takes the default.
    labels : sequence of str
        Region names by label index.
    skull : dict
        The definitions' ``model.skull``: ``default`` and per region name the thickness (fu),
        ``blend`` (fu) the distance over which region thicknesses blend.
    fu : float
        Face unit in head sizes.
    surface : SkinSurface
        Its Laplacian and mass diffuse the thickness (heat diffusion over ``blend``).
    """
    n = len(surface.index)
    thick = np.full(n, float(skull["default"]) * fu)
    if region is not None:
        region = np.asarray(region).reshape(n).astype(np.int64)
        for r_i, r_name in enumerate(labels):
            if r_name in skull:
                thick[region == r_i] = float(skull[r_name]) * fu
    # the offset skull is smooth: region thicknesses blend over ~1 cm of skin
    return surface.diffuse(thick, (float(skull["blend"]) * fu) ** 2)


def skull_clamp(mouth):
    """(n,) bool: where the offset skull lies under the skin.

    Under outward-facing skin only: not under the lips (the inner lip surfaces face each other,
    ``mouth.zone`` >= 0.05) nor under skin whose normal points into the head (``mouth.inward``).
    """
    return (mouth.zone < 0.05) & ~mouth.inward


def slide_over_bone(G, slide, clamp, thickness, skull_normals, slide_thickness, fu):
    """Muscle fields ``G`` (k, n, 3) with the muscles over bone sliding on the skull.

    Where the skull lies close under outward skin (``clamp`` (n,) bool; ``thickness`` (n,) head
    sizes at most ``slide_thickness`` fu; ``fu`` the face unit in head sizes) the skin of a muscle
    with ``slide`` (k,) bool set slides over the bone: the part of its field along the skull
    normal (``skull_normals`` (n, 3), toward a deep origin) is dropped, fully below
    ``slide_thickness``, fading out by 1.5 times it.
    Returns a new (k, n, 3) array.
    """
    over_bone = clamp * ramp(thickness, 1.5 * float(slide_thickness) * fu, float(slide_thickness) * fu)
    G = G.copy()
    for i in np.flatnonzero(slide):
        G_i = G[i]
        G_i -= (over_bone * (G_i * skull_normals).sum(axis=1))[:, None] * skull_normals
    return G
