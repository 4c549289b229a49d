"""The elliptical ring of a sphincter muscle: its frame on the face and its profile.

A sphincter (orbicularis oris round the mouth, orbicularis oculi round the eye) has no line of
action: it draws the skin inside an ellipse toward the ellipse's centre (Waters 1987's sphincter
muscle model). Its frame is set by two points, the centre on the skin and a lateral point on the
skin (the mouth corner, the outer eye corner): ``x`` runs from the centre toward the lateral point
(across the face, the head's up axis removed), ``y`` up, ``z`` out of the face. The ellipse's
semi-axes are given per quadrant in multiples of the centre -> lateral distance, so one definition
fits any head. The same ellipse bounds a *sheet* muscle (``kind`` "sheet": mentalis, which lifts the
chin's soft tissue as one patch against the lower lip): a patch of skin with a centre and a lateral
point, moved as one piece rather than drawn toward its centre.
"""
from __future__ import annotations

import numpy as np

from ..errors import AutobonesError

QUADRANTS = ("lateral", "medial", "above", "below")
RING_KINDS = ("sphincter", "sheet")   # muscle kinds given by an ellipse on the skin (centre, lateral point, reach)


def ring_frame(centre, lateral, up=(0.0, 1.0, 0.0), front=(0.0, 0.0, 1.0)):
    """The sphincter's axes and half size.

    Parameters
    ----------
    centre, lateral : (3,) float
        The ring's centre and its lateral point (any frame and unit).
    up, front : (3,) float
        The head's up and front directions in that frame (default the canonical +Y and +Z).

    Returns
    -------
    axes : (3, 3) float
        Rows ``ex`` (toward the lateral point, across the face), ``ey`` (up), ``ez`` (front),
        orthonormal.
    half : float
        The centre -> lateral distance along ``ex`` (same unit as the points).
    """
    c, q = np.asarray(centre, dtype=np.float64), np.asarray(lateral, dtype=np.float64)
    up, front = np.asarray(up, dtype=np.float64), np.asarray(front, dtype=np.float64)
    ez = front / np.linalg.norm(front)
    ex = (q - c) - ((q - c) @ ez) * ez
    ex = ex - (ex @ up) / (up @ up) * up          # across the face, level
    half = float(np.linalg.norm(ex))
    if not half > 0:
        raise AutobonesError("sphincter: its lateral point lies straight above, below or in front of its centre")
    ex = ex / half
    ey = np.cross(ez, ex)
    ey = ey if ey @ up > 0 else -ey
    ez = np.cross(ex, ey)
    ez = ez if ez @ front > 0 else -ez
    return np.stack([ex, ey, ez]), half


def ring_profile(P, centre, axes, half, reach, core=0.3, hole=None, split=None, depth=0.6):
    """The ring's profile (Waters 1987's sphincter falloff, with per-quadrant semi-axes).

    Parameters
    ----------
    P : (n, 3) float
        Points, same frame and unit as ``centre``.
    centre : (3,) float
    axes, half
        From :func:`ring_frame`.
    reach : dict
        Semi-axes in multiples of ``half``: ``lateral`` (x > 0), ``medial``, ``above`` (y > 0),
        ``below``; each > 0.
    core : float
        Elliptical radius (0..1) inside which the profile is 1; it falls to 0 at 1 as a raised
        cosine.
    hole : (2,) float, optional
        Elliptical radii between which the profile rises from 0 (an inner part left to other
        joints: the eyelids inside orbicularis oculi's orbital part).
    split : float, optional
        The ring is one half of a sphincter that spans the midline (the mouth): the profile fades
        out across ``x = 0`` over this many ``half`` (the two halves sum to the whole).
    depth : float
        Points more than ``depth`` times the largest semi-axis behind the centre get 0 (the back
        of the head, the inside of the mouth).

    Returns
    -------
    rho : (n,) float
        Elliptical radius (1 on the ellipse).
    g : (n,) float
        The profile in [0, 1].
    """
    missing = [q for q in QUADRANTS if not float(reach.get(q, 0.0)) > 0]
    if missing:
        raise AutobonesError(f"sphincter: reach needs positive {', '.join(missing)}")
    X = (np.asarray(P, dtype=np.float64) - centre) @ np.asarray(axes).T / half
    x, y, z = X[:, 0], X[:, 1], X[:, 2]
    ax, ay = _semi_axes(x, y, reach)
    rho = np.sqrt((x / ax) ** 2 + (y / ay) ** 2)
    g = 0.5 * (1.0 + np.cos(np.pi * np.clip((rho - core) / (1.0 - core), 0.0, 1.0)))
    if hole is not None:
        g = g * np.clip((rho - hole[0]) / (hole[1] - hole[0]), 0.0, 1.0)
    if split is not None:
        g = g * np.clip(0.5 + x / float(split), 0.0, 1.0)
    g = g * (z > -float(depth) * max(float(reach[q]) for q in QUADRANTS))
    return rho, g


def ring_outline(centre, lateral, reach, radius=0.7, count=32, arc=None, up=(0.0, 1.0, 0.0), front=(0.0, 0.0, 1.0)):
    """Points on the ring's ellipse at elliptical radius ``radius``, in the ring's plane (for pictures).

    ``centre``, ``lateral`` (3,) and ``up``, ``front`` as for :func:`ring_frame`; ``reach`` as for
    :func:`ring_profile`. ``arc`` (start, stop) in radians from the lateral side toward ``up``: an
    open arc of ``count`` points, ends included (``(-pi/2, pi/2)``: the lateral half); default the
    whole ellipse, ``count`` points going round once from the lateral side. Returns (count, 3)
    float, same frame and unit as the points.
    """
    axes, half = ring_frame(centre, lateral, up, front)
    if arc is None:
        t = np.linspace(0.0, 2.0 * np.pi, int(count), endpoint=False)
    else:
        t = np.linspace(float(arc[0]), float(arc[1]), int(count))
    c, s = np.cos(t), np.sin(t)
    ax, ay = _semi_axes(c, s, reach)
    x, y = ax * c, ay * s
    return np.asarray(centre, dtype=np.float64) + float(radius) * half * (x[:, None] * axes[0] + y[:, None] * axes[1])


def _semi_axes(x, y, reach):
    """The semi-axes (in ``half`` units) of the quadrant each ring coordinate (x, y) lies in."""
    return (np.where(x >= 0, float(reach["lateral"]), float(reach["medial"])),
            np.where(y >= 0, float(reach["above"]), float(reach["below"])))
