"""The carried head and jaw joints put where the head's anatomy is: from its ear canals, on its midplane.

``transfer`` carries the generic rig's skeleton by the under-skin warp of the dense correspondence
(:mod:`.under_skin`), which follows the whole head's shape: on the zoo's SMPL heads it put the head
joint 0.08-0.13 ex-ex from the occiput-C1 centre and the jaw 0.05-0.08 from the condyle, and on
heads without ear landmarks 0.04-0.06 ex-ex beside the landmarks' midplane (James, the bunny:
``benchmarks/zoo.py`` check 4). Both joints are midline ones (the generic's are,
:mod:`autobones.rig_building.anatomy`).
"""
from __future__ import annotations

import numpy as np

from ..io.landmark_names import mirror_name

EAR_LANDMARKS = ("tragion_l", "tragion_r", "exocanthion_l", "exocanthion_r")
MIN_PAIRS = 2   # left/right landmark pairs needed to say where the midplane is


def anchor_joints_at_the_ears(skeleton, generic, landmarks, V, F, names=("head", "jaw")):
    """The carried ``head`` and ``jaw`` joints moved to where the generic's sit relative to its ear
    canals, and onto the landmarks' midplane.

    The generic rig's joints are placed from its tragions (the occiput-C1 centre of rotation and the
    condyles; Chancey, Ottaviano, Myers & Nightingale 2007, :mod:`autobones.rig_building.anatomy`).
    Where the head has both tragions and both exocanthions, each joint is the head's tragion
    midpoint plus the generic's offset from its own, turned by the landmarks' similarity (Umeyama
    1991) and scaled by the ex-ex ratio (the measurement's own scaling): 0.03-0.05 and 0.01-0.02
    ex-ex from the anatomy on the SMPL heads. Either way, with at least ``MIN_PAIRS`` left/right
    pairs, each joint then goes onto the landmarks' midplane (``landmarks.refine.symmetry_plane``):
    the similarity's small roll and asymmetric tragions put them 0.02-0.04 ex-ex beside it on the
    cat and the stuffed toy, the warp 0.04-0.06 on James. A joint that would fall outside the head
    (winding number below 1/2) is moved back toward the carried one until inside, or left where the
    warp put it.

    Parameters
    ----------
    skeleton : Skeleton
        The carried skeleton, head frame.
    generic : LabelledRig
        The generic rig (its ``skeleton`` and ``landmarks``, its own frame).
    landmarks : dict str -> (3,) float
        The head's landmarks shared with the generic rig, head frame.
    V, F : (n, 3) float, (m, 3) int
        The head.
    names : tuple of str
        Joints to place.

    Returns
    -------
    (Skeleton, list of str, list of str)
        The skeleton (a parent bone whose tail was at a moved joint follows it), the joints placed
        from the ears, and the joints put on the midplane.
    """
    from ..landmarks.refine import symmetry_plane
    from ..skeleton import Skeleton

    from_ears = _from_the_ears(generic, landmarks)
    pairs = sum(1 for n in landmarks if n.endswith("_l") and mirror_name(n) in landmarks)
    plane = symmetry_plane(landmarks) if pairs >= MIN_PAIRS else None
    if from_ears is None and plane is None:
        return skeleton, [], []
    heads, tails = np.array(skeleton.heads, dtype=np.float64), np.array(skeleton.tails, dtype=np.float64)
    bones, gbones = list(skeleton.names), list(generic.skeleton.names)
    size = float(np.ptp(V, axis=0).max())
    anchored, centred = [], []
    for name in (n for n in names if n in bones and n in gbones):
        i = bones.index(name)
        want = heads[i] if from_ears is None else from_ears(generic.skeleton.heads[gbones.index(name)])
        if plane is not None:
            normal, offset = plane
            want = want - (float(want @ normal) - offset) * normal
        p = _inside_toward(V, F, want, heads[i])
        if p is None:
            continue
        # the bone ending at this joint (the neck's tail at the head joint) keeps meeting it
        tails[np.linalg.norm(tails - heads[i], axis=1) <= 1e-9 * size] = p
        heads[i] = p
        if from_ears is not None:
            anchored.append(name)
        if plane is not None:
            centred.append(name)
    return Skeleton(bones, np.array(skeleton.parents).copy(), heads, tails), anchored, centred


def _from_the_ears(generic, landmarks):
    """A map from a generic joint (3,) to where it goes on the head by its ear canals, or None
    without both tragions and both exocanthions on both."""
    from ..geometry.rotations import similarity

    G = generic.landmarks
    if not all(n in landmarks and n in G for n in EAR_LANDMARKS):
        return None
    shared = [n for n in landmarks if n in G]
    _, R = similarity(np.array([G[n] for n in shared], dtype=np.float64),
                      np.array([landmarks[n] for n in shared], dtype=np.float64))

    def ears(L):
        L = {n: np.asarray(L[n], dtype=np.float64) for n in EAR_LANDMARKS}
        return 0.5 * (L["tragion_l"] + L["tragion_r"]), float(np.linalg.norm(L["exocanthion_l"] - L["exocanthion_r"]))

    (ear_g, ex_g), (ear_t, ex_t) = ears(G), ears(landmarks)
    return lambda joint: ear_t + (ex_t / ex_g) * (R @ (np.asarray(joint, dtype=np.float64) - ear_g))


def _inside_toward(V, F, p, anchor, steps=20):
    """``p`` (3,) if inside the head, else the first point inside on the way to ``anchor`` (3,), else
    None. Inside: a winding number above 1/2, or at least the anchor's own where that is lower (an
    open mouth or neck lowers it around a joint that is inside all the same)."""
    import igl

    Q = p + np.linspace(0.0, 1.0, steps + 1)[:, None] * (anchor - p)
    w = igl.fast_winding_number(np.ascontiguousarray(V, dtype=np.float64), np.ascontiguousarray(F, dtype=np.int64),
                                np.ascontiguousarray(Q))
    inside = np.flatnonzero(w > min(0.5, w[-1] - 1e-9))
    return Q[inside[0]] if len(inside) and inside[0] < steps else None
