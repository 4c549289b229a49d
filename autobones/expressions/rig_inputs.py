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
    """The :class:`RigInputs` of ``rig`` (empty where the rig has none).

    The one place the expressions package reads these from the rig: today from
    ``rig.extra['muscles' | 'landmarks' | 'field_labels']``.
    """
    extra = getattr(rig, "extra", None) or {}
    return RigInputs(extra.get("muscles") or getattr(rig, "muscles", None) or [],
                     extra.get("landmarks") or {}, extra.get("field_labels") or {})
