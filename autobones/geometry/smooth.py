"""Smooth step functions used to blend fields and weights."""
import numpy as np


def smoothstep(t):
    """C1 smooth step of ``t`` (any shape): 0 for t <= 0, 1 for t >= 1, ``3t² - 2t³`` between."""
    t = np.clip(np.asarray(t, dtype=np.float64), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def ramp(v, a, b):
    """Smooth step of ``v``: 0 at ``a``, 1 at ``b`` (either order), C1 in between."""
    return smoothstep((np.asarray(v, dtype=np.float64) - a) / (b - a))


def step(d, centre, width):
    """Smooth step of ``d``: 0 below ``centre - width/2``, 1 above ``centre + width/2``."""
    return smoothstep((d - centre) / width + 0.5)
