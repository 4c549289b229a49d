"""Action units posed through a head's own ARKit shapes (issue #34 item 2): the shape layer.

A rig made with ``transfer(..., arkit=True)`` carries the head's 52 ARKit shapes, deformation-
transferred from ICT-FaceKit (``Rig.arkit_targets``: name -> (n, 3) displacement at weight 1, the
rig's input frame and units). They explain ICT's real action units far better than the muscle
model's fields (benchmarks/README.md, "AUs through the head's ARKit shapes"), so ``Rig.pose``
drives every AU that the definitions' ``au_arkit`` table maps through those shapes, and leaves the
AUs the table does not map (and muscles, jaw, eyelids, gaze, head/neck, tissue) to the muscle model.

The rule, one AU key ``k`` at intensity ``a`` (after an emotion preset has been expanded into its AUs,
intensities multiplied, as :meth:`ExpressionModel.parameters` does):

- ``"12"`` (no side): every shape of the AU's row at weight ``a`` (mouthSmileLeft and
  mouthSmileRight both at ``a``; jawOpen at ``a`` for AU26).
- ``"12L"`` / ``"12R"``: only the row's ``...Left`` / ``...Right`` shapes (ARKit's Left is the
  subject's own left, as the model's ``_l``). A row whose shape has no sides (browInnerUp,
  mouthPucker, mouthFunnel, mouthShrugLower, jawOpen) cannot move one side alone: that key stays
  with the muscle model.
- Keys of the same AU add (``{"12": 0.3, "12L": 0.5}``: mouthSmileLeft 0.8, mouthSmileRight 0.3),
  as the model adds them.
- Different AUs sharing a shape (jawOpen for AU26 and AU27, eyeBlink for AU43 and AU45) do not
  add: the shape takes the AU weight of largest magnitude (``{26: 1, 27: 1}`` is jawOpen 1, not 2),
  because each AU alone already shows the whole shape.

The result is the sum of ``weight * target`` (linear, what a glTF player gives for those weights),
added to the muscle layer's pose unturned by the head/neck/jaw bones and not refined by the tissue
pass, as ``Rig.pose(arkit=...)`` adds shapes.
"""
from __future__ import annotations

import numpy as np

from ..arguments import intensity_mixes
from ..errors import AutobonesError
from .definitions import au_arkit_table, parse_au_key

LAYERS = ("auto", "shapes", "muscles")
NO_SHAPES = ("layer='shapes': this rig has no ARKit shapes; make it with autobones transfer HEAD --arkit "
             "(or autobones.transfer(..., arkit=True))")


def resolve_layer(layer, has_shapes):
    """``"auto"`` / ``"shapes"`` / ``"muscles"`` and whether the rig has ARKit shapes -> the layer
    the mapped AUs use (``"shapes"`` or ``"muscles"``). AutobonesError for another value, or for
    ``"shapes"`` on a rig without shapes (one line saying how to make them)."""
    if not isinstance(layer, str) or layer not in LAYERS:
        raise AutobonesError(f"layer: {layer!r} is not one of {', '.join(LAYERS)}")
    if layer == "auto":
        return "shapes" if has_shapes else "muscles"
    if layer == "shapes" and not has_shapes:
        raise AutobonesError(NO_SHAPES)
    return layer


def table_of(doc):
    """The ``au_arkit`` table (:func:`au_arkit_table`) of the definitions ``doc``, or the packaged
    one when ``doc`` predates the table (a rig saved before it existed poses with today's table)."""
    return au_arkit_table(doc if isinstance(doc, dict) and "au_arkit" in doc else None)


def au_mix(au, expression, presets):
    """AU key -> intensity: ``au`` (dict, keys as :func:`parse_au_key` takes) plus each emotion of
    ``expression`` (a name, or dict name -> intensity) expanded through ``presets`` (the definitions'
    ``expressions``: name -> {"au": {key: intensity}}), intensities multiplied and summed per key.
    Keys are normalised (``"AU12"`` -> ``"12"``, ``"12l"`` -> ``"12L"``). AutobonesError for an
    unknown emotion or an intensity that is not a finite number."""
    au, expression, _, _ = intensity_mixes(au, expression, None, None)
    mix = {}
    for name, a in (expression or {}).items():
        if name not in presets:
            raise AutobonesError(f"unknown expression {name!r}; known: {', '.join(presets)}")
        for k, v in presets[name]["au"].items():
            key = parse_au_key(k)[0]
            mix[key] = mix.get(key, 0.0) + a * float(v)
    for k, v in (au or {}).items():
        key = parse_au_key(k)[0]
        mix[key] = mix.get(key, 0.0) + v
    return mix


def _side_of(name):
    return "l" if name.endswith("Left") else "r" if name.endswith("Right") else None


def split_mix(mix, table, names):
    """Which AUs the shapes pose, with what weights, and which stay with the muscles.

    Parameters
    ----------
    mix : dict str -> float
        Normalised AU key (``"12"``, ``"12L"``) -> intensity (:func:`au_mix`).
    table : list of dict
        The ``au_arkit`` rows (:func:`table_of`): ``au`` (list of int) and ``arkit`` (list of str).
    names : collection of str
        The ARKit shapes the rig has.

    Returns
    -------
    weights : dict str -> float
        ARKit shape name -> weight (the module's rule), shapes with a nonzero weight only.
    rest : dict str -> float
        The keys the muscle model poses: AUs the table does not map, one-sided keys of a row
        without sides, and rows whose shapes the rig lacks.
    """
    row_of = {str(a): row for row in table for a in row["au"]}
    per_au, rest = {}, {}   # (shape, AU) -> summed intensity: keys of one AU add
    for key, a in mix.items():
        _, base, side = parse_au_key(key)
        row = row_of.get(base)
        shapes = [] if row is None else [s for s in row["arkit"] if side is None or _side_of(s) == side]
        if not shapes or not all(s in names for s in row["arkit"]):
            rest[key] = rest.get(key, 0.0) + a
            continue
        for s in shapes:
            per_au[s, base] = per_au.get((s, base), 0.0) + a
    weights = {}
    for (s, _), w in per_au.items():   # AUs sharing a shape: the largest magnitude, not the sum
        if abs(w) > abs(weights.get(s, 0.0)):
            weights[s] = w
    return weights, rest


def shape_displacement(weights, targets, n):
    """Sum of ``weight * targets[name]`` over ``weights`` (dict name -> float): (n, 3) float64 in
    the targets' frame and units (the rig's input frame and units); zeros when ``weights`` is empty."""
    if not weights:
        return np.zeros((n, 3))
    W = np.array(list(weights.values()), dtype=np.float64)
    T = np.stack([np.asarray(targets[s], dtype=np.float64) for s in weights])
    return np.tensordot(W, T, axes=1)


def mapped_aus(table):
    """The AU numbers (str) the table maps, in the table's order."""
    return [str(a) for row in table for a in row["au"]]
