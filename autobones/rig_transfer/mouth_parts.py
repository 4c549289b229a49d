"""The mouth's separate inner parts on a transferred head (teeth, gums, tongue, a mouth bag): which
ride the jaw and which the skull, by the rule the expression model poses them with
(:mod:`autobones.geometry.mouth_parts`): a small part (a tooth) whole by its centre against the
occlusal level through the stomion, a larger one split vertex by vertex at the lower teeth's
crowns, nothing behind the jaw joint riding the jaw.

Two steps around the jaw's repair (:mod:`.jaw`): :func:`carried_mouth_parts` gives every inner part
that rule as its carried jaw weight, so the repair starts from it and smooths it where it steps
(its springs keep every edge off the lip line within 0.27; the rule's own 0.03 fu split stepped by
up to 0.64 across 85 edges of ICT identity002's mouth bag); :func:`rigid_mouth_parts` then moves
the small parts whole again (a tooth is rigid, and the repair's lip seeds reach the tips of the
incisors).

Why: the repair solves one smooth field from the lips' and the chin's landmarks, and a separate part
inside the mouth has none of them, so its weight was what the generic skin (which has no teeth)
carried and whichever seeds reached it. Measured on ICT identity001 (32 separate teeth): the upper
incisors carried jaw 0-1 (their tips dip under the mouth plane, where the lower lip's band seeds
them), the lower molars 0-0.5 (their crowns lie above the upper face's plane through the gonions),
so the exported rig tore its teeth as the jaw opened, and a 1 % jitter of the landmarks moved their
weights by up to 1.0; ``benchmarks/teeth.py``.

Frames and units: the head's own in and out; the rule works in the rig's canonical frame (+Y up,
+Z front, head sizes), lengths of its parameters in face units (the exocanthion distance).
"""
from __future__ import annotations

import numpy as np

from ..geometry.areas import triangle_areas
from ..geometry.mouth_parts import MOUTH_PARTS, inner_mouth_parts, mouth_part_weights
from ..geometry.topology import mesh_parts, weld

EYE_REACH = 0.5   # fu above the stomion: parts centred higher (lashes, lid shells) are the eyes'


def carried_mouth_parts(V, F, W, names, heads, frame, landmarks, params=None):
    """Skin weights with every separate part inside the mouth set by the rule (module doc): the jaw
    weight the repair starts from. Arguments and returns as :func:`rigid_mouth_parts`."""
    return _mouth_parts(V, F, W, names, heads, frame, landmarks, params, small_only=False)


def rigid_mouth_parts(V, F, W, names, heads, frame, landmarks, params=None):
    """Skin weights with the small separate parts inside the mouth (teeth) moved whole (module doc).

    Parameters
    ----------
    V : (n, 3) float
        The head's vertices, its own frame and units.
    F : (m, 3) int
        Its triangles; coincident vertices are welded to find the parts.
    W : (n, b) float
        Skin weights, rows summing to 1 (the jaw column repaired).
    names : list of str
        The b bone names; nothing changes without ``jaw`` and ``head``.
    heads : (b, 3) float
        The bones' joints, head frame.
    frame : autobones.orient.Frame
        The head's canonical frame (``to_canonical``: head sizes, +Y up, +Z front).
    landmarks : dict str -> (3,) float
        Head frame; nothing changes without ``stomion`` and both ``exocanthion``.
    params : dict, optional
        ``reach``, ``band``, ``rigid_size``, ``pharynx`` (fu): the expression model's defaults
        (:data:`autobones.geometry.mouth_parts.MOUTH_PARTS`) unless given.

    Returns
    -------
    W : (n, b) float
        A new array; rows of the parts hold only jaw and head weight, summing to 1.
    rows : (p,) int64
        The parts' vertices, sorted (empty when none).
    """
    return _mouth_parts(V, F, W, names, heads, frame, landmarks, params, small_only=True)


def _mouth_parts(V, F, W, names, heads, frame, landmarks, params, small_only):
    W = np.asarray(W, dtype=np.float64)
    need = ("stomion", "exocanthion_l", "exocanthion_r")
    if "jaw" not in names or "head" not in names or not all(k in landmarks for k in need):
        return W.copy(), np.zeros(0, dtype=np.int64)
    p = dict(MOUTH_PARTS, **(params or {}))
    V = np.asarray(V, dtype=np.float64)
    Vc = frame.to_canonical(V)
    L = {k: frame.to_canonical(np.asarray(landmarks[k], dtype=np.float64).reshape(1, 3))[0] for k in need}
    fu = float(np.linalg.norm(L["exocanthion_l"] - L["exocanthion_r"]))
    st = L["stomion"]
    # parts of the welded mesh (an unwelded export splits every face apart); the skin is the largest
    diag = float(np.linalg.norm(np.ptp(V, axis=0))) or 1.0
    Vw, Fw, index = weld(V, np.asarray(F, dtype=np.int64), 1e-6 * diag)
    part_w = mesh_parts(len(Vw), Fw)
    area = np.bincount(part_w[Fw[:, 0]], weights=triangle_areas(Vw, Fw), minlength=len(Vw))
    part = part_w[index]
    eyes = [names.index(e) for e in ("eye_l", "eye_r") if e in names]
    eye_w = W[:, eyes].sum(axis=1) if eyes else np.zeros(len(V))
    candidates = (part != int(np.argmax(area))) & (eye_w < 0.5)
    found = [f for f in inner_mouth_parts(Vc, part, candidates, st, fu, p["reach"], p["rigid_size"])
             if (f[2] or not small_only) and f[1][1] - st[1] <= EYE_REACH * fu]
    if not found:
        return W.copy(), np.zeros(0, dtype=np.int64)
    pivot = frame.to_canonical(np.asarray(heads, dtype=np.float64)[names.index("jaw")].reshape(1, 3))[0]
    return mouth_part_weights(W, names.index("jaw"), names.index("head"), Vc, found, st, pivot, fu,
                              p["band"], p["pharynx"])
