"""The schema check of what a rig's sidecar and a definitions file may hold (issue #33 item 5).

A sidecar or a definitions file edited by hand, damaged or made hostile is refused here, in one
line naming the key and what is wrong with it, before any of it is used: ``load_rig`` (every
command that reads a rig) calls :func:`check_sidecar`, and ``load_expressions`` (every reader of
definitions: ``pose --definitions``, a sidecar's own, the API's dicts) calls :func:`check_definitions`.
Without it, a tampered value surfaced deep inside as a traceback (``labels`` of 300 overflowing
int8, a 2x2 frame rotation, ``muscles`` a string), as a gigantic allocation (``vertex_count`` 1e12:
931 GiB), or as NaN in every posed vertex (``model.smoothing`` NaN).

What is checked: types (an object, a list, a number that is not a bool), shapes (3-vectors, the 3x3
rotation), finite values, ranges (labels within ``label_names``, ``head_size`` > 0, a rotation that is
one), and sizes (``vertex_count`` against :data:`MAX_VERTICES` before anything is allocated; the glb's
own count is compared by ``load_rig``). Keys autobones does not know are left alone (a newer
version's sidecar still loads), but no number anywhere may be NaN or infinite: the JSON reader
refuses those tokens (:func:`no_constants`) and a dict given through the API is walked.
"""
from __future__ import annotations

import math
import numbers

import numpy as np

from ..errors import AutobonesError

# far above any head scan (a 1M-vertex scan is large); what the sidecar claims is checked against
# this before an array of that size is made, and against the glb's count after
MAX_VERTICES = 50_000_000
MAX_BONES = 10_000


class SchemaError(AutobonesError):
    """A value of a sidecar or definitions file that the schema refuses; the message starts with its key."""


def no_constants(token):
    """``json.loads``'s ``parse_constant``: NaN, Infinity and -Infinity are not JSON numbers, and
    autobones never writes them (strict JSON), so a file holding one was damaged or made so."""
    raise SchemaError(f"a non-finite number ({token}) in the JSON; autobones never writes one")


def finite_float(text):
    """``json.loads``'s ``parse_float``: a literal too large for a float (1e400) is refused, not
    read as infinity."""
    value = float(text)
    if not math.isfinite(value):
        raise SchemaError(f"the number {text[:20]} is too large for a float")
    return value


def is_number(x):
    return isinstance(x, numbers.Real) and not isinstance(x, bool)


def _finite(x, key):
    """``x`` (a number) as a float, SchemaError naming ``key`` when not finite: JSON's whole numbers
    have no bound, and ``float(10**400)`` raises OverflowError instead of giving inf."""
    try:
        x = float(x)
    except OverflowError:
        raise SchemaError(f"{key} is a whole number too large for a float, not a finite number") from None
    if not math.isfinite(x):
        raise SchemaError(f"{key} is {x}, not a finite number")
    return x


def number(x, key, low=None, high=None, above=None):
    """``x`` as a finite float in ``[low, high]`` (and ``> above``); SchemaError naming ``key`` otherwise."""
    if not is_number(x):
        raise SchemaError(f"{key} is {_kind(x)}, not a number")
    x = _finite(x, key)
    if (low is not None and x < low) or (high is not None and x > high) or (above is not None and x <= above):
        bounds = f"> {above:g}" if above is not None else f"in [{low:g}, {high:g}]" if high is not None else f">= {low:g}"
        raise SchemaError(f"{key} is {x:g}, expected a number {bounds}")
    return x


def integer(x, key, low, high):
    """``x`` as an int in ``[low, high]``; SchemaError naming ``key`` otherwise (1.0 is not an int here)."""
    if not isinstance(x, numbers.Integral) or isinstance(x, bool):
        raise SchemaError(f"{key} is {_kind(x)}, not a whole number")
    if not low <= x <= high:
        raise SchemaError(f"{key} is {x}, expected a whole number in [{low}, {high}]")
    return int(x)


def vector(x, key, n=3):
    """``x`` as an (n,) finite float array; SchemaError naming ``key`` otherwise."""
    if not isinstance(x, (list, tuple)) or len(x) != n:
        raise SchemaError(f"{key} is {_kind(x)}, expected a list of {n} numbers")
    return np.array([number(v, f"{key}[{i}]") for i, v in enumerate(x)])


def mapping(x, key):
    if not isinstance(x, dict):
        raise SchemaError(f"{key} is {_kind(x)}, expected an object")
    return x


def sequence(x, key):
    if not isinstance(x, list):
        raise SchemaError(f"{key} is {_kind(x)}, expected a list")
    return x


def _kind(x):
    if x is None:
        return "null"
    if isinstance(x, str):
        return f"the string {x[:20]!r}"
    if isinstance(x, (list, tuple)):
        return f"a list of {len(x)}"
    if isinstance(x, dict):
        return "an object"
    if isinstance(x, bool):
        return str(x).lower()
    return repr(x)[:20] if is_number(x) else type(x).__name__


def check_finite_tree(x, key):
    """SchemaError naming the first NaN or infinite number anywhere in the JSON value ``x``
    (a dict given through the API has not passed the JSON reader's refusal)."""
    stack = [(x, key)]
    while stack:  # iterative: a deep value must not end in a RecursionError
        v, k = stack.pop()
        if isinstance(v, dict):
            stack.extend((vv, f"{k}.{kk}") for kk, vv in v.items())
        elif isinstance(v, (list, tuple)):
            stack.extend((vv, f"{k}[{i}]") for i, vv in enumerate(v))
        elif is_number(v):
            _finite(v, k)


# ---------------------------------------------------------------------------------------------------
# the sidecar

def check_frame(d, key="frame"):
    """The sidecar's ``frame``: a 3x3 rotation (orthonormal, det +1), an origin, ``head_size`` > 0, and
    optionally ``axes`` (the head's anatomical axes, a rotation too) and ``front_check`` (how clearly
    the front was told from the back, or with ``against`` ``"down"`` a face capture's up from its down)."""
    mapping(d, key)
    _rotation(d.get("rotation"), f"{key}.rotation")
    if d.get("axes") is not None:
        _rotation(d["axes"], f"{key}.axes")
    vector(d.get("origin"), f"{key}.origin")
    number(d.get("head_size"), f"{key}.head_size", above=0.0)
    if d.get("symmetry_error") is not None:
        number(d["symmetry_error"], f"{key}.symmetry_error", low=0.0)
    check = d.get("front_check")
    if check is not None:
        mapping(check, f"{key}.front_check")
        if check.get("told_by") not in ("reference head", "neck cut") or not isinstance(check.get("close"), bool):
            raise SchemaError(f"{key}.front_check: expected told_by 'reference head' or 'neck cut' and close true "
                              "or false")
        number(check.get("margin"), f"{key}.front_check.margin")
        if check.get("against", "back") not in ("back", "down"):
            raise SchemaError(f"{key}.front_check.against: expected 'back' or 'down' (a face capture's up told "
                              "from its down)")


def _rotation(R, key):
    """``R``: 3 rows of 3 numbers, orthonormal and right-handed (a sidecar's rotation)."""
    if not isinstance(R, list) or len(R) != 3:
        raise SchemaError(f"{key} is {_kind(R)}, expected 3 rows of 3 numbers")
    R = np.array([vector(row, f"{key}[{i}]") for i, row in enumerate(R)])
    if np.abs(R @ R.T - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0:
        raise SchemaError(f"{key} is not a rotation (its rows are not orthonormal, right-handed)")


def check_bones(bones):
    sequence(bones, "bones")
    if not 1 <= len(bones) <= MAX_BONES:
        raise SchemaError(f"bones has {len(bones)} bones, expected 1 to {MAX_BONES}")
    names = []
    for i, b in enumerate(bones):
        mapping(b, f"bones[{i}]")
        if not isinstance(b.get("name"), str):
            raise SchemaError(f"bones[{i}].name is {_kind(b.get('name'))}, expected a string")
        if b.get("parent") is not None and b["parent"] not in names:
            raise SchemaError(f"bones[{i}].parent {str(b['parent'])[:40]!r} is not a bone listed before it")
        vector(b.get("head"), f"bones[{i}].head")
        vector(b.get("tail"), f"bones[{i}].tail")
        names.append(b["name"])
    if len(set(names)) != len(names):
        raise SchemaError("bones: two bones have the same name")


def check_int_list(values, key, low, high, n=None):
    """A list of whole numbers in ``[low, high]`` (``n`` of them), checked at numpy speed."""
    sequence(values, key)
    if n is not None and len(values) != n:
        raise SchemaError(f"{key} has {len(values)} entries for {n} vertices")
    if not all(isinstance(v, int) and not isinstance(v, bool) for v in values):
        bad = next(v for v in values if not isinstance(v, int) or isinstance(v, bool))
        raise SchemaError(f"{key} holds {_kind(bad)}, expected whole numbers")
    lo, hi = (min(values), max(values)) if len(values) else (low, high)
    if lo < low or hi > high:  # Python ints: 10**30 is refused, not wrapped
        bad = lo if lo < low else hi
        raise SchemaError(f"{key} holds {str(bad)[:24]}, expected whole numbers in [{low}, {high}]")
    return np.asarray(values, dtype=np.int64)


def check_sidecar(meta, model_defaults):
    """SchemaError naming the first key of the sidecar dict ``meta`` that is malformed (see the
    module doc); returns its vertex count. The caller has checked ``format``; ``model_defaults``: see
    :func:`check_definitions`."""
    n = integer(meta.get("vertex_count"), "vertex_count", 3, MAX_VERTICES)
    check_bones(meta.get("bones"))
    check_frame(meta.get("frame"))
    names = meta.get("label_names", ["face", "middle", "back"])
    sequence(names, "label_names")
    check_int_list(meta.get("labels"), "labels", 0, max(len(names) - 1, 0), n)
    check_int_list(meta.get("facial_mask", []), "facial_mask", 0, n - 1)
    if meta.get("options") is not None:
        mapping(meta["options"], "options")
    _check_attributes(meta, n)
    defs = (meta.get("expressions") or {}).get("definitions") if isinstance(meta.get("expressions"), dict) else None
    if meta.get("expressions") is not None:
        mapping(meta["expressions"], "expressions")
    if defs is not None:
        check_definitions(defs, model_defaults, "expressions.definitions")
    return n


def _check_attributes(meta, n):
    """The optional keys a pipeline adds (``Rig``'s typed attributes): None or their documented shape."""
    if meta.get("landmarks") is not None:
        for name, p in mapping(meta["landmarks"], "landmarks").items():
            vector(p, f"landmarks.{name}")
    if meta.get("muscles") is not None:
        for i, m in enumerate(sequence(meta["muscles"], "muscles")):
            mapping(m, f"muscles[{i}]")
            for k in ("name", "type"):
                if not isinstance(m.get(k), str):
                    raise SchemaError(f"muscles[{i}].{k} is {_kind(m.get(k))}, expected a string")
            vector(m.get("origin"), f"muscles[{i}].origin")
            vector(m.get("insertion"), f"muscles[{i}].insertion")
            for k in ("width", "width_canonical"):
                if k in m:
                    number(m[k], f"muscles[{i}].{k}", low=0.0)
    if meta.get("field_labels") is not None:
        for k, v in mapping(meta["field_labels"], "field_labels").items():
            if not isinstance(v, list) or not all(isinstance(s, str) for s in v):
                raise SchemaError(f"field_labels.{k} is {_kind(v)}, expected a list of strings")
    if meta.get("reliable_fraction") is not None:
        number(meta["reliable_fraction"], "reliable_fraction", 0.0, 1.0)
    if meta.get("neck_height_canonical") is not None:
        number(meta["neck_height_canonical"], "neck_height_canonical")
    if meta.get("facial_bone_partner") is not None:
        check_int_list(meta["facial_bone_partner"], "facial_bone_partner", -1, MAX_BONES)
    if meta.get("arkit") is not None:
        names = mapping(meta["arkit"], "arkit").get("names", [])
        if not isinstance(names, list) or not all(isinstance(s, str) for s in names):
            raise SchemaError(f"arkit.names is {_kind(names)}, expected a list of strings")


# ---------------------------------------------------------------------------------------------------
# expression definitions

def check_definitions(doc, model_defaults, key="definitions"):
    """SchemaError naming the first malformed entry of the expression definitions ``doc``: the four
    sections objects, every number finite, the ``model`` numbers numbers, each muscle type's
    ``shortening``/``dropoff``/``wire``, each action unit's ``muscles`` weights, ``jaw_deg`` and
    ``eyelids``, each expression's ``au`` intensities. ``model_defaults``: the ``model`` section's
    fallbacks (``expressions.definitions.MODEL_DEFAULTS``, given by the caller: that module reads
    definitions through this one), whose types the file's values must have."""
    mapping(doc, key)
    for section in ("model", "muscle_types", "action_units", "expressions"):
        if section not in doc:
            raise SchemaError(f"{key} has no {section!r}")
        mapping(doc[section], f"{key}.{section}")
    check_finite_tree(doc, key)
    _check_like(doc["model"], model_defaults, f"{key}.model")
    for name, spec in doc["muscle_types"].items():
        where = f"{key}.muscle_types.{name}"
        mapping(spec, where)
        for k in ("shortening", "dropoff"):
            if k in spec:
                number(spec[k], f"{where}.{k}")
        if "wire" in spec:
            for i, w in enumerate(sequence(spec["wire"], f"{where}.wire")):
                number(w, f"{where}.wire[{i}]")
    for au, spec in doc["action_units"].items():
        where = f"{key}.action_units.{au}"
        mapping(spec, where)
        for m, w in mapping(spec.get("muscles", {}), f"{where}.muscles").items():
            number(w, f"{where}.muscles.{m}")
        if "jaw_deg" in spec:
            number(spec["jaw_deg"], f"{where}.jaw_deg", -90.0, 90.0)
        for lid, w in mapping(spec.get("eyelids", {}), f"{where}.eyelids").items():
            number(w, f"{where}.eyelids.{lid}")
    for name, spec in doc["expressions"].items():
        where = f"{key}.expressions.{name}"
        for au, w in mapping(mapping(spec, where).get("au", {}), f"{where}.au").items():
            number(w, f"{where}.au.{au}")


def _check_like(section, defaults, key):
    """Each key of ``section`` whose default is a number (a bool, a dict) is one too; a key with no
    default (the required ``rest_weight``, ``lips.cut_width``...) is a number, or a list of them."""
    for k, v in section.items():
        d = defaults.get(k)
        if k not in defaults and not isinstance(v, dict):
            for i, x in enumerate(v if isinstance(v, list) else [v]):
                number(x, f"{key}.{k}" + (f"[{i}]" if isinstance(v, list) else ""))
        elif isinstance(d, bool):
            if not isinstance(v, bool):
                raise SchemaError(f"{key}.{k} is {_kind(v)}, expected true or false")
        elif is_number(d) and v is not None:
            number(v, f"{key}.{k}")
        elif isinstance(d, dict) and v is not None:
            _check_like(mapping(v, f"{key}.{k}"), d, f"{key}.{k}")
        elif k not in defaults:  # a section of its own (skull, creases): its values are numbers
            _check_like(v, {}, f"{key}.{k}")
