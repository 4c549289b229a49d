"""Creases: the furrows frontalis and corrugator contractions press into the skin.

Horizontal furrows across the forehead above a raised brow (frontalis), vertical ones between
the brows (corrugator): fixed displacement fields, linear in the contraction, along the inward
normal.
"""
from __future__ import annotations

import numpy as np


def crease_fields(V, N, skin, influence, types, insertions, midline_x, fu, creases):
    """Crease displacement per unit contraction of the muscles that crease.

    Parameters
    ----------
    V, N : (n, 3) float
        Vertices and unit normals, canonical frame (+Y up, +Z front), head sizes.
    skin : (n,) bool
        Vertices that crease.
    influence : (k, n) float
        Each muscle's influence field (the crease fades with it).
    types : list of str
        Muscle type per muscle: ``frontalis*`` crease the forehead, ``corrugator`` and
        ``lateral_corrugator`` the glabella.
    insertions : (k, 3) float
        Muscle insertions (the forehead's furrows start half a wavelength above them).
    midline_x : float
        x of the face's midline (the stomion), where the glabella's furrows centre.
    fu : float
        Face unit in head sizes.
    creases : dict
        The definitions' ``model.creases`` (fu): ``forehead_wavelength``, ``forehead_amplitude``,
        ``glabella_wavelength``, ``glabella_amplitude``.

    Returns
    -------
    dict int -> (n, 3) float
        Muscle index -> displacement (head sizes), only for muscles whose crease moves something.
    """
    out = {}
    for i, ty in enumerate(types):
        if ty.startswith("frontalis"):
            lam, amp = float(creases["forehead_wavelength"]) * fu, float(creases["forehead_amplitude"]) * fu
            phase = (V[:, 1] - insertions[i][1]) / lam
            furrow = 0.5 * (1.0 - np.cos(2.0 * np.pi * phase)) * (phase > 0.5)
        elif ty in ("corrugator", "lateral_corrugator"):
            lam, amp = float(creases["glabella_wavelength"]) * fu, float(creases["glabella_amplitude"]) * fu
            dx = V[:, 0] - midline_x
            furrow = 0.5 * (1.0 + np.cos(2.0 * np.pi * dx / lam)) * (np.abs(dx) < lam)
        else:
            continue
        K = -(amp * influence[i] * furrow * skin)[:, None] * N
        if np.any(K):
            out[i] = K
    return out
