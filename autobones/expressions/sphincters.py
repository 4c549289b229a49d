"""Sphincter muscles (orbicularis oris round the mouth, orbicularis oculi round the eye) and sheet
muscles (mentalis), each given by an ellipse on the skin.

Bibliowicz 2005 (§4.2) leaves the sphincters out: his muscle joints are linear. Here a sphincter
draws the skin inside its elliptical ring toward the ring's centre (Waters 1987's sphincter):
the ring's frame comes from the muscle's two carried points (centre and lateral point,
:func:`autobones.geometry.ring.ring_frame`) and its profile is the muscle's own influence field,
built on the generic rig by :func:`autobones.geometry.ring.ring_profile` and carried onto the head
by ``transfer`` like every other attribute. A muscle type is a sphincter when its definition in
``generic_rig/expressions.json`` has a ``sphincter`` entry:

- ``pull``: ``radial`` (each point moves by its distance to the centre times the profile, the
  lips gathering in a pucker) or ``sheet`` (by the ring's half size times the profile, toward the
  centre: the cheek lifted as one sheet round the eye);
- ``narrow``, ``close``: the share of that pull across the face (toward the centre line) and up or
  down (toward the mouth line or the fissure; negative: away from it, lips turned out);
- ``protrude``: forward motion (ring half sizes at profile 1; negative: rolled in), weighted by the
  profile squared, so it peaks on the lips or the cheek's crest.

A sheet muscle's type has a ``sheet`` entry instead, with the same keys and ``pull`` ``line``: the
skin inside the ellipse moves as one patch toward the ellipse's level line (up from below it, by the
point's distance from the line, at most the ellipse's half size, times the profile), plus ``narrow``
and ``protrude`` as above. Mentalis is one
(after Ekman, Friesen & Hager 2002's AU17): it does not pull the chin's skin toward its bony origin
but lifts the chin's soft tissue, which bunches and pushes the lower lip up and out. On ICT's
mouthShrugLower the lower lip, the skin under it and the chin rise by 12 / 21 / 25 and come forward
by 9 / 7 / 7 thousandths of a head size, where mentalis's wire drew them back toward its origin
(benchmarks/README.md, the muscle fields' ceiling).

Like a wire's, the field is linear in the contraction: one (n, 3) basis field per muscle.
"""
from __future__ import annotations

import numpy as np

from ..errors import AutobonesError
from ..geometry.ring import ring_frame

PULLS = ("radial", "sheet", "line")


def ring_spec(spec):
    """The ``sphincter`` or ``sheet`` entry of a muscle type definition, or None."""
    if spec is None:
        return None
    return spec.get("sphincter") if spec.get("sphincter") is not None else spec.get("sheet")


def is_sphincter(spec):
    """Whether a muscle type definition (:func:`definitions.muscle_types`) is a sphincter or a sheet
    (a muscle given by an ellipse, moved by :func:`sphincter_field` rather than by a wire)."""
    return ring_spec(spec) is not None


def is_sheet(spec):
    """Whether a muscle type definition is a sheet (``sheet`` entry: mentalis)."""
    return spec is not None and spec.get("sheet") is not None


def sphincter_field(V, centre, lateral, profile, spec):
    """Skin displacement of one sphincter per unit contraction.

    Parameters
    ----------
    V : (n, 3) float
        Vertices, canonical frame (+Y up, +Z front), head sizes.
    centre, lateral : (3,) float
        The muscle's origin (the ring's centre) and insertion (its lateral point), same frame.
    profile : (n,) float
        The muscle's influence field (0..1), the ring's profile.
    spec : dict
        The muscle type (``shortening`` and ``sphincter`` or ``sheet``: ``pull``, ``narrow``,
        ``close``, ``protrude``; module doc).

    Returns
    -------
    (n, 3) float
        Displacement at contraction 1 (``shortening`` applied), canonical, head sizes.
    """
    s = ring_spec(spec)
    pull = s.get("pull", "radial")
    if pull not in PULLS:
        raise AutobonesError(f"sphincter: pull must be one of {', '.join(PULLS)}, got {pull!r}")
    axes, half = ring_frame(centre, lateral)
    X = (np.asarray(V, dtype=np.float64) - centre) @ axes.T          # ring coordinates, head sizes
    g = np.clip(np.asarray(profile, dtype=np.float64), 0.0, 1.0)
    x, y = X[:, :1], X[:, 1:2]
    if pull == "line":
        # toward the level line by the distance from it, at most the half size: the patch rises as
        # one piece, and the rim next to the line (the lower lip) less, so it does not ride over it
        inward = -float(s.get("narrow", 0.0)) * x * axes[0] \
            - float(s.get("close", 1.0)) * np.sign(y) * np.minimum(np.abs(y), half) * axes[1]
    else:
        inward = -(float(s.get("narrow", 1.0)) * x * axes[0] + float(s.get("close", 1.0)) * y * axes[1])
    if pull == "sheet":
        # a unit pull toward the centre (the ring's half size at profile 1), not one growing with distance
        r = np.linalg.norm(X[:, :2], axis=1, keepdims=True)
        inward = inward * (half / np.maximum(r, 0.25 * half))
    d = inward * g[:, None] + (float(s.get("protrude", 0.0)) * half * g * g)[:, None] * axes[2]
    return float(spec["shortening"]) * d
