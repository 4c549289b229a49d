"""Is a face human? Five landmarks against a human face that may wear an expression.

``landmarks --assist`` treats a human face otherwise than an animal's: it runs the automatic
detector and takes the chin's lowest point off the midline profile. It decides from the five
given names alone (outer eye corners, nose tip, mouth corners), by their shape against the
generic human's after the best rotation, translation and uniform scale (:func:`face_distance`).

A neutral reference alone told a smiling or open-mouthed person from a cartoon poorly: the mouth
corners move 0.05-0.1 ex-ex in an expression, as far as a humanoid monster's face differs from a
person's (ICT identity000 with an open jaw 0.084, puckered 0.088, smiling 0.063; the beast 0.072).
So the reference may wear an expression: the generic rig's expression space (ICT-FaceKit's ARKit
shapes carried onto its skin, ``expressions.npz``; Li et al. 2020) read at the five names, its
weights in [0, 1] solved with the similarity (bounded least squares with a small ridge, alternated
with Umeyama's similarity a few rounds), as model-based face fitting solves expression with pose
(Blanz & Vetter 1999), and the jaw may open on its hinge (an articulation, not a learned shape:
:func:`hinge_displacement`). Over the shared heads (benchmarks/README.md, "a person wearing an
expression is a person"): nine neutral human heads 0.006-0.018, three ICT identities wearing five
expressions 0.003-0.020 (0.005-0.042 with the expression's own shapes left out of the space); eleven
animals, cartoons and statues 0.065 (a humanoid monster) to 0.199 (a camel), so
:data:`HUMAN_FACE_EXPRESSIVE` lies between. Without a space (a rig given as an object, a rig
folder without the file) the neutral reference and :data:`HUMAN_FACE`.

The joints' face gate (:func:`autobones.rig_transfer.joints.face_fit`: may a face's landmarks place a
rig's head and jaw joints?) measures the same distance over every name the face shares with the generic
(``names=``), with its own bound.

Distances are in units of the given ex-ex (RMS over the points); all functions are pure.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import lsq_linear

from ..errors import AutobonesError
from ..geometry.closest import closest_points
from ..geometry.rotations import similarity

#: The five names the distance is measured on (the assisted landmarks' required set).
FIVE = ("exocanthion_l", "exocanthion_r", "pronasale", "cheilion_l", "cheilion_r")

#: Largest neutral :func:`face_distance` of a human-proportioned face (between the neutral humans'
#: 0.044 and the beast's 0.072).
HUMAN_FACE = 0.06

#: Largest expression-tolerant :func:`face_distance` of a human face (between the humans' 0.042,
#: expressive ones with their expression left out of the space included, and the beast's 0.065).
HUMAN_FACE_EXPRESSIVE = 0.05

#: Ridge on the expression weights against the squared RMS residual (ex-ex^2 summed over the 15
#: coordinates): 1e-4 let a bunny wear a smile down to 0.060; 1e-2 left an open jaw (space alone) at 0.044.
RIDGE = 1e-3

#: The jaw opening (degrees) one unit of :func:`hinge_displacement`'s weight stands for (ICT's
#: jawOpen turns the lower teeth about 25 degrees).
HINGE_DEG = 30.0

#: ex-ex: how far a placed landmark is taken to sit from where it belongs, beside how far expressions move
#: it, in :func:`stillness`. On the shared neutral humans (their family held out of the face joints'
#: calibration) 0.005, 0.01 and 0.02 put the head joint 0.082, 0.085 and 0.093 from the anatomy, against
#: 0.104 unweighted; the jaw 0.071-0.072 each time.
PLACEMENT = 0.01

#: Rounds of (similarity, weights). Over the shared heads six leave a human's distance at most 0.008 ex-ex
#: above its value after 200 (the alternation creeps down) and an animal's within 0.003: the gate errs
#: toward "not human", far from its bound either way.
ROUNDS = 6


def _normalised(X):
    """(k, 3) points centred and scaled to unit ex-ex (rows 0 and 1 the outer eye corners)."""
    X = X - X.mean(axis=0)
    return X / np.linalg.norm(X[0] - X[1])


def _on_skin(reference, vertices, faces, names):
    """Where the names sit on the generic skin: (points (k, 3), face (k,) int, bary (k, 3) float,
    F (m, 3) int64), each name's nearest triangle and its barycentric coordinates there."""
    B0 = np.array([reference[n] for n in names], dtype=np.float64)
    F = np.asarray(faces, dtype=np.int64)
    _, face, bary, _ = closest_points(B0, np.asarray(vertices, dtype=np.float64), F)
    return B0, face, bary, F


def _expression_fields(on_skin, basis):
    _, face, bary, F = on_skin
    return np.einsum("pj,kpjc->kpc", bary, np.asarray(basis, dtype=np.float64)[:, F[face]])


def _hinge_field(on_skin, jaw, degrees):
    from ..rig_transfer.jaw_prior import open_jaw

    B0, face, bary, F = on_skin
    weight = np.einsum("pj,pj->p", bary, np.asarray(jaw["weight"], dtype=np.float64)[F[face]])
    return (open_jaw(B0, weight, jaw["pivot"], jaw["axis"], degrees, jaw.get("glide")) - B0)[None]


def expression_displacements(reference, vertices, faces, basis, names=FIVE):
    """How each expression moves the ``names`` (default the five) on the generic skin.

    Parameters
    ----------
    reference : dict str -> (3,)
        The generic's landmarks (its frame), at least ``names``, on or near its skin.
    vertices, faces : (n, 3) float, (m, 3) int
        The generic's rest skin.
    basis : (k, n, 3) float
        The expression space's displacement fields on that skin (its units).
    names : sequence of str
        The names, in the order :func:`face_distance` is given them.

    Returns
    -------
    (k, len(names), 3) float64: each name's displacement at its barycentric point in its nearest triangle.
    """
    return _expression_fields(_on_skin(reference, vertices, faces, names), basis)


def hinge_displacement(reference, vertices, faces, jaw, degrees=HINGE_DEG, names=FIVE):
    """How opening the generic's jaw by ``degrees`` moves the ``names``: (1, len(names), 3) float64.

    ``jaw`` is the generic's jaw prior (:func:`autobones.rig_transfer.jaw_prior.jaw_prior`: a
    per-vertex ``weight`` (n,), the hinge's ``pivot`` and ``axis`` (3,), its ``glide`` (3,) per
    degree), read at the names' barycentric points. An articulation, not a learned shape: it covers
    an open mouth whatever expression space the rig carries (left out of ICT's, an open jaw's
    distance falls from 0.069-0.074 to 0.025-0.031 with it)."""
    return _hinge_field(_on_skin(reference, vertices, faces, names), jaw, degrees)


def face_motion_fields(reference, vertices, faces, basis, jaw=None, names=FIVE):
    """Both at once, the names found on the skin once: :func:`expression_displacements` then, with a
    ``jaw`` prior, :func:`hinge_displacement` (at :data:`HINGE_DEG`): (k [+ 1], len(names), 3) float64,
    what :func:`face_distance` and :func:`is_human_face` take as the face's motion."""
    on_skin = _on_skin(reference, vertices, faces, names)
    fields = [_expression_fields(on_skin, basis)]
    if jaw is not None:
        fields.append(_hinge_field(on_skin, jaw, HINGE_DEG))
    return np.concatenate(fields)


def stillness(displacements, unit, placement=PLACEMENT):
    """Weights (n,) of a face's names for a similarity that reads the head's pose from the face: each
    name's ``1 / (m^2 + placement^2)``, ``m`` its RMS displacement over the face's motion
    ``displacements`` ((k, n, 3), :func:`face_motion_fields`) in units of ``unit`` (the reference's
    ex-ex). A smile or raised brows move the mouth corners and brows 0.02-0.06 ex-ex a shape (RMS),
    the eye corners, nasion and zygia under 0.01: an expressive face's pose is read from what its
    expressions leave still, and a neutral face's from what stays put in the generic's frame as well
    (placement noise, ``placement``, keeps every name in)."""
    D = np.asarray(displacements, dtype=np.float64)
    m = np.sqrt((D ** 2).sum(axis=2).mean(axis=0)) / float(unit)
    return 1.0 / (m ** 2 + placement ** 2)


def face_distance(given, reference, displacements=None, ridge=RIDGE, rounds=ROUNDS, names=FIVE):
    """How far the ``given`` names (name -> (3,), any frame and unit) are from a human face.

    The RMS distance (in ex-ex) over ``names`` (default :data:`FIVE`; the two outer eye corners
    first) between the given shape and the ``reference``'s (name -> (3,)), after the best similarity
    (a proper rotation: a mirrored face is not the same face). With ``displacements``
    ((k, len(names), 3), :func:`expression_displacements` of the same names) the reference may
    wear any combination of them, weights in [0, 1] with a ``ridge`` on their squares, solved
    alternately with the similarity for ``rounds`` rounds; the smaller of that and the neutral
    distance is returned.
    """
    if tuple(names[:2]) != ("exocanthion_l", "exocanthion_r"):
        raise AutobonesError("face_distance: the names must start with exocanthion_l, exocanthion_r (the unit)")
    A = _normalised(np.array([given[n] for n in names], dtype=np.float64))
    B0 = np.array([reference[n] for n in names], dtype=np.float64)

    def distance(B):
        Bn = _normalised(B)
        s, R = similarity(A, Bn)
        return float(np.sqrt(((s * A @ R.T - Bn) ** 2).sum(axis=1).mean())), s * A @ R.T

    best, fitted = distance(B0)
    if displacements is None or not len(displacements):
        return best
    D = np.asarray(displacements, dtype=np.float64)
    k = len(D)
    # the weights' problem linearised about the neutral reference's normalisation (its centre and
    # ex-ex), the distance itself measured exactly with each round's weights
    scale = np.linalg.norm(B0[0] - B0[1])
    M = (D - D.mean(axis=1, keepdims=True)).reshape(k, -1).T / scale
    M = np.vstack([M, np.sqrt(ridge) * np.eye(k)])
    for _ in range(rounds):
        y = np.concatenate([(fitted - (B0 - B0.mean(axis=0)) / scale).ravel(), np.zeros(k)])
        w = lsq_linear(M, y, bounds=(0.0, 1.0)).x
        d, fitted = distance(B0 + np.einsum("k,kpc->pc", w, D))
        best = min(best, d)
    return best


def is_human_face(given, reference, motion=None):
    """True when the five ``given`` names are a human face's: :func:`face_distance` to the ``reference``
    at most :data:`HUMAN_FACE_EXPRESSIVE` when it may wear ``motion`` ((k, 5, 3): the generic's
    expression space and its jaw's hinge, :func:`expression_displacements` and :func:`hinge_displacement`;
    :func:`autobones.rig_transfer.pipeline.face_motion` makes both), else at most :data:`HUMAN_FACE`
    against the neutral reference."""
    if motion is not None and len(motion):
        return face_distance(given, reference, motion) <= HUMAN_FACE_EXPRESSIVE
    return face_distance(given, reference) <= HUMAN_FACE


__all__ = ["FIVE", "HINGE_DEG", "HUMAN_FACE", "HUMAN_FACE_EXPRESSIVE", "PLACEMENT", "RIDGE",
           "expression_displacements", "face_distance", "face_motion_fields", "hinge_displacement",
           "is_human_face", "stillness"]
