"""What the expression model reads from a transferred rig beyond its mesh, bones and weights."""
from __future__ import annotations

from typing import NamedTuple


class RigInputs(NamedTuple):
    """The rig's muscles, landmarks and field label names, in the rig's input frame and units.

    muscles : list of dict
        ``name``, ``type``, ``side``, ``origin``, ``insertion``, ``width_canonical`` (head sizes).
    landmarks : dict str -> (3,) float
        Named landmarks (stomion, cheilions, palpebrale points, exocanthions, menton...).
    field_labels : dict str -> list of str
        Label names of the integer fields (``region``).
    """

    muscles: list
    landmarks: dict
    field_labels: dict


def rig_inputs(rig):
    """The :class:`RigInputs` of ``rig``: a transferred :class:`autobones.rig.Rig`'s typed
    ``muscles``, ``landmarks`` and ``field_labels`` (empty where the rig has none, as a placed rig)."""
    return RigInputs(getattr(rig, "muscles", None) or [], getattr(rig, "landmarks", None) or {},
                     getattr(rig, "field_labels", None) or {})
