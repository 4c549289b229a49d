"""FACS action units as morph targets (blend shapes) for engines: one displacement field per AU.

Goes beyond the cited methods: the skin/muscle model of Bibliowicz 2005 (``expressions.ExpressionModel``) is
evaluated once per action unit at intensity 1 on the rig's own head, and the displacement
from the neutral mesh is what an engine adds, weighted, to the rest positions (glTF morph
targets, Blender shape keys). The targets are exact at weights 0 and 1 one at a time; a mix,
or a weight between, is their linear blend, whereas the model itself is not linear in every
part (the skull clamp, and the jaw and eyelid rotations): ``Rig.pose`` / ``autobones pose``
recompute any mix exactly from the muscle parameters the sidecar keeps.

The targets are the muscle layer's, also on a rig with ARKit shapes, where ``Rig.pose`` drives the AUs
the ``au_arkit`` table maps through those shapes (:mod:`.au_shapes`): such a rig's glb carries the ARKit
shapes as targets of their own, so an engine reaches the shape layer by weighting them.
"""
from __future__ import annotations

import hashlib
import json

import numpy as np

from ..errors import AutobonesError
from .definitions import parse_au_key


def target_keys(action_units, which=True):
    """The AU keys to write as targets, in order.

    Parameters
    ----------
    action_units : iterable of str
        AU numbers defined by the expression data (``"1"``, ``"12"``...).
    which : True, "sides" or sequence of str
        True (or ``"au"``): one target per AU, both sides (``12``). ``"sides"``: each AU
        followed by its left and right halves (``12``, ``12L``, ``12R``; the subject's
        left and right). A sequence: those keys (``[12, "12L", "AU6"]``), checked.

    Returns
    -------
    list of str
        Keys such as ``"12"`` and ``"12L"``; the target of key ``k`` is named ``"AU" + k``.
    """
    aus = sorted((str(a) for a in action_units), key=lambda a: (len(a), a))
    if which is True or which == "au":
        return aus
    if which == "sides":
        return [k for a in aus for k in (a, a + "L", a + "R")]
    if isinstance(which, str) or not hasattr(which, "__iter__"):
        raise AutobonesError(f"morph targets: {which!r} is not True, 'sides' or a list of action units")
    out = []
    for k in which:
        key, base, _side = parse_au_key(k)
        if base not in aus:
            raise AutobonesError(f"morph targets: unknown action unit {k!r}; defined: {', '.join(aus)}")
        if key not in out:
            out.append(key)
    return out


def au_morph_targets(model, which=True, tissue=False):
    """Displacement of every chosen AU at intensity 1 from the neutral mesh.

    Parameters
    ----------
    model : expressions.ExpressionModel
        A fitted model (``rig.expression_model()``).
    which : True, "sides" or sequence of str
        See :func:`target_keys`.
    tissue : bool
        Each target posed with the layered tissue pass (:meth:`ExpressionModel.pose`).

    Returns
    -------
    targets : list of (str, (n, 3) float)
        ``("AU12", posed - neutral)`` in the rig's input frame and units, float64; only
        targets that move at least one vertex once stored as float32.
    skipped : list of str
        Names of the targets that were all zero on this head (e.g. ``AU43`` on a head
        without eyelid landmarks), not written.
    """
    neutral = np.asarray(model.vertices_, dtype=np.float64)
    targets, skipped = [], []
    for key in target_keys(model.action_units, which):
        delta = model.pose(au={key: 1.0}, tissue=tissue) - neutral
        name = "AU" + key
        if not np.isfinite(delta).all():
            raise AutobonesError(f"morph target {name}: the pose is not finite on this head")
        if not np.any(delta.astype(np.float32)):
            skipped.append(name)
        else:
            targets.append((name, delta))
    return targets, skipped


def definitions_digest(doc):
    """SHA-256 (hex) of the expression definitions as canonical JSON (sorted keys): a
    version stamp that changes whenever any number of the data file changes."""
    text = json.dumps(doc, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode()).hexdigest()
