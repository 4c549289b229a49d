"""The expression definitions: reading the data file, its model parameters, action-unit keys.

``generic_rig/expressions.json`` (format ``autobones-expressions/1``) holds the skin/muscle
model's parameters (section ``model``, lengths in face units: fu = the head's exocanthion
distance), the muscle types, the FACS action units and the emotion prototypes (Erdoğdu 2010,
Table 3-3). :func:`model_parameters` is the one place the ``model`` section is resolved: every
optional key has its fallback in :data:`MODEL_DEFAULTS`, every required key is checked there.
"""
from __future__ import annotations

import copy
import os

from ..errors import AutobonesError
from ..geometry.mouth_parts import MOUTH_PARTS
from ..io.files import read_json, shown
from ..io.rig_schema import SchemaError, check_definitions, finite_float, no_constants

# The fallbacks used when a definitions file lacks an optional ``model`` key: the values the
# model used before the key existed, so an older user file poses as it did. The shipped
# expressions.json sets most of them explicitly (several to other values: slide_thickness
# 0.08, under_chin_depth 0.8, cheek_spread 0.25, jaw_glide [0.0035, 0.004], eyelids.lateral_reach
# 1.6, eyelids.corner_release 1.0, eyelids.smoothing 0.02).
MODEL_DEFAULTS = {
    "skull_smoothing_passes": 10,       # neighbour-sum passes smoothing the skull directions
    "smoothing": 0.012,                 # fu: heat diffusion of the muscle fields
    "normalise_overlaps": False,        # overlapping wire dropoffs normalised to sum <= 1
    "slide_thickness": 0.04,            # fu: muscles of type "slide" slide over bone this close
    "jaw_spread": 0.15,                 # fu: jaw weight diffused below the mouth line
    "cheek_spread": 0.0,                # fu: jaw weight diffused up into the cheeks
    "under_chin_height": 0.15,          # fu above the menton
    "under_chin_depth": 0.6,            # fu behind the menton
    "jaw_glide": [0.0, 0.0],            # fu per degree: (down, forward)
    "unfold_reach": 0.25,               # fu from the first folds
    "lips": {"normal_bias": 0.03},      # fu: the mouth line follows the lip surfaces' normals
    "skull": {"blend": 0.1},            # fu: region thicknesses blend over this much skin
    "eyelids": {
        "depth": 0.02,                  # fu behind the eye pivot
        "lateral_reach": 1.0,           # half fissure widths past the outer corner
        "corner_exponent": 1.0,
        "corner_release": 0.0,          # fissure heights
        "smoothing": None,              # fu; None: the muscle fields' ``smoothing``
        "margin_hold": 0.85,            # share of the muscles' pull the lid margins ignore
        "attached_part_size": 0.5,      # fu: lashes and eye shells up to this size
        "hinge": "pivot",               # the lids turn about +X through the eye pivot only
        "hinge_medial_height": 0.0,     # corners hinge: through the endocanthion itself
        "hinge_band": 0.0,              # fissure heights: the corners hinge's reach from the margin
        "hinge_lower": False,           # the lower lids hinge too
    },
    "mouth_parts": dict(MOUTH_PARTS),   # fu (geometry.mouth_parts: transfer's exported weights use the same)
}

# keys every definitions file must set (no fallback), by section ("" = the model section itself)
MODEL_REQUIRED = {
    "": ("rest_weight", "cross_talk", "cvs", "lips", "skull", "creases", "eyelids"),
    "lips": ("zone_half_width", "zone_height", "cut_width"),
    "skull": ("default",),
    "creases": ("forehead_amplitude", "forehead_wavelength", "glabella_amplitude", "glabella_wavelength"),
    "eyelids": ("lower_range", "upper_height", "lower_height", "width_margin"),
}

# fallbacks of the optional keys of a muscle type (``shortening`` 0: the type does not move)
MUSCLE_TYPE_DEFAULTS = {"shortening": 0.0, "slide": False, "galea": None, "sphincter": None, "sheet": None}


def load_expressions(path=None):
    """The expression definitions (default ``generic_rig/expressions.json``) as a dict.

    ``path`` may also be a dict (returned as it is). Raises AutobonesError when the file cannot
    be read or lacks one of the sections ``model``, ``muscle_types``, ``action_units``,
    ``expressions``.
    """
    if path is None:
        from ..generic_rig import expressions_path

        path = expressions_path()
    if isinstance(path, dict):  # the API's own dict, or a sidecar's: checked as a file is
        try:
            check_definitions(path, MODEL_DEFAULTS)
        except SchemaError as exc:
            raise AutobonesError(f"expression definitions: {exc}") from None
        return path
    if not isinstance(path, (str, bytes, os.PathLike)):
        raise AutobonesError(f"definitions: expected a path, a dict or None, not {type(path).__name__}")
    path = os.fspath(path)
    doc = read_json(path, "definitions", invalid="cannot read the expression definitions",  # bounded
                    parse_constant=no_constants, parse_float=finite_float)
    try:
        check_definitions(doc, MODEL_DEFAULTS)
    except SchemaError as exc:
        raise AutobonesError(f"{shown(path)}: cannot read the expression definitions ({exc})") from None
    return doc


def model_parameters(doc):
    """The definitions' ``model`` section over :data:`MODEL_DEFAULTS`, checked.

    Parameters
    ----------
    doc : dict
        Expression definitions (:func:`load_expressions`).

    Returns
    -------
    dict
        A new dict: every key of :data:`MODEL_DEFAULTS` (nested sections merged key by key) and
        every key of the file; ``eyelids.smoothing`` None resolved to ``smoothing``. Lengths in
        face units, as in the file.

    Raises AutobonesError naming the first required key (:data:`MODEL_REQUIRED`) the file lacks.
    """
    model = doc.get("model")
    if not isinstance(model, dict):
        raise AutobonesError("expression definitions: the 'model' section is missing or not an object")
    out = copy.deepcopy(MODEL_DEFAULTS)
    for key, value in model.items():
        if isinstance(out.get(key), dict) and isinstance(value, dict):
            out[key].update(value)
        else:
            out[key] = value
    for section, keys in MODEL_REQUIRED.items():
        where = out if not section else model.get(section)
        for key in keys:
            if not isinstance(where, dict) or key not in where:
                name = f"model.{section}.{key}" if section else f"model.{key}"
                raise AutobonesError(f"expression definitions: {name} is missing (see generic_rig/expressions.json)")
    if out["eyelids"]["smoothing"] is None:
        out["eyelids"]["smoothing"] = out["smoothing"]
    return out


def muscle_types(doc):
    """Muscle type name -> its definition over :data:`MUSCLE_TYPE_DEFAULTS` (new dicts).

    ``wire`` (fractions origin -> insertion where the wire runs) and ``dropoff`` (muscle widths)
    have no fallback: a linear type a rig's muscle uses must set them; a sphincter type
    (``sphincter``: :mod:`sphincters`) needs neither.
    """
    return {name: {**MUSCLE_TYPE_DEFAULTS, **spec} for name, spec in doc["muscle_types"].items()}


def parse_au_key(key):
    """An action-unit key as given by a user -> (key, base, side).

    ``12``, ``"12"``, ``"AU12"``, ``" au12l "`` -> ``("12", "12", None)`` ... ``("12L", "12", "l")``:
    the normalised key (stripped, upper case, without the ``AU`` prefix), the AU number and the
    side (``"l"`` / ``"r"``: the subject's left / right half, or None for both). Whether the AU
    exists is for the caller to check.
    """
    key = str(key).strip().upper().removeprefix("AU")
    if key[-1:] in ("L", "R"):
        return key, key[:-1], key[-1].lower()
    return key, key, None


def au_arkit_table(doc=None):
    """The definitions' ``au_arkit`` table: FACS action units and the ICT-FaceKit / ARKit shapes
    that show them (issue #16 item 3; goes beyond the seeds). Not used to pose the model.

    Parameters
    ----------
    doc : dict, str, path or None
        Expression definitions (anything :func:`load_expressions` takes; None: the packaged file).

    Returns
    -------
    list of dict
        One new dict per row, in the file's order: ``au`` (list of int, FACS numbers; two where one
        shape stands for both, e.g. jawOpen for AU26/27), ``facs`` (list of str, their FACS names),
        ``ict`` (list of str, ICT-FaceKit expression names, ``_L`` / ``_R`` where ICT splits the
        shape), ``arkit`` (list of str, ARKit ``BlendShapeLocation`` names) and ``source`` (str).

    Raises AutobonesError when the section is missing or a row lacks one of those keys or has
    an empty list.
    """
    doc = load_expressions(doc)
    table = doc.get("au_arkit")
    rows = table.get("rows") if isinstance(table, dict) else None
    if not isinstance(rows, list):
        raise AutobonesError("expression definitions: the 'au_arkit' section (with its 'rows') is missing")
    out = []
    for i, row in enumerate(rows):
        try:
            rec = {"au": [int(a) for a in row["au"]], "facs": [str(n) for n in row["facs"]],
                   "ict": [str(n) for n in row["ict"]], "arkit": [str(n) for n in row["arkit"]],
                   "source": str(row["source"])}
        except (KeyError, TypeError, ValueError) as exc:
            raise AutobonesError(f"expression definitions: au_arkit row {i} is malformed ({exc!r})") from None
        if not (rec["au"] and rec["ict"] and rec["arkit"]) or len(rec["facs"]) != len(rec["au"]):
            raise AutobonesError(f"expression definitions: au_arkit row {i} needs au, facs (one name per AU), "
                                 "ict and arkit names")
        out.append(rec)
    return out
