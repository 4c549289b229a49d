"""Muscle joints: origin, insertion and contraction (Bibliowicz 2005, §4.2).

A muscle is a joint from its origin under the skin to its insertion on the skin;
a contraction is a scaling about the origin along the origin -> insertion
direction. A point q riding the joint (Bibliowicz's locators, parented to the joint)
moves, for a contraction that shortens the muscle by the fraction s, by

    -s ((q - o) . u) u,         u = (i - o) / |i - o|,

which is linear in s: that is what keeps the whole skin/muscle model linear in the
contractions (``expressions.ExpressionModel``). A negative s lengthens the joint
(Bibliowicz 2005 swaps the mentalis ends so that its contraction pushes; here a definition may
simply use a negative shortening).

The joints of a transferred rig come with it (:func:`rig_inputs.rig_inputs`: origin and
insertion in the head's input frame; ``width_canonical`` in head sizes).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import AutobonesError
from .rig_inputs import rig_inputs
from .sphincters import is_sheet, is_sphincter


@dataclass
class MuscleJoints:
    """The muscles of one head as arrays, all in the same frame and units.

    Attributes
    ----------
    names, types, sides : list of str
        ``zygomaticus_major_l``, ``zygomaticus_major``, ``l`` (``l``, ``r`` or ``m``).
    origins, insertions : (k, 3) float
        Joint ends.
    widths : (k,) float
        Influence radius across the muscle line (the width of Lee, Terzopoulos & Waters 1995), same units.
    """

    names: list
    types: list
    sides: list
    origins: np.ndarray
    insertions: np.ndarray
    widths: np.ndarray

    def __len__(self):
        return len(self.names)

    @property
    def directions(self):
        """(k, 3) unit origin -> insertion directions."""
        d = self.insertions - self.origins
        return d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)

    @property
    def lengths(self):
        """(k,) rest lengths."""
        return np.linalg.norm(self.insertions - self.origins, axis=1)

    def transformed(self, fn, scale):
        """A copy with ``fn`` ((k, 3) -> (k, 3)) applied to the ends and widths times ``scale``."""
        return MuscleJoints(list(self.names), list(self.types), list(self.sides), fn(self.origins),
                            fn(self.insertions), self.widths * scale)

    def locator_displacements(self, Q, muscle, anchor=None):
        """Unit-contraction displacement of locators riding one muscle joint.

        Parameters
        ----------
        Q : (p, 3) float
            Locator rest positions (same frame as the joints).
        muscle : int
            Muscle index.
        anchor : float, optional
            For a muscle without a bony origin (frontalis, on the galea aponeurotica, which
            the occipitalis holds from behind): the joint scales about the point ``anchor``
            of the way origin -> insertion instead of the origin, and locators above the
            origin (the aponeurosis) move as one piece with it.

        Returns
        -------
        (p, 3) float
            Displacement per unit shortening: ``-((q - o) . u) u``, or with an anchor
            ``-(max(t, 0) - anchor) (i - o)`` where ``t`` is the locator's fraction of the way
            origin ``o`` -> insertion ``i``; multiply by the shortening fraction s.
        """
        Q = np.asarray(Q, dtype=np.float64)
        o = self.origins[muscle]
        if anchor is None:
            u = self.directions[muscle]
            return -((Q - o) @ u)[:, None] * u[None, :]
        L = self.insertions[muscle] - o
        t = (Q - o) @ L / (L @ L)
        return -(np.maximum(t, 0.0) - float(anchor))[:, None] * L[None, :]

    def contract(self, Q, muscle, shortening):
        """Locators ``Q`` (p, 3) moved by a contraction of ``muscle`` shortening it by the
        fraction ``shortening`` (0: rest, 0.2: 20% shorter, negative: longer)."""
        return np.asarray(Q, dtype=np.float64) + shortening * self.locator_displacements(Q, muscle)


def muscles_from_rig(rig):
    """The :class:`MuscleJoints` of a transferred rig, in its input frame and units.

    Reads the rig's muscles (:func:`rig_inputs.rig_inputs`; each with ``name``, ``type``, ``side``,
    ``origin``, ``insertion`` and ``width_canonical`` in head sizes, or ``width`` in mesh units).
    """
    muscles = rig_inputs(rig).muscles
    if not muscles:
        raise AutobonesError("this rig has no muscles: expressions need a rig made by "
                             "autobones.transfer (or its saved glb with the .rig.json sidecar)")
    size = float(rig.frame.size) if getattr(rig, "frame", None) is not None else 1.0
    names, types, sides, O, I, W = [], [], [], [], [], []
    for m in muscles:
        try:
            names.append(str(m["name"]))
            types.append(str(m.get("type", m["name"])))
            sides.append(str(m.get("side", "m")))
            O.append(np.asarray(m["origin"], dtype=np.float64))
            I.append(np.asarray(m["insertion"], dtype=np.float64))
            W.append(float(m["width_canonical"]) * size if "width_canonical" in m else float(m["width"]))
        except (KeyError, TypeError, ValueError) as exc:
            raise AutobonesError(f"muscle {m.get('name', '?')!r}: incomplete definition ({exc})") from None
    O, I = np.array(O), np.array(I)
    if not (np.isfinite(O).all() and np.isfinite(I).all()):
        raise AutobonesError("the rig's muscles have non-finite origins or insertions")
    if (np.linalg.norm(I - O, axis=1) <= 0).any():
        raise AutobonesError("a muscle of the rig has its origin on its insertion (zero length)")
    return MuscleJoints(names, types, sides, O, I, np.array(W))


def influence_fields(fields, names, n):
    """(k, n) float: the rig's influence field ``muscle/<name>`` of each muscle in ``names``
    (``fields`` a dict of (n,) arrays; 0 where a muscle has none)."""
    infl = np.zeros((len(names), n))
    for i, nm in enumerate(names):
        f = fields.get(f"muscle/{nm}")
        if f is not None:
            infl[i] = np.asarray(f, dtype=np.float64).reshape(n)
    return infl


def check_muscle_kinds(muscles, types):
    """One clear error when a rig's muscle was built as one kind (its record's ``kind``: linear,
    "sphincter" or "sheet") and the definitions move its type as another (a rig transferred before
    mentalis became a sheet, posed with today's definitions): its field would be read as the wrong
    shape. The rig's own sidecar definitions always match it."""
    for m in muscles:
        t = types.get(m.get("type"))
        if t is None:
            continue
        built = m.get("kind", "linear")
        moved = "sheet" if is_sheet(t) else "sphincter" if is_sphincter(t) else "linear"
        if built != moved:
            raise AutobonesError(f"muscle {m.get('name')!r} is a {built} muscle in this rig but the expression "
                                 f"definitions move its type {m.get('type')!r} as a {moved}: pose it with the "
                                 "definitions saved with the rig, or transfer the head again")
