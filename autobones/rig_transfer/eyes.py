"""Eyeballs on a transferred head: bound rigidly to the eye bones, and the eye bones centred in them.

A generic skin (Orvalho, Zacur & Susin 2008, §2) has no eyeballs to carry weights for; a
head that models them needs them to turn with the eye bones as rigid parts. Everything in
the head's input frame and units.
"""
from __future__ import annotations

import numpy as np

from ..geometry.topology import mesh_parts
from ..skeleton import Skeleton


def bind_eyeballs(V, F, W, skeleton, generic, under):
    """Separate parts sitting on an eye bone (eyeballs, corneas) follow it rigidly.

    A generic skin has no eyeballs to carry weights for, and on the target they
    would take the eyelids' weights from the closest skin. A part counts as an
    eyeball when its centroid is within 0.35 eye-fissure lengths of the eye bone's
    pivot and it is no wider than 1.5 fissures (eyelashes and lids sit farther out).

    Parameters
    ----------
    V : (n, 3) float
        Head vertices, input frame and units.
    F : (m, 3) int
        Head triangles (eyeballs are separate connected parts).
    W : (n, b) float
        Skin weights, columns in ``skeleton`` order; not modified.
    skeleton : Skeleton
        Transferred bones, same frame.
    generic : LabelledRig
        The generic rig (its ``exocanthion_l`` / ``endocanthion_l`` landmarks give the fissure).
    under : ThinPlateSpline
        The generic -> head under-skin warp.

    Returns
    -------
    W : (n, b) float
        A copy with eyeball vertices bound (weight 1) to their eye bone.
    bound : dict str -> (n,) bool
        ``{eye bone name: vertices bound}``.
    """
    names = skeleton.names
    bound = {}
    if not all(n in generic.landmarks for n in ("exocanthion_l", "endocanthion_l")):
        return W, bound
    ex, en = under.transform(np.array([generic.landmarks["exocanthion_l"], generic.landmarks["endocanthion_l"]]))
    fissure = np.linalg.norm(ex - en)
    part = mesh_parts(len(V), F)
    if part.max() == 0:
        return W, bound
    count = np.bincount(part)
    centroid = np.stack([np.bincount(part, weights=V[:, j]) for j in range(3)], axis=1) / count[:, None]
    W = W.copy()
    for eye in ("eye_l", "eye_r"):
        if eye not in names:
            continue
        pivot = skeleton.heads[names.index(eye)]
        for p in np.flatnonzero(np.linalg.norm(centroid - pivot, axis=1) < 0.35 * fissure):
            members = part == p
            if np.ptp(V[members], axis=0).max() < 1.5 * fissure and members.sum() < 0.5 * len(V):
                W[members] = 0.0
                W[members, names.index(eye)] = 1.0
                bound[eye] = bound.get(eye, np.zeros(len(V), dtype=bool)) | members
    return W, bound


def centre_eye_bones(V, skeleton, eyeballs, max_residual=0.1):
    """Move each eye bone to the centre of the eyeball it carries, when the head has one.

    The warped pivot can sit several millimetres off a modelled eyeball's centre (ICT:
    0.06-0.08 face units), and gaze and the lid joints turn about it: the eyeball would
    swing through the lids. A least-squares sphere through the bound vertices is trusted
    when their median distance to it is under ``max_residual`` of its radius (a cornea
    bulge or an iris disc stays within that; a non-spherical part is left alone).

    Parameters
    ----------
    V : (n, 3) float
        Head vertices.
    skeleton : Skeleton
        Bones in the head's frame and units; not modified.
    eyeballs : dict str -> (n,) bool
        Vertices bound rigidly to each eye bone (from :func:`bind_eyeballs`).

    Returns
    -------
    Skeleton
        A copy with each such eye bone (head and tail) translated to its sphere's centre.
    """
    heads, tails = skeleton.heads.copy(), skeleton.tails.copy()
    for eye, members in eyeballs.items():
        P = V[members]
        if len(P) < 10:
            continue
        centre, radius = fit_sphere(P)
        if not radius > 0 or np.median(np.abs(np.linalg.norm(P - centre, axis=1) - radius)) > max_residual * radius:
            continue
        j = skeleton.names.index(eye)
        shift = centre - heads[j]
        heads[j] += shift
        tails[j] += shift
    return Skeleton(list(skeleton.names), skeleton.parents.copy(), heads, tails)


def fit_sphere(P):
    """Algebraic least-squares sphere through points P (m, 3): (centre (3,), radius)."""
    c0 = P.mean(axis=0)
    Q = P - c0                                   # centred, for conditioning
    A = np.c_[2.0 * Q, np.ones(len(Q))]
    x = np.linalg.lstsq(A, (Q * Q).sum(axis=1), rcond=None)[0]
    r2 = x[3] + x[:3] @ x[:3]
    return c0 + x[:3], float(np.sqrt(r2)) if r2 > 0 else 0.0
