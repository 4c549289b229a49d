"""Where the head turns and where the jaw hinges, from the ear canals: the generic rig's joints.

Chancey, Ottaviano, Myers & Nightingale 2007 (J. Biomech. 40:1953) measured, relative to the external
auditory meatus (the ear canal), the occiput-C1 centre of rotation 22.5 mm posterior and 22.6 mm
inferior (adults); the mandibular condyle sits 10-15 mm anterior of the canal at its height. The
contract's tragions lie beside the canals and stand in for them.
"""
from __future__ import annotations

import numpy as np

# offsets relative to the ear canal (here the tragions'
# midpoint, which lies beside it) in millimetres of an adult whose ex-ex is EX_EX_MM, as (up, front)
EX_EX_MM = 90.0
OCCIPUT_C1_MM = (-22.6, -22.5)   # the occiput-C1 centre of rotation: inferior, posterior
CONDYLE_MM = (0.0, 12.0)         # the mandibular condyle: at the canal's height, 10-15 mm anterior


def anatomical_joints(L):
    """The occiput-C1 centre of rotation and the jaw's condyle hinge from the ear canals.

    Chancey, Ottaviano, Myers & Nightingale 2007 (J. Biomech. 40) measured the occiput-C1 centre
    of rotation 22.5 mm posterior and 22.6 mm inferior of the external auditory meatus; the
    mandibular condyle sits 10-15 mm anterior of it at its height (:data:`CONDYLE_MM`: 12). The
    tragions stand in for the canals, and millimetres are scaled by the head's ex-ex over
    :data:`EX_EX_MM` (both offsets are adult averages; the ratio keeps a child's or a cartoon's
    proportions). Both joints are put on the midline: the hinge of the two condyles, the pivot
    of the two occipital condyles.

    Parameters
    ----------
    L : mapping str -> (3,) float
        Canonical-frame landmarks (+Y up, +Z front, +X left) with ``tragion_l/_r`` and
        ``exocanthion_l/_r``.

    Returns
    -------
    head, jaw : (3,) float
        Canonical positions of the ``head`` joint and the ``jaw`` joint.
    """
    tr = 0.5 * (np.asarray(L["tragion_l"], dtype=np.float64) + np.asarray(L["tragion_r"], dtype=np.float64))
    mm = float(np.linalg.norm(np.asarray(L["exocanthion_l"]) - np.asarray(L["exocanthion_r"]))) / EX_EX_MM
    head = tr + mm * np.array([0.0, *OCCIPUT_C1_MM])
    jaw = tr + mm * np.array([0.0, *CONDYLE_MM])
    head[0] = jaw[0] = 0.0
    return head, jaw
